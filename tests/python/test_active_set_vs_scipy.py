"""Cross-check of the reference solver against scipy on outside QPs.

A small QP  min 1/2 x'Ax - b'x  s.t.  Jx >= c  is written with scipy.io.mmwrite (the Matrix
Market folder of `contactbench convert`), converted to .qpsnap, solved with
`contactbench solve --solver active-set`, and its objective compared with
scipy.optimize.minimize (SLSQP, trust-constr) on the same QP to 1e-7 relative.
"""
import json
import os
import subprocess
import tempfile
import unittest

import numpy as np
import scipy.io
import scipy.optimize
import scipy.sparse


def contactbench():
    path = os.environ.get("CB_CONTACTBENCH", "")
    if not path or not os.path.exists(path):
        raise unittest.SkipTest("CB_CONTACTBENCH is not set to a built contactbench binary")
    return path


def make_qp(seed, n=30, m=12, duplicate=False):
    """Seeded strictly convex QP with a known feasible point (so the set is not empty)."""
    rng = np.random.default_rng(seed)
    B = rng.standard_normal((n, n))
    A = B @ B.T / n + 0.5 * np.eye(n)
    A = 0.5 * (A + A.T)
    b = A @ rng.standard_normal(n)
    J = np.zeros((m, n))
    for i in range(m):
        cols = rng.choice(n, size=4, replace=False)
        J[i, cols] = rng.standard_normal(4)
    if duplicate:
        J[m - 1] = J[0]
    x_feasible = rng.standard_normal(n)
    # Rows tight or loose at x_feasible; the unconstrained minimiser violates several of them.
    c = J @ x_feasible - np.abs(rng.standard_normal(m)) * (rng.random(m) < 0.5)
    if duplicate:
        c[m - 1] = c[0]
    return A, b, J, c, np.zeros(n)


def write_folder(folder, A, b, J, c, x0):
    os.makedirs(folder, exist_ok=True)
    scipy.io.mmwrite(os.path.join(folder, "A.mtx"), scipy.sparse.coo_matrix(A), symmetry="general")
    scipy.io.mmwrite(os.path.join(folder, "J.mtx"), scipy.sparse.coo_matrix(J))
    for name, v in (("b", b), ("c", c), ("x0", x0)):
        scipy.io.mmwrite(os.path.join(folder, name + ".mtx"), v.reshape(-1, 1))


def scipy_objective(A, b, J, c, method):
    f = lambda x: 0.5 * x @ A @ x - b @ x
    grad = lambda x: A @ x - b
    cons = [{"type": "ineq", "fun": lambda x: J @ x - c, "jac": lambda x: J}]
    x_start = np.linalg.solve(A, b)
    if method == "SLSQP":
        res = scipy.optimize.minimize(f, x_start, jac=grad, constraints=cons, method="SLSQP",
                                      options={"ftol": 1e-13, "maxiter": 2000})
    else:
        lin = scipy.optimize.LinearConstraint(J, c, np.inf)
        res = scipy.optimize.minimize(f, x_start, jac=grad, hess=lambda x: A, constraints=[lin],
                                      method="trust-constr",
                                      options={"gtol": 1e-12, "xtol": 1e-14, "maxiter": 5000})
    return res.fun, res.x, res


class ActiveSetVsScipy(unittest.TestCase):
    def solve_with_contactbench(self, A, b, J, c, x0):
        exe = contactbench()
        with tempfile.TemporaryDirectory() as tmp:
            folder = os.path.join(tmp, "qp")
            write_folder(folder, A, b, J, c, x0)
            snap = os.path.join(tmp, "out.qpsnap")
            conv = subprocess.run([exe, "convert", folder, snap], capture_output=True, text=True)
            self.assertEqual(conv.returncode, 0, conv.stderr)
            out_json = os.path.join(tmp, "out.json")
            sol_dir = os.path.join(tmp, "solution")
            run = subprocess.run([exe, "solve", snap, "--solver", "active-set", "--json", out_json,
                                  "--save-solution", sol_dir], capture_output=True, text=True)
            self.assertEqual(run.returncode, 0, run.stderr)
            with open(out_json) as fh:
                record = json.load(fh)
            x = None
            x_path = os.path.join(sol_dir, "x.mtx")
            if os.path.exists(x_path):
                x = np.asarray(scipy.io.mmread(x_path)).reshape(-1)
            return record, x

    def check_seed(self, seed, duplicate=False):
        A, b, J, c, x0 = make_qp(seed, duplicate=duplicate)
        record, x = self.solve_with_contactbench(A, b, J, c, x0)
        self.assertEqual(record["status"], "converged", record.get("message"))
        f_cb = record["objective"]
        f_sp, x_sp, res = scipy_objective(A, b, J, c, "SLSQP")
        self.assertTrue(res.success, res.message)
        # scipy's point must be feasible for the comparison to mean anything
        self.assertGreaterEqual((J @ x_sp - c).min(), -1e-8)
        self.assertLessEqual(abs(f_cb - f_sp), 1e-7 * max(1.0, abs(f_sp)),
                             "contactbench %.15g vs SLSQP %.15g" % (f_cb, f_sp))
        if x is not None:
            self.assertEqual(x.shape, (A.shape[0],))
            self.assertGreaterEqual((J @ x - c).min(), -1e-10 * max(1.0, np.abs(c).max()))
            self.assertAlmostEqual(0.5 * x @ A @ x - b @ x, f_cb, delta=1e-10 * max(1.0, abs(f_cb)))
            self.assertLess(np.abs(x - x_sp).max(), 1e-4)
        # the constraints matter: the constrained optimum is strictly above the unconstrained one
        x_unc = np.linalg.solve(A, b)
        self.assertGreater(f_cb, 0.5 * x_unc @ A @ x_unc - b @ x_unc + 1e-6)
        return A, b, J, c, f_cb

    def test_objective_matches_slsqp(self):
        for seed in (1, 2, 3):
            with self.subTest(seed=seed):
                self.check_seed(seed)

    def test_duplicate_row_matches_slsqp(self):
        self.check_seed(4, duplicate=True)

    def test_objective_matches_trust_constr(self):
        A, b, J, c, f_cb = self.check_seed(5)
        f_tc, x_tc, res = scipy_objective(A, b, J, c, "trust-constr")
        self.assertGreaterEqual((J @ x_tc - c).min(), -1e-7)
        self.assertLessEqual(abs(f_cb - f_tc), 1e-7 * max(1.0, abs(f_tc)),
                             "contactbench %.15g vs trust-constr %.15g" % (f_cb, f_tc))


if __name__ == "__main__":
    unittest.main()
