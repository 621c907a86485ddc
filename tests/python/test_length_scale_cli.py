"""The scene size l a user gives (issue 41; docs/accuracy.md "Length scale"), through the binary
(env CB_CONTACTBENCH): `solve/judge/run --length-scale L`, a suite's `length_scale`, and the
snapshot field `convert --length-scale` writes; bad values end in exit 2 naming the option or
field. A problem without geometry takes its reference solution's extent.

Run from tests/python: /usr/bin/python3 -m unittest -v test_length_scale_cli
"""
import json
import os
import shutil
import subprocess
import tempfile
import unittest

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
CB = os.environ.get("CB_CONTACTBENCH", os.path.join(ROOT, "build", "bin", "contactbench"))


def run(args):
    return subprocess.run([CB] + args, capture_output=True, text=True, timeout=300,
                          env=dict(os.environ, OPENBLAS_NUM_THREADS="1"))


def write_mtx_folder(folder, A, b):
    """A box QP without geometry (J = I, c = 0, x0 = 0) as a Matrix Market folder."""
    os.makedirs(folder)
    n = len(b)

    def dense(name, v):
        with open(os.path.join(folder, name), "w") as f:
            f.write("%%%%MatrixMarket matrix array real general\n%d 1\n" % n)
            f.writelines("%.17g\n" % x for x in v)

    with open(os.path.join(folder, "A.mtx"), "w") as f:
        f.write("%%%%MatrixMarket matrix coordinate real general\n%d %d %d\n" % (n, n, n * n))
        f.writelines("%d %d %.17g\n" % (i + 1, j + 1, A[i, j]) for i in range(n) for j in range(n))
    with open(os.path.join(folder, "J.mtx"), "w") as f:
        f.write("%%%%MatrixMarket matrix coordinate real general\n%d %d %d\n" % (n, n, n))
        f.writelines("%d %d 1\n" % (i + 1, i + 1) for i in range(n))
    dense("b.mtx", b)
    dense("c.mtx", np.zeros(n))
    dense("x0.mtx", np.zeros(n))


class LengthScaleCli(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.mkdtemp(prefix="cb_length_")
        os.environ["CB_CACHE"] = os.path.join(cls.tmp, "cache")
        # A = diag(1, 2, 4, 8), b = (4, -1, 8, 16): x* = (4, 0, 2, 2), whose range is 4.
        A = np.diag([1.0, 2.0, 4.0, 8.0])
        b = np.array([4.0, -1.0, 8.0, 16.0])
        write_mtx_folder(os.path.join(cls.tmp, "box"), A, b)
        cls.snap = os.path.join(cls.tmp, "box.qpsnap")
        r = run(["convert", os.path.join(cls.tmp, "box"), cls.snap])
        assert r.returncode == 0, r.stderr

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.tmp, ignore_errors=True)

    def solve(self, *extra, snap=None):
        out = os.path.join(self.tmp, "run.json")
        r = run(["solve", snap or self.snap, "--solver", "pgs", "--json", out] + list(extra))
        self.assertEqual(r.returncode, 0, r.stderr)
        with open(out) as f:
            return json.load(f)

    def test_without_geometry_l_is_the_reference_extent(self):
        rec = self.solve()
        self.assertEqual(rec["length_scale_source"], "reference_extent")
        self.assertAlmostEqual(rec["length_scale"], 4.0, delta=1e-9)

    def test_given_on_the_command_line(self):
        rec = self.solve("--length-scale", "0.5")
        self.assertEqual((rec["length_scale"], rec["length_scale_source"]), (0.5, "given"))
        r = run(["solve", self.snap, "--solver", "pgs", "--length-scale", "-1"])
        self.assertEqual(r.returncode, 2)
        self.assertIn("solve: --length-scale: expected a finite number > 0, got '-1'", r.stderr)

    def test_snapshot_field_written_by_convert(self):
        snap = os.path.join(self.tmp, "box-l.qpsnap")
        r = run(["convert", self.snap, snap, "--length-scale", "2.5"])
        self.assertEqual(r.returncode, 0, r.stderr)
        rec = self.solve(snap=snap)
        self.assertEqual((rec["length_scale"], rec["length_scale_source"]), (2.5, "snapshot"))
        r = run(["convert", self.snap, os.path.join(self.tmp, "bad.qpsnap"), "--length-scale", "nan"])
        self.assertEqual(r.returncode, 2)
        self.assertIn("convert: --length-scale: expected a finite number > 0, got 'nan'", r.stderr)
        self.assertFalse(os.path.exists(os.path.join(self.tmp, "bad.qpsnap")))

    def test_suite_key_and_run_option(self):
        suite = os.path.join(self.tmp, "suite.json")
        with open(suite, "w") as f:
            json.dump({"name": "l", "snapshots": [self.snap], "solvers": ["pgs"], "length_scale": 3.0}, f)
        for extra, expected in (([], (3.0, "suite")), (["--length-scale", "7"], (7.0, "given"))):
            out = os.path.join(self.tmp, "suite-out-%d" % len(extra))
            r = run(["run", suite, "--out", out] + extra)
            self.assertEqual(r.returncode, 0, r.stderr)
            with open(os.path.join(out, "runs", "box__pgs.json")) as f:
                rec = json.load(f)
            self.assertEqual((rec["length_scale"], rec["length_scale_source"]), expected)
        with open(suite, "w") as f:
            json.dump({"name": "l", "snapshots": [self.snap], "solvers": ["pgs"], "length_scale": 0}, f)
        r = run(["run", suite, "--out", os.path.join(self.tmp, "bad-out")])
        self.assertEqual(r.returncode, 2)
        self.assertIn("/length_scale: must be > 0, got 0", r.stderr)

    def test_judge_uses_the_same_l(self):
        sol = os.path.join(self.tmp, "x.txt")
        with open(sol, "w") as f:
            f.write("4\n0\n2\n2\n")
        r = run(["judge", self.snap, sol])
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertIn("of the scene size l = 4 (reference_extent)", r.stdout)
        r = run(["judge", self.snap, sol, "--length-scale", "8"])
        self.assertIn("of the scene size l = 8 (given)", r.stdout)


if __name__ == "__main__":
    unittest.main()
