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


class ReportsStaleFigures(unittest.TestCase):
    """A figure measured at a commit goes stale when the code it describes changes after it."""

    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory()
        self.root = self.tmp.name
        self.git("init", "-q")
        write(self.root, "solvers/mprgp/mprgp.cpp", "int iterations = 224;\n")
        write(self.root, "plots/fig.py", "print(1)\n")
        self.commit("first")
        self.measured = self.git("rev-parse", "--short=10", "HEAD").strip()

    def tearDown(self):
        self.tmp.cleanup()

    def git(self, *args):
        return subprocess.run(["git", "-c", "user.name=t", "-c", "user.email=t@t", *args], cwd=self.root,
                              check=True, capture_output=True, text=True).stdout

    def commit(self, message):
        self.git("add", "-A")
        self.git("commit", "-q", "-m", message)

    def doc(self, tail=""):
        write(self.root, "docs/work.md", f"# Work\n\n224 iterations. Measured at {self.measured} with "
                                         f"`contactbench solve f.qpsnap`.{tail}\n")
        self.commit("doc")

    def change_solver(self, path="solvers/mprgp/mprgp.cpp", text="int iterations = 317;\n", message="solver"):
        write(self.root, path, text)
        self.commit(message)

    def stale(self, line, path="solvers/mprgp/mprgp.cpp"):
        """The check's message for docs/work.md's block at `line`, measured at self.measured."""
        return (f"docs/work.md:{line}: figures measured at {self.measured} with `contactbench solve f.qpsnap` "
                f"predate changes to {path}: re-measure, or say why they still stand (\"Still stands: <commit> ...\") "
                "or that they were not re-measured (\"Not re-measured: ...\")")

    def test_fresh_figures_pass(self):
        self.doc()
        self.assertEqual(stale_figures_problems(self.root), [])

    def test_a_later_change_to_another_folder_leaves_them_fresh(self):
        self.doc()
        write(self.root, "plots/fig.py", "print(2)\n")
        self.commit("plots only")
        self.assertEqual(stale_figures_problems(self.root), [])

    def test_a_planted_solver_change_makes_them_stale(self):
        self.doc()
        self.change_solver()
        self.assertEqual(stale_figures_problems(self.root), [self.stale(3)])

    def test_a_measured_line_wrapped_over_lines_is_read_whole(self):
        # "Measured at <commit>" at the end of one line and "with `command`" on the next: the block
        # is checked as if on one line, and reported at the line where "Measured at" starts.
        write(self.root, "docs/work.md", f"# Work\n\n224 iterations,\nall converged. Measured at {self.measured}\n"
                                         "with `contactbench solve\nf.qpsnap` (covers\nsolvers/).\n")
        self.commit("doc")
        self.assertEqual(stale_figures_problems(self.root), [])
        self.change_solver()
        self.assertEqual(stale_figures_problems(self.root), [self.stale(4)])

    def test_a_measured_line_in_mid_sentence_is_read_too(self):
        write(self.root, "docs/work.md", f"# Work\n\nThe share, measured at {self.measured} with `make share`, "
                                         "was 0.16.\n")
        self.commit("doc")
        self.change_solver()
        self.assertEqual(len(stale_figures_problems(self.root)), 1)

    def test_a_pure_move_leaves_them_fresh_and_a_later_change_does_not(self):
        self.doc()
        os.makedirs(os.path.join(self.root, "solvers", "engine"))
        self.git("mv", "solvers/mprgp/mprgp.cpp", "solvers/engine/mprgp.cpp")
        write(self.root, "plots/fig.py", "# solvers/engine/mprgp.cpp\n")
        self.commit("Pure move: solvers/mprgp/ into solvers/engine/")
        self.assertEqual(stale_figures_problems(self.root), [])
        self.change_solver("solvers/engine/mprgp.cpp")
        self.assertEqual(len(stale_figures_problems(self.root)), 1)
        self.assertIn("predate changes to solvers/engine/mprgp.cpp:", stale_figures_problems(self.root)[0])

    def test_a_stated_reason_keeps_them_up_to_the_commit_it_names(self):
        self.doc()
        write(self.root, "solvers/mprgp/mprgp.cpp", "int iterations_ = 224;\n")
        self.commit("solver")
        renamed = self.git("rev-parse", "--short=10", "HEAD").strip()
        # A reason that names no commit vouches for nothing after the measurement.
        write(self.root, "docs/work.md", f"# Work\n\n224 iterations. Measured at {self.measured} with "
                                         "`contactbench solve f.qpsnap`.\nStill stands: a variable was renamed.\n")
        self.commit("reason without a commit")
        self.assertEqual(len(stale_figures_problems(self.root)), 1)
        write(self.root, "docs/work.md", f"# Work\n\n224 iterations. Measured at {self.measured} with "
                                         f"`contactbench solve f.qpsnap`.\nStill stands: {renamed} renames a variable.\n")
        self.commit("reason")
        self.assertEqual(stale_figures_problems(self.root), [])
        # The next change to the solver is not covered by that reason.
        write(self.root, "solvers/mprgp/mprgp.cpp", "int iterations_ = 317;\n")
        self.commit("solver again")
        self.assertEqual(stale_figures_problems(self.root), [
            f"docs/work.md:3: figures measured at {self.measured} with `contactbench solve f.qpsnap` (said to still "
            f"stand at {renamed}) predate changes to solvers/mprgp/mprgp.cpp: re-measure, or say why they still stand "
            "(\"Still stands: <commit> ...\") or that they were not re-measured (\"Not re-measured: ...\")"])

    def test_saying_they_were_not_re_measured_keeps_them_visible(self):
        self.doc("\nNot re-measured: the solver changed after it; `make ladder` gives today's figures.")
        self.change_solver()
        self.assertEqual(stale_figures_problems(self.root), [])

    def test_covers_narrows_what_they_describe(self):
        write(self.root, "docs/work.md", f"Measured at {self.measured} with `make x` (covers plots/*.py).\n")
        write(self.root, "solvers/mprgp/mprgp.cpp", "int iterations = 1;\n")
        self.commit("solver and doc")
        self.assertEqual(stale_figures_problems(self.root), [])
        write(self.root, "plots/fig.py", "print(3)\n")
        self.commit("plot")
        self.assertEqual(len(stale_figures_problems(self.root)), 1)

    def test_an_unknown_commit_is_reported(self):
        write(self.root, "docs/work.md", "Measured at 0123456789 with `make x`.\n")
        self.commit("doc")
        self.assertEqual(stale_figures_problems(self.root), [
            "docs/work.md:1: figures measured at 0123456789, a commit this clone does not have (cannot tell "
            "whether `make x` would still give them)"])


def stale_figures_problems(root):
    return [p for p in docs_check.check(root) if "measured at" in p]


if __name__ == "__main__":
    unittest.main()
