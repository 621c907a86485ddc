"""Tests of plots/stiff.py (issue 17's stiff figure) on hand-written run JSONs.

Run from tests/python with PYTHONPATH=plots and MPLBACKEND=Agg:
    /usr/bin/python3 -m unittest test_stiff
"""
import io
import json
import math
import os
import shutil
import sys
import tempfile
import unittest
from contextlib import redirect_stdout

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(ROOT, "plots"))
os.environ.setdefault("MPLBACKEND", "Agg")

import stiff  # noqa: E402

COLUMNS = ["iteration", "time_s", "a_products", "step", "stationarity", "primal", "dual", "complementarity",
           "gap", "accuracy", "objective", "native_residual", "active_set"]


def run_json(solver, errors, setup_s=0.5):
    """A run whose history has error e at iteration k and time 0.1 (k + 1)."""
    rows = []
    for k, e in enumerate(errors):
        stat = e * 4.0 if solver == "cg" else 1.0  # cg: stationarity relative to its start (4.0)
        rows.append([k, 0.1 * (k + 1), k, "cg", stat, 0, 0, 0, e, e, 0.0, e, 3])
    return {"solver": solver, "status": "converged", "iterations": len(errors) - 1,
            "time": {"setup_s": setup_s, "solve_s": 0.1 * len(errors)},
            "counters": {"expansion_steps": 1, "proportioning_steps": 2, "precond_factorizations": 1},
            "info": {"ichol": {"factor_nonzeros": 10, "a_nonzeros": 16}},
            "history": {"columns": COLUMNS, "rows": rows, "stride": 1}}


class StiffPlotTest(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.mkdtemp(prefix="cb_stiff_")
        os.makedirs(os.path.join(self.tmp, "runs"))
        runs = {"1e+10__mprgp-ichol": run_json("mprgp", [1.0, 1e-3, 1e-9]),
                "1e+10__cg-ichol": run_json("cg", [1.0, 1e-5, 1e-7, 1e-9]),
                "1e+04__mprgp-jacobi": run_json("mprgp", [1.0, 1e-2])}
        for stem, run in runs.items():
            with open(os.path.join(self.tmp, "runs", stem + ".json"), "w") as f:
                json.dump(run, f)

    def tearDown(self):
        shutil.rmtree(self.tmp, ignore_errors=True)

    def test_table_counts_iterations_and_time_to_tol_with_setup(self):
        with redirect_stdout(io.StringIO()):
            self.assertEqual(stiff.main(["plot", "--out", self.tmp]), 0)
        import pandas as pd
        table = pd.read_csv(os.path.join(self.tmp, "stiff.csv"))
        mp = table[(table.youngs == 1e10) & (table.config == "mprgp-ichol")].iloc[0]
        self.assertEqual(mp.first_iteration_at_tol, 2)
        self.assertAlmostEqual(mp.first_time_at_tol_s, 0.5 + 0.3)
        cg = table[(table.youngs == 1e10) & (table.config == "cg-ichol")].iloc[0]
        self.assertEqual(cg.first_iteration_at_tol, 3)  # 4e-9 / 4.0 = 1e-9 <= 1e-8; 4e-7/4 = 1e-7 is not
        soft = table[(table.youngs == 1e4) & (table.config == "mprgp-jacobi")].iloc[0]
        self.assertTrue(math.isnan(soft.first_iteration_at_tol))
        for ext in ("png", "pdf"):
            self.assertGreater(os.path.getsize(os.path.join(self.tmp, f"stiff.{ext}")), 1000)

    def test_empty_folder_is_an_error(self):
        empty = tempfile.mkdtemp(prefix="cb_stiff_empty_")
        try:
            with redirect_stdout(io.StringIO()):
                self.assertEqual(stiff.main(["plot", "--out", empty]), 2)
        finally:
            shutil.rmtree(empty, ignore_errors=True)


if __name__ == "__main__":
    unittest.main()
