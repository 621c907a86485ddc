"""plots.which_solver on constructed ladder records: the fitted growth exponent, the cells of runs
that did not reach tol (shown with their status, never dropped), and bad input."""
import json
import os
import subprocess
import sys
import tempfile
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", ".."))

from plots import which_solver  # noqa: E402


def record(snapshot, label, n, m, status, total_s, peak_mb, message=""):
    return {"snapshot": {"id": snapshot, "n": n, "m": m}, "label": label, "solver": label, "status": status,
            "message": message, "provenance": {"cpu": "AMD EPYC", "cores": 2, "load_average": [m / 10.0, 0, 0]},
            "time": {"setup_s": 0.0, "solve_s": total_s, "total_s": total_s},
            "memory": {"peak_rss_mb": peak_mb}, "settings": {"time_limit_s": 300},
            "accuracy": {"max": 1e-7 if status == "converged" else 1e-2}}


class WhichSolverTest(unittest.TestCase):
    def make_results(self, folder):
        os.makedirs(os.path.join(folder, "runs"))
        runs = []
        for k, n in enumerate((1000, 4000, 16000)):
            snap = "rung%d" % k
            # "quad" takes n^2 / 1e6 s and n / 100 MiB; "lin" 1e-3 n s; "capped" stops at the cap on the last rung
            runs.append(record(snap, "quad", n, 10, "converged", n * n / 1e6, n / 100.0))
            runs.append(record(snap, "lin", n, 10, "converged", 1e-3 * n, 50.0))
            runs.append(record(snap, "capped", n, 10, "converged" if k < 2 else "time_limit",
                               0.5 * n / 1000.0 if k < 2 else 300.2, 80.0))
            runs.append(record(snap, "relaxed", n, 10, "solved_relaxation", 0.01, 40.0))
        for r in runs:
            path = os.path.join(folder, "runs", "%s__%s.json" % (r["snapshot"]["id"], r["label"]))
            with open(path, "w") as f:
                json.dump(r, f)

    def test_exponents_and_cells(self):
        with tempfile.TemporaryDirectory() as tmp:
            folder = os.path.join(tmp, "ladder")
            self.make_results(folder)
            self.assertEqual(which_solver.main([folder, "--axis", "n"]), 0)
            with open(os.path.join(folder, "figures", which_solver.STEM + ".md")) as f:
                text = f.read()
            self.assertTrue(os.path.isfile(os.path.join(folder, "figures", "which_solver.png")))
        self.assertIn("| quad | 2.00 | 3 of 3 |", text)
        self.assertIn("| lin | 1.00 | 3 of 3 |", text)
        self.assertIn("| capped | 1.00 | 2 of 3 |", text)  # the capped run is not a time
        self.assertIn("| relaxed | - | 0 of 3 |", text)
        self.assertIn("time_limit after 300 s / 80 MiB", text)
        self.assertIn("solved_relaxation after 0.01 s / 40 MiB", text)
        self.assertIn("| rung2 | 16000 | 10 | ", text)

    def test_density_ladder_fits_in_m_and_marks_row_caps(self):
        with tempfile.TemporaryDirectory() as tmp:
            folder = os.path.join(tmp, "density")
            os.makedirs(os.path.join(folder, "runs"))
            runs = []
            for k, m in enumerate((10, 100, 1000, 10000)):
                snap = "density_%d" % m
                # "sqrt" takes 0.1 m^0.5 s at fixed n; "dual" 1e-4 m^1.5 s and refuses the last rung at its row cap
                n = 98304 if m == 10000 else 100000  # the last rung's n is smaller: rows still go in m's order
                runs.append(record(snap, "sqrt", n, m, "converged", 0.1 * m ** 0.5, 500.0))
                if k < 3:
                    runs.append(record(snap, "dual", n, m, "converged", 1e-4 * m ** 1.5, 600.0))
                else:
                    runs.append(record(snap, "dual", n, m, "not_applicable", 0.0, 300.0,
                                       "pgs: m = 10000 rows exceeds max_rows = 2000 (S = J A^-1 J' is dense)"))
            for r in runs:
                with open(os.path.join(folder, "runs", "%s__%s.json" % (r["snapshot"]["id"], r["label"])), "w") as f:
                    json.dump(r, f)
            result = subprocess.run([sys.executable, "-m", "plots.which_solver", folder, "--axis", "m"],
                                    capture_output=True, text=True, cwd=os.path.join(HERE, "..", ".."))
            self.assertEqual(result.returncode, 0, result.stderr)
            with open(os.path.join(folder, "figures", which_solver.STEM + ".md")) as f:
                text = f.read()
        self.assertIn("which_solver: sqrt: time ~ m^p, p = 0.50 (4 of 4 runs converged)", result.stdout)
        self.assertIn("which_solver: dual: time ~ m^p, p = 1.50 (3 of 4 runs converged)", result.stdout)
        self.assertIn("time ~ m^p", text)
        self.assertIn("| dual | 1.50 | 3 of 4 |", text)
        self.assertIn("Machine: AMD EPYC, 2 cores; load average (1 min) when the runs started: 1.0 to 1000.0.", text)
        self.assertIn("| density_10000 | 98304 | 10000 | row cap (m > 2000) | 10 s / 500 MiB |", text)
        order = [text.index("| density_%d |" % m) for m in (10, 100, 1000, 10000)]
        self.assertEqual(order, sorted(order))

    def test_growth_exponent_needs_two_sizes(self):
        self.assertIsNone(which_solver.growth_exponent([5, 5], [1, 2]))
        self.assertAlmostEqual(which_solver.growth_exponent([10, 100, 1000], [3, 300, 30000]), 2.0)

    def test_not_a_results_folder_is_exit_2(self):
        with tempfile.TemporaryDirectory() as tmp:
            result = subprocess.run([sys.executable, "-m", "plots.which_solver", tmp], capture_output=True,
                                    text=True, cwd=os.path.join(HERE, "..", ".."))
        self.assertEqual(result.returncode, 2, result.stderr)
        self.assertIn("not a results folder", result.stderr)


if __name__ == "__main__":
    unittest.main()
