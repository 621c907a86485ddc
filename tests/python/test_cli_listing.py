"""`contactbench solvers` and `contactbench --version` (the binary named by CB_CONTACTBENCH)."""
import json
import os
import subprocess
import unittest

CONTACTBENCH = os.environ.get("CB_CONTACTBENCH", "")


def run(*args):
    return subprocess.run([CONTACTBENCH, *args], capture_output=True, text=True)


@unittest.skipUnless(CONTACTBENCH and os.path.isfile(CONTACTBENCH), "CB_CONTACTBENCH is not set to the binary")
class Listing(unittest.TestCase):
    def test_solvers_one_line_each_with_applicability(self):
        text = run("solvers")
        self.assertEqual(text.returncode, 0, text.stderr)
        listed = json.loads(run("solvers", "--json").stdout)
        lines = text.stdout.splitlines()
        self.assertEqual(len(lines), len(listed))
        for line, entry in zip(lines, listed):
            self.assertTrue(line.startswith(entry["name"] + " "), line)
            self.assertIn(f"[{entry['applies_to']}] {entry['description']}", line)
        by_name = {e["name"]: e["applies_to"] for e in listed}
        self.assertTrue(by_name["mprgp"].startswith("decoupled rows only"))
        self.assertTrue(by_name["mprgp-box"].startswith("bounds only"))
        self.assertNotIn("template", by_name)  # the model solver is not registered
        for e in listed:  # a peer names its library; the project's own solvers leave it empty
            self.assertEqual(bool(e["library"]), e["description"].startswith("peer: "), e["name"])
        self.assertEqual({e["name"]: e["library"] for e in listed}["mprgp"], "")

    def test_version_names_commit_build_and_libraries(self):
        text = run("--version")
        self.assertEqual(text.returncode, 0, text.stderr)
        facts = json.loads(run("--version", "--json").stdout)
        self.assertRegex(facts["git_commit"], r"^([0-9a-f]{40}|unknown)$")
        for key in ("build_type", "compiler", "eigen", "suitesparse", "nlohmann_json", "blas"):
            self.assertTrue(facts[key] and facts[key] != "unknown", key)
        self.assertIn("CHOLMOD", facts["suitesparse"])
        for label in ("build type", "compiler", "Eigen", "SuiteSparse", "nlohmann-json", "BLAS", "peers"):
            self.assertIn(label, text.stdout)
        # Every peer `solvers` lists (description "peer: LIB VERSION ...") is named with its library.
        listed = {e["name"]: e["description"] for e in json.loads(run("solvers", "--json").stdout)}
        peers = {name: d for name, d in listed.items() if d.startswith("peer: ")}
        self.assertEqual(set(facts["peers"]), set(peers))
        for name, library in facts["peers"].items():
            self.assertTrue(peers[name].startswith("peer: " + library + " "), (name, library))
            self.assertIn(f"{name} ({library})", text.stdout)

    def test_unknown_option_is_bad_input(self):
        self.assertEqual(run("solvers", "--bogus").returncode, 2)


if __name__ == "__main__":
    unittest.main()
