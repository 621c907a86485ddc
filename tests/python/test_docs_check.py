"""Tests of the docs-check (tests/python/docs_check.py): the repository is clean, and each kind of
dangling reference in a small made-up repository is reported with its file and line."""
import os
import subprocess
import tempfile
import unittest

import docs_check

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
SHARED = ".." + "/" + "shared"  # assembled, so that this file does not mention it


def write(root, rel, text):
    path = os.path.join(root, rel)
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "w") as f:
        f.write(text)


class RepositoryIsClean(unittest.TestCase):
    def test_every_cited_document_section_and_path_exists(self):
        self.assertEqual(docs_check.check(ROOT), [])

    def test_the_counts_the_code_prints_match_the_documents(self):
        binary = docs_check.find_binary(ROOT)
        if binary is None:
            self.skipTest("no contactbench built (ctest sets CB_CONTACTBENCH)")
        self.assertEqual(docs_check.check_counts(ROOT, binary), [])


class ReportsDanglingReferences(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory()
        self.root = self.tmp.name
        write(self.root, "docs/ALGORITHMS.md", "# Algorithms\n\n## 1. One\n\n## 2. Two\n\n### Power method\n")
        write(self.root, "docs/DESIGN.md", "# Design\n\n## Metrics\n")

    def tearDown(self):
        self.tmp.cleanup()

    def problems(self):
        return docs_check.check(self.root)

    def test_resolved_references_are_clean(self):
        write(self.root, "solvers/a.cpp", '// DESIGN.md "Metrics"; ALGORITHMS.md §2 "Power method"\n'
                                          '// later §1 of the same document\n')
        write(self.root, "README.md", "| ALGORITHMS.md §1 |\n| §2 |\nsee [design](docs/DESIGN.md#metrics)\n")
        self.assertEqual(self.problems(), [])

    def test_missing_document(self):
        write(self.root, "solvers/a.hpp", "/// as INTERFACES.md \"Results folder\" says\n")
        self.assertEqual(self.problems(), ["solvers/a.hpp:1: cites INTERFACES.md, which is not in the repository"])

    def test_missing_numbered_section(self):
        write(self.root, "solvers/a.cpp", "// x\n// ALGORITHMS.md §3\n")
        self.assertEqual(self.problems(),
                         ["solvers/a.cpp:2: cites ALGORITHMS.md §3, which has no heading numbered 3"])

    def test_bare_section_refers_to_the_last_cited_document(self):
        write(self.root, "README.md", "| ALGORITHMS.md §1 |\n| §9 |\n")
        self.assertEqual(self.problems(),
                         ["README.md:2: cites §9 of ALGORITHMS.md, which has no heading numbered 9"])

    def test_missing_named_section(self):
        write(self.root, "plots/x.py", '# DESIGN.md "Across a suite"\n')
        self.assertEqual(self.problems(),
                         ['plots/x.py:1: cites DESIGN.md "Across a suite", which has no such heading'])

    def test_broken_markdown_link(self):
        write(self.root, "docs/README.md", "see [the style](STYLE.md) and [design](DESIGN.md)\n")
        self.assertEqual(self.problems(), ["docs/README.md:1: cites STYLE.md, which is not in the repository",
                                           "docs/README.md:1: links to STYLE.md, which is not in the repository"])

    def test_shared_folder_only_in_ci(self):
        write(self.root, "Makefile", f"DATA ?= {SHARED}/paper-data\n")
        write(self.root, ".ci/run", f"export PAPER_DATA_SOURCE={SHARED}/authors/x.tar.gz\n")
        self.assertEqual(self.problems(),
                         [f"Makefile:1: mentions {SHARED} (only .ci/ may: nothing may depend on it)"])

    def test_missing_source_paths(self):
        write(self.root, "harness/runner.cpp", "")
        write(self.root, "harness/runner.hpp", "")
        write(self.root, "harness/cmd_run.cpp", "")
        write(self.root, "docs/DESIGN.md",
              "harness/runner.cpp, harness/runner.{hpp,cpp}, harness/runner, harness/cmd_*.cpp, harness/runner.*\n"
              "harness/kkt.*, harness/cmd_<name>.cpp, scenes/x.json, solvers/my_solver.{hpp,cpp}\n"
              "harness/runner.{hpp,py} and harness/cmd_*.py; see https://example.org/harness/gone.cpp\n")
        write(self.root, "CMakeLists.txt", "# runs tests/build/no_peers.sh\nadd_test(tests/gone.sh)\n")
        write(self.root, "harness/a.cpp", '// as harness/gone.hpp says\nconst char* p = "harness/data.txt";\n')
        write(self.root, "plots/b.py", '"""Reads harness/gone.csv."""\nPATH = "harness/data.txt"  # harness/none.txt\n')
        self.assertEqual(self.problems(), [
            "CMakeLists.txt:1: cites tests/build/no_peers.sh, which is not in the repository",
            "CMakeLists.txt:2: cites tests/gone.sh, which is not in the repository",
            "docs/DESIGN.md:2: cites harness/kkt.*, which is not in the repository",
            "docs/DESIGN.md:3: cites harness/runner.{hpp,py}, which is not in the repository",
            "docs/DESIGN.md:3: cites harness/cmd_*.py, which is not in the repository",
            "harness/a.cpp:1: cites harness/gone.hpp, which is not in the repository",
            "plots/b.py:1: cites harness/gone.csv, which is not in the repository",
            "plots/b.py:2: cites harness/none.txt, which is not in the repository"])

    def fake_binary(self, cases, solvers):
        """A stand-in contactbench printing `stress --list` and `solvers` as the real one does."""
        path = os.path.join(self.root, "fake-contactbench")
        with open(path, "w") as f:
            f.write("#!/bin/sh\nif [ \"$1\" = stress ]; then printf '%s' '" +
                    "".join(f"{case}\t{family}\tseverity 0\tx\n" for case, family in cases) +
                    "'; else printf '%s' '" + "".join(f"{name}  [any J] x\n" for name in solvers) + "'; fi\n")
        os.chmod(path, 0o755)
        return path

    def test_counts_the_code_prints(self):
        binary = self.fake_binary([("a-1", "a"), ("a-2", "a"), ("b-1", "b")], ["mprgp", "command"])
        write(self.root, "docs/DESIGN.md", "# Design\n\nruns on 3 seeded\ncases in 2 families\n")
        write(self.root, "README.md", "| name | what |\n|---|---|\n| `mprgp` | ours |\n| `ipopt` | peer (optional) |\n"
                                      "| `pgs` | gone |\n\nThe `command` entry runs a program.\n")
        self.assertEqual(docs_check.check_counts(self.root, binary),
                         ["README.md:5: the solver table lists `pgs`, which is not registered (`contactbench "
                          "solvers`) and not marked optional"])
        write(self.root, "docs/DESIGN.md", "# Design\n\nruns on 33 seeded cases in 12 families\n")
        write(self.root, "README.md", "| `mprgp` | ours |\n")
        self.assertEqual(docs_check.check_counts(self.root, binary), [
            "docs/DESIGN.md:3: says 33 seeded cases in 12 families; `contactbench stress --list` prints 3 cases "
            "in 2 families",
            "README.md: does not name the registered solver `command`"])

    def test_command_line_exit_status(self):
        write(self.root, "a.md", "ALGORITHMS.md §7\n")
        run = subprocess.run(["/usr/bin/python3", os.path.join(HERE, "docs_check.py"), self.root],
                             capture_output=True, text=True)
        self.assertEqual(run.returncode, 1)
        self.assertEqual(run.stdout, "a.md:1: cites ALGORITHMS.md §7, which has no heading numbered 7\n")


if __name__ == "__main__":
    unittest.main()
