"""plots/qpsnap.py against files written by contactbench, and contactbench against scipy.io.mmwrite.

Needs CB_CONTACTBENCH (set by ctest) for the interop tests; the reader tests run without it.
    cd tests/python && PYTHONPATH=../../plots /usr/bin/python3 -m unittest test_qpsnap_reader
"""
import json
import os
import shutil
import subprocess
import sys
import tempfile
import unittest
import zlib

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(os.path.dirname(HERE)))  # plots/ is a package of the repository root

from plots import qpsnap  # noqa: E402

CONTACTBENCH = os.environ.get("CB_CONTACTBENCH", "")
HAVE_CB = bool(CONTACTBENCH) and os.path.exists(CONTACTBENCH)


def write_raw(path, arrays, n=3, m=2, edit=None):
    """An independent writer: arrays {name: ndarray} in sorted name order, no header padding."""
    header = {"format": "qpsnap", "version": 1, "n": n, "m": m, "arrays": {}, "meta": {"scene": "tiny"}}
    data = b""
    for name in sorted(arrays):
        a = arrays[name]
        raw = a.astype("<i8" if a.dtype.kind == "i" else "<f8").tobytes()
        header["arrays"][name] = {"dtype": "int64" if a.dtype.kind == "i" else "float64", "shape": list(a.shape),
                                  "offset": len(data), "nbytes": len(raw), "crc32": zlib.crc32(raw) & 0xFFFFFFFF}
        data += raw
    if edit:
        edit(header)
    text = json.dumps(header).encode()
    with open(path, "wb") as f:
        f.write(len(text).to_bytes(8, "little") + text + data)
    return path


def tiny():
    i = lambda v: np.array(v, dtype=np.int64)  # noqa: E731
    return {"A.indptr": i([0, 2, 5, 7]), "A.indices": i([0, 1, 0, 1, 2, 1, 2]),
            "A.data": np.array([4, 1, 1, 5, 2, 2, 6.0]), "b": np.array([1, 2, 3.0]), "x0": np.zeros(3),
            "J.indptr": i([0, 1, 3]), "J.indices": i([0, 1, 2]), "J.data": np.array([1, -1, 1.0]),
            "c": np.array([0.5, -1])}


def tiny_friction():
    """tiny() with friction (version 2): mu per row, T = [0 1 0; 0 0 1; 1 0 0; 0 1 1] (2m x n)."""
    a = tiny()
    a.update({"mu": np.array([0.3, 0.0]), "T.indptr": np.array([0, 1, 2, 3, 5], dtype=np.int64),
              "T.indices": np.array([1, 2, 0, 1, 2], dtype=np.int64), "T.data": np.ones(5)})
    return a


def version2(header):
    header["version"] = 2


def run_cb(*args):
    return subprocess.run([CONTACTBENCH, *args], check=True, capture_output=True, text=True).stdout


class ReaderTest(unittest.TestCase):
    def setUp(self):
        self.dir = tempfile.mkdtemp(prefix="cb_qpsnap_py_")

    def tearDown(self):
        shutil.rmtree(self.dir, ignore_errors=True)

    def path(self, name):
        return os.path.join(self.dir, name)

    def expect_error(self, path, tail):
        with self.assertRaises(qpsnap.QpsnapError) as ctx:
            qpsnap.read_qpsnap(path)
        self.assertEqual(str(ctx.exception), f"{path}: {tail}")

    def test_reads_tiny(self):
        snap = qpsnap.read_qpsnap(write_raw(self.path("t.qpsnap"), tiny()))
        self.assertEqual((snap["n"], snap["m"]), (3, 2))
        self.assertEqual(snap["meta"], {"scene": "tiny"})
        A, J = qpsnap.matrices(snap)
        np.testing.assert_array_equal(A.toarray(), [[4, 1, 0], [1, 5, 2], [0, 2, 6]])
        np.testing.assert_array_equal(J.toarray(), [[1, 0, 0], [0, -1, 1]])

    def test_corruptions_match_cpp_messages(self):
        a = tiny()
        a["A.indices"] = np.array([0, 1, 0, 1, 2, 1, 7], dtype=np.int64)
        self.expect_error(write_raw(self.path("r.qpsnap"), a), "A.indices: column 7 out of range [0, 3) in row 2")
        a = tiny()
        a["b"] = np.array([1, np.nan, 3])
        self.expect_error(write_raw(self.path("nan.qpsnap"), a), "b: non-finite value nan at index 1")
        a = tiny()
        a["A.data"] = np.array([4, 1, 1.5, 5, 2, 2.25, 6])
        self.expect_error(write_raw(self.path("asym.qpsnap"), a),
                          "A: not symmetric: A(0, 1) = 1 but A(1, 0) = 1.5 (difference 0.5 > 1e-12 * max|A_ij| = "
                          "6.0000000000000003e-12)")
        a = tiny()
        del a["J.data"]
        self.expect_error(write_raw(self.path("miss.qpsnap"), a), "J.data: required array missing")
        self.expect_error(write_raw(self.path("v.qpsnap"), tiny(), edit=lambda h: h.update(version=3)),
                          "version: unsupported version 3 (this reader knows versions 1 and 2)")
        p = write_raw(self.path("crc.qpsnap"), tiny())
        with open(p, "rb") as f:
            raw = bytearray(f.read())
        raw[-1] ^= 1
        with open(p, "wb") as f:
            f.write(raw)
        with self.assertRaisesRegex(qpsnap.QpsnapError, r"x0\.crc32: mismatch: header says \d+, data has \d+"):
            qpsnap.read_qpsnap(p)
        a = tiny()
        a["J.indices"] = np.array([0, 2, 1], dtype=np.int64)
        self.expect_error(write_raw(self.path("s.qpsnap"), a), "J.indices: columns not strictly increasing in row 1 (2 then 1)")
        a = tiny()
        a["A.data"] = np.array([4, 1, 1, 5, 2, 2, -6.0])
        self.expect_error(write_raw(self.path("d.qpsnap"), a), "A: diagonal entry A(2, 2) = -6 is not positive (A must be SPD)")
        with open(self.path("short.qpsnap"), "wb") as f:
            f.write(b"abcde")
        self.expect_error(self.path("short.qpsnap"),
                          "header: file too short: 5 bytes, a .qpsnap starts with an 8-byte header length")

    def test_friction_fields_read(self):
        snap = qpsnap.read_qpsnap(write_raw(self.path("f.qpsnap"), tiny_friction(), edit=version2))
        np.testing.assert_array_equal(snap["arrays"]["mu"], [0.3, 0.0])
        np.testing.assert_array_equal(qpsnap.tangents(snap).toarray(), [[0, 1, 0], [0, 0, 1], [1, 0, 0], [0, 1, 1]])
        self.assertIsNone(qpsnap.tangents(qpsnap.read_qpsnap(write_raw(self.path("t.qpsnap"), tiny()))))

    def test_friction_corruptions_match_cpp_messages(self):
        # The same files and messages as tests/problems/test_qpsnap.cpp's QpsnapFrictionCorrupt.
        a = tiny_friction()
        a["mu"] = np.array([0.3, -0.5])
        self.expect_error(write_raw(self.path("neg.qpsnap"), a, edit=version2),
                          "mu: negative friction coefficient -0.5 at contact 1")
        a["mu"] = np.array([np.nan, 0.1])
        self.expect_error(write_raw(self.path("nan.qpsnap"), a, edit=version2), "mu: non-finite value nan at index 0")
        a = tiny_friction()
        for t in ("T.indptr", "T.indices", "T.data"):
            del a[t]
        self.expect_error(write_raw(self.path("not.qpsnap"), a, edit=version2),
                          "T: missing: mu needs the two tangent rows per contact (T, 2m x n)")
        a = tiny_friction()
        del a["mu"]
        self.expect_error(write_raw(self.path("nomu.qpsnap"), a, edit=version2),
                          "mu: missing: T is given without friction coefficients")
        a = tiny_friction()
        a["T.indptr"], a["T.indices"], a["T.data"] = np.array([0, 1, 2, 3]), np.array([1, 2, 0]), np.ones(3)
        self.expect_error(write_raw(self.path("rows.qpsnap"), a, edit=version2),
                          "T.indptr.shape: expected [5] (m = 2, two tangent rows per contact, 2m + 1 entries), got [4]")
        a = tiny_friction()
        a["T.indices"] = np.array([1, 2, 0, 1, 3])
        self.expect_error(write_raw(self.path("cols.qpsnap"), a, edit=version2),
                          "T.indices: column 3 out of range [0, 3) in row 3")
        a = tiny_friction()
        a["v0"] = np.array([0, 1, 2.0])
        self.expect_error(write_raw(self.path("v0.qpsnap"), a, edit=version2), "h: missing: v0 is given without the step h")
        self.expect_error(write_raw(self.path("h.qpsnap"), a, edit=lambda h: h.update(version=2, h=-0.01)),
                          "h: expected a positive finite time step, got -0.01")
        self.expect_error(write_raw(self.path("v1.qpsnap"), tiny_friction()),
                          "arrays.T.data: a version 2 array in a version 1 snapshot")

    @unittest.skipUnless(HAVE_CB, "CB_CONTACTBENCH not set")
    def test_contactbench_refuses_hostile_friction_with_exit_2(self):
        a = tiny_friction()
        a["mu"] = np.array([np.nan, 0.1])
        p = write_raw(self.path("nan_mu.qpsnap"), a, edit=version2)
        r = subprocess.run([CONTACTBENCH, "info", p], capture_output=True, text=True)
        self.assertEqual(r.returncode, 2)
        self.assertIn(f"{p}: mu: non-finite value nan at index 0", r.stderr)
        self.assertEqual(r.stdout, "")
        p = write_raw(self.path("ok.qpsnap"), tiny_friction(), edit=version2)
        info = json.loads(run_cb("info", p, "--json"))
        self.assertEqual(info["version"], 2)
        self.assertEqual((info["friction"]["mu_min"], info["friction"]["mu_max"]), (0.0, 0.3))
        self.assertEqual(info["friction"]["frictional_contacts"], 1)
        self.assertIn("friction:    mu in [0.0, 0.3], 1 of 2 contacts with mu > 0, T 4 x 3 (5 nonzeros)",
                      run_cb("info", p))
        old = json.loads(run_cb("info", write_raw(self.path("v1.qpsnap"), tiny()), "--json"))
        self.assertEqual((old["version"], old["friction"]["mu_max"], old["friction"]["tangent_rows"]), (1, 0.0, 0))

    def test_small_asymmetry_symmetrised(self):
        a = tiny()
        a["A.data"] = np.array([4, 1, 1 + 1e-15, 5, 2, 2, 6])
        snap = qpsnap.read_qpsnap(write_raw(self.path("a.qpsnap"), a))
        A, _ = qpsnap.matrices(snap)
        self.assertEqual(A[0, 1], A[1, 0])
        self.assertEqual(A[0, 1], 0.5 * 1 + 0.5 * (1 + 1e-15))

    @unittest.skipUnless(HAVE_CB, "CB_CONTACTBENCH not set")
    def test_reads_what_contactbench_writes(self):
        p = self.path("plane.qpsnap")
        run_cb("generate", "plane", "--out", p, "--seed", "3", "--param", "nx=3")
        info = json.loads(run_cb("info", p, "--json"))
        snap = qpsnap.read_qpsnap(p)
        self.assertEqual(snap["n"], info["n"])
        self.assertEqual(snap["m"], info["m"])
        self.assertEqual(snap["arrays"]["A.data"].size, info["nnz_A"])
        self.assertEqual(qpsnap.content_hash(p), info["hash"])
        self.assertEqual(snap["meta"]["generator"]["family"], "plane")
        A, J = qpsnap.matrices(snap)
        self.assertEqual(abs(A - A.T).max(), 0.0)
        x0, c = snap["arrays"]["x0"], snap["arrays"]["c"]
        self.assertEqual(int(np.sum(J @ x0 - c < 0)), info["violated_at_x0"])
        self.assertEqual(snap["arrays"]["contact.vertex"].shape, (snap["m"], 4))

    @unittest.skipUnless(HAVE_CB, "CB_CONTACTBENCH not set")
    def test_scipy_mmwrite_folder_converts(self):
        import scipy.io
        import scipy.sparse as sp
        rng = np.random.default_rng(5)
        n, m = 30, 7
        B = sp.random(n, n, density=0.1, random_state=1, format="csr")
        A = (B @ B.T + sp.identity(n) * 2.0).tocsr()  # SPD, symmetric: mmwrite writes "symmetric"
        J = sp.random(m, n, density=0.2, random_state=2, format="csr")
        b, x0, c = rng.normal(size=n), rng.normal(size=n), rng.normal(size=m)
        folder = self.path("mm")
        os.makedirs(folder)
        scipy.io.mmwrite(os.path.join(folder, "A.mtx"), A)
        scipy.io.mmwrite(os.path.join(folder, "J.mtx"), J)
        scipy.io.mmwrite(os.path.join(folder, "b.mtx"), b.reshape(-1, 1))
        scipy.io.mmwrite(os.path.join(folder, "x0.mtx"), x0.reshape(-1, 1))
        scipy.io.mmwrite(os.path.join(folder, "c.mtx"), c.reshape(-1, 1))
        out = self.path("from_scipy.qpsnap")
        run_cb("convert", folder, out)
        snap = qpsnap.read_qpsnap(out)
        A2, J2 = qpsnap.matrices(snap)
        ref_A = scipy.io.mmread(os.path.join(folder, "A.mtx")).toarray()
        np.testing.assert_array_equal(A2.toarray(), ref_A)
        np.testing.assert_allclose(A2.toarray(), A.toarray(), rtol=1e-15, atol=1e-15)
        np.testing.assert_array_equal(J2.toarray(), scipy.io.mmread(os.path.join(folder, "J.mtx")).toarray())
        np.testing.assert_array_equal(snap["arrays"]["b"], b)
        np.testing.assert_array_equal(snap["arrays"]["x0"], x0)
        np.testing.assert_array_equal(snap["arrays"]["c"], c)
        # And back out: scipy reads what contactbench writes.
        back = self.path("back")
        run_cb("convert", out, back)
        np.testing.assert_array_equal(scipy.io.mmread(os.path.join(back, "A.mtx")).toarray(), ref_A)
        np.testing.assert_array_equal(scipy.io.mmread(os.path.join(back, "c.mtx")).ravel(), c)

    @unittest.skipUnless(HAVE_CB, "CB_CONTACTBENCH not set")
    def test_convert_round_trip_is_bit_exact(self):
        p1, folder, p2 = self.path("a.qpsnap"), self.path("f"), self.path("b.qpsnap")
        run_cb("generate", "coupled", "--out", p1, "--seed", "8", "--param", "nx=2", "--param", "nz=2")
        run_cb("convert", p1, folder)
        run_cb("convert", folder, p2)
        s1, s2 = qpsnap.read_qpsnap(p1), qpsnap.read_qpsnap(p2)
        self.assertEqual(set(s1["arrays"]), set(s2["arrays"]))
        for name in s1["arrays"]:
            self.assertEqual(s1["arrays"][name].tobytes(), s2["arrays"][name].tobytes(), name)
        self.assertEqual(s1["meta"], s2["meta"])

    @unittest.skipUnless(HAVE_CB, "CB_CONTACTBENCH not set")
    def test_bad_input_exit_status_and_message(self):
        p = write_raw(self.path("bad.qpsnap"), {**tiny(), "b": np.array([1, np.inf, 3])})
        r = subprocess.run([CONTACTBENCH, "info", p], capture_output=True, text=True)
        self.assertEqual(r.returncode, 2)
        self.assertIn(f"{p}: b: non-finite value inf at index 1", r.stderr)


if __name__ == "__main__":
    unittest.main()
