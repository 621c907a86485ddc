"""plots/friction_suite.py's suite instances: suites/friction.json at a given tol with its data under
OUT, the solvers' order reversed in even rounds (interleaved rounds, docs/work.md "Claims"), and the
problem groups of the report.

Run from tests/python: /usr/bin/python3 -m unittest test_friction_suite
"""
import json
import os
import sys
import tempfile
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(os.path.dirname(HERE)))

from plots import friction_suite as fs  # noqa: E402


class TestFrictionSuiteInstances(unittest.TestCase):
    def test_tol_paths_and_order(self):
        with open(fs.SUITE) as f:
            suite = json.load(f)
        labels = [s["label"] for s in suite["solvers"]]
        with tempfile.TemporaryDirectory() as out:
            odd = json.load(open(fs.instantiate(out, 1e-4, 1)))
            even = json.load(open(fs.instantiate(out, 1e-4, 2)))
            self.assertTrue(os.path.basename(fs.instantiate(out, 1e-8, 3)).endswith("tol1e-08.round3.json"))
        self.assertEqual(odd["tol"], 1e-4)
        self.assertEqual([s["label"] for s in odd["solvers"]], labels)
        self.assertEqual([s["label"] for s in even["solvers"]], labels[::-1])
        sims = [e for e in odd["snapshots"] if isinstance(e, dict)]
        self.assertEqual([e["sim"] for e in sims], [os.path.join(out, "sim", n) for n, _ in fs.SCENES])
        self.assertEqual([e["scene"] for e in sims],
                         [os.path.join(fs.ROOT, "scenes", f"{n}.json") for n, _ in fs.SCENES])
        self.assertIn(os.path.join(out, "fclib"), odd["snapshots"])

    def test_problem_groups(self):
        self.assertEqual(fs.problem_group("friction_slide_f0003_n0"), "friction_slide")
        self.assertEqual(fs.problem_group("two_dinos_1303_friction_f0011_n0"), "two_dinos_1303_friction")
        self.assertEqual(fs.problem_group("CubeH8"), "FCLIB global")


if __name__ == "__main__":
    unittest.main()
