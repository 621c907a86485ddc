"""plots/qpsnap.py's write_qpsnap: numpy/scipy arrays -> .qpsnap, read back by the Python reader and
by contactbench (which rewrites it: every array must come back bit for bit).

    cd tests/python && /usr/bin/python3 -m unittest test_qpsnap_writer
"""
import json
import os
import subprocess
import sys
import tempfile
import unittest

import numpy as np
import scipy.sparse as sp

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(os.path.dirname(HERE)))  # plots/ is a package of the repository root

from plots import qpsnap  # noqa: E402

CONTACTBENCH = os.environ.get("CB_CONTACTBENCH", "")


def small_qp():
    """A 4-unknown SPD A with values whose bits matter, two constraints."""
    A = sp.csr_matrix(np.array([[4.0, -1.0 / 3.0, 0, 0], [-1.0 / 3.0, 4.0, 0.1, 0], [0, 0.1, 3.0, 0],
                                [0, 0, 0, 2.0 / 7.0]]))
    b = np.array([1.0, -2.0 / 3.0, 0.5, 1e-3])
    J = sp.csr_matrix(np.array([[1.0, 0, 0, 0], [0, 0.5, 0.5, 0]]))
    c = np.array([0.25, -1.0 / 9.0])
    return A, b, J, c


class WriteQpsnap(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.mkdtemp(prefix="cb_qpsnap_writer_")

    def tearDown(self):
        import shutil
        shutil.rmtree(self.tmp, ignore_errors=True)

    def test_round_trip_through_the_python_reader(self):
        A, b, J, c = small_qp()
        path = qpsnap.write_qpsnap(os.path.join(self.tmp, "mine.qpsnap"), A, b, J, c, x0=np.ones(4),
                                   meta={"family": "mine"}, x_ref=np.arange(4.0))
        snap = qpsnap.read_qpsnap(path)
        self.assertEqual((snap["n"], snap["m"], snap["meta"]), (4, 2, {"family": "mine"}))
        a = snap["arrays"]
        self.assertEqual(a["A.data"].tobytes(), A.data.astype("<f8").tobytes())
        self.assertEqual(list(a["A.indices"]), list(A.indices))
        self.assertEqual(a["b"].tobytes(), b.tobytes())
        self.assertEqual(a["c"].tobytes(), c.tobytes())
        self.assertEqual(list(a["x0"]), [1.0] * 4)
        self.assertEqual(list(a["x_ref"]), [0.0, 1.0, 2.0, 3.0])
        self.assertNotIn("lambda_ref", a)

    def test_dense_arrays_and_no_constraints(self):
        A, b, _, _ = small_qp()
        path = qpsnap.write_qpsnap(os.path.join(self.tmp, "free.qpsnap"), A.toarray(), b)
        snap = qpsnap.read_qpsnap(path)
        self.assertEqual((snap["n"], snap["m"]), (4, 0))
        self.assertEqual(list(snap["arrays"]["J.indptr"]), [0])

    def test_a_bad_problem_leaves_no_file(self):
        A, b, J, c = small_qp()
        bad = A.tolil()
        bad[0, 1] = 5.0  # not symmetric
        path = os.path.join(self.tmp, "bad.qpsnap")
        with self.assertRaises(qpsnap.QpsnapError) as e:
            qpsnap.write_qpsnap(path, bad.tocsr(), b, J, c)
        self.assertIn(": A: not symmetric: A(0, 1) = 5 but A(1, 0) = -0.33333333333333331", str(e.exception))
        with self.assertRaises(qpsnap.QpsnapError) as e:
            qpsnap.write_qpsnap(path, A, b[:3], J, c)
        self.assertEqual(str(e.exception), path + ": A: expected shape (3, 3), got (4, 4)")
        self.assertEqual(os.listdir(self.tmp), [])

    @unittest.skipUnless(CONTACTBENCH and os.path.exists(CONTACTBENCH), "CB_CONTACTBENCH not set (ctest sets it)")
    def test_contactbench_reads_it_bit_for_bit(self):
        A, b, J, c = small_qp()
        path = qpsnap.write_qpsnap(os.path.join(self.tmp, "mine.qpsnap"), A, b, J, c, meta={"family": "mine"})
        info = subprocess.run([CONTACTBENCH, "info", path, "--json"], capture_output=True, text=True)
        self.assertEqual(info.returncode, 0, info.stderr)
        self.assertEqual((json.loads(info.stdout)["n"], json.loads(info.stdout)["nnz_A"]), (4, 8))
        back = os.path.join(self.tmp, "back.qpsnap")
        out = subprocess.run([CONTACTBENCH, "convert", path, back], capture_output=True, text=True)
        self.assertEqual(out.returncode, 0, out.stderr)
        mine, theirs = qpsnap.read_qpsnap(path)["arrays"], qpsnap.read_qpsnap(back)["arrays"]
        self.assertEqual(sorted(mine), sorted(theirs))
        for name in mine:
            self.assertEqual(mine[name].tobytes(), theirs[name].tobytes(), name)

    def friction(self):
        """mu, T (2m x n), cT, h, v0 for small_qp()."""
        T = sp.csr_matrix(np.array([[0, 1.0, 0, 0], [0, 0, 1.0 / 3.0, 0], [1.0, 0, 0, 0], [0, 0, 0, -1.0]]))
        return {"mu": np.array([0.5, 0.0]), "T": T, "cT": np.array([0.1, -0.2, 1.0 / 7.0, 0.0]), "h": 0.01,
                "v0": np.array([1.0, -1.0, 0.5, 2.0 / 3.0])}

    def test_friction_round_trip_is_version_2(self):
        A, b, J, c = small_qp()
        f = self.friction()
        path = qpsnap.write_qpsnap(os.path.join(self.tmp, "fric.qpsnap"), A, b, J, c, **f)
        snap = qpsnap.read_qpsnap(path)
        self.assertEqual((snap["header"]["version"], snap["header"]["h"]), (2, 0.01))
        self.assertEqual(snap["arrays"]["mu"].tobytes(), f["mu"].tobytes())
        self.assertEqual(snap["arrays"]["cT"].tobytes(), f["cT"].tobytes())
        self.assertEqual(snap["arrays"]["v0"].tobytes(), f["v0"].tobytes())
        np.testing.assert_array_equal(qpsnap.tangents(snap).toarray(), f["T"].toarray())
        # No friction field: version 1, as before.
        plain = qpsnap.write_qpsnap(os.path.join(self.tmp, "plain.qpsnap"), A, b, J, c)
        self.assertEqual(qpsnap.read_qpsnap(plain)["header"]["version"], 1)

    def test_bad_friction_leaves_no_file(self):
        A, b, J, c = small_qp()
        path = os.path.join(self.tmp, "bad.qpsnap")
        f = self.friction()
        f["T"] = f["T"][:3]
        with self.assertRaises(qpsnap.QpsnapError) as e:
            qpsnap.write_qpsnap(path, A, b, J, c, **f)
        self.assertEqual(str(e.exception), path + ": T: expected shape (4, 4), got (3, 4)")
        f = self.friction()
        f["mu"] = np.array([0.5, -1.0])
        with self.assertRaises(qpsnap.QpsnapError) as e:
            qpsnap.write_qpsnap(path, A, b, J, c, **f)
        self.assertIn(": mu: negative friction coefficient -1 at contact 1", str(e.exception))
        self.assertEqual(os.listdir(self.tmp), [])

    @unittest.skipUnless(CONTACTBENCH and os.path.exists(CONTACTBENCH), "CB_CONTACTBENCH not set (ctest sets it)")
    def test_contactbench_keeps_friction_bit_for_bit(self):
        A, b, J, c = small_qp()
        path = qpsnap.write_qpsnap(os.path.join(self.tmp, "fric.qpsnap"), A, b, J, c, **self.friction())
        back = os.path.join(self.tmp, "back.qpsnap")
        out = subprocess.run([CONTACTBENCH, "convert", path, back], capture_output=True, text=True)
        self.assertEqual(out.returncode, 0, out.stderr)
        mine, theirs = qpsnap.read_qpsnap(path), qpsnap.read_qpsnap(back)
        self.assertEqual(sorted(mine["arrays"]), sorted(theirs["arrays"]))
        for name in mine["arrays"]:
            self.assertEqual(mine["arrays"][name].tobytes(), theirs["arrays"][name].tobytes(), name)
        self.assertEqual(theirs["header"]["h"], 0.01)


if __name__ == "__main__":
    unittest.main()
