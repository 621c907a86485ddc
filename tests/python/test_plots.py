"""Tests of the plot scripts on small results folders written in the INTERFACES.md schema.

Run from tests/python with PYTHONPATH=plots and MPLBACKEND=Agg:
    /usr/bin/python3 -m unittest
"""
import hashlib
import io
import itertools
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
sys.path.insert(0, ROOT)  # plots/ is a package of the repository root
sys.path.insert(0, os.path.join(HERE, "fixtures"))
os.environ.setdefault("MPLBACKEND", "Agg")

import make_fixture as mf  # noqa: E402
from plots import claims, convergence, loader, profiles, report, reproduce, stability  # noqa: E402
from plots.paper_context import PaperContext, round_folders  # noqa: E402

FAKE_CB = os.path.join(HERE, "fixtures", "fake_contactbench.py")


class TempDirCase(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.mkdtemp(prefix="cb_plots_")

    def tearDown(self):
        shutil.rmtree(self.tmp, ignore_errors=True)


class TestLoader(TempDirCase):
    def test_reads_runs_summary_and_histories(self):
        recs = [mf.make_run("s0", "a", iterations=5), mf.make_run("s0", "b", iterations=8, confirmed=False)]
        res = loader.load_results(mf.write_results(self.tmp, recs))
        self.assertEqual(sorted(res.labels()), ["a", "b"])
        self.assertEqual(len(res.runs), 2)
        self.assertEqual(len(res.histories), 6 + 9)
        self.assertEqual(len(res.history("s0", "b")), 9)
        self.assertTrue(res.history("s0", "missing").empty)
        # booleans written as "true"/"false" text in summary.csv come back as bool
        self.assertEqual(res.summary["status_confirmed"].tolist(), [True, False])
        run_b = res.runs[res.runs["label"] == "b"].iloc[0]
        self.assertFalse(run_b["status_confirmed"])
        self.assertEqual(run_b["a_products"], 8)
        self.assertEqual(res.suite["name"], "fixture")

    def test_status_notes_explain_unconfirmed_once_with_the_count(self):
        recs = [mf.make_run("s0", "a", status="unconfirmed", confirmed=False),
                mf.make_run("s1", "a", status="unconfirmed", confirmed=False), mf.make_run("s0", "b")]
        res = loader.load_results(mf.write_results(self.tmp, recs))
        self.assertEqual(loader.status_notes(res.runs), [f"2 run(s) {loader.UNCONFIRMED_MEANING}"])
        self.assertEqual(loader.status_notes(res.runs[res.runs["label"] == "b"]), [])

    def test_not_a_results_folder_names_the_folder(self):
        with self.assertRaisesRegex(FileNotFoundError, "not a results folder"):
            loader.load_results(os.path.join(self.tmp, "nothing"))

    def test_qpsnap_header(self):
        import fake_contactbench as fake
        path = os.path.join(self.tmp, "x.qpsnap")
        fake.write_snapshot(path, 12, 3, {"scene": "t", "frame": 7})
        table = loader.snapshot_table(self.tmp)
        self.assertEqual(table.iloc[0]["n"], 12)
        self.assertEqual(table.iloc[0]["frame"], 7)
        with open(path, "wb") as f:
            f.write(b"\x01\x02")
        with self.assertRaisesRegex(ValueError, "shorter than"):
            loader.read_qpsnap_header(path)


class TestConvergence(TempDirCase):
    def test_three_figures_png_and_pdf(self):
        recs = [mf.make_run(f"s{i}", lab, iterations=it) for i in range(2) for lab, it in (("a", 5), ("b", 9))]
        recs.append(mf.make_run("s2", "a", history=False))  # a run without history is still drawn
        folder = mf.write_results(self.tmp, recs)
        with redirect_stdout(io.StringIO()):
            self.assertEqual(convergence.main([folder]), 0)
        for stem in ("time", "iterations", "a_products"):
            for ext in ("png", "pdf"):
                path = os.path.join(folder, "figures", f"convergence_{stem}.{ext}")
                self.assertTrue(os.path.getsize(path) > 1000, path)

    def test_work_figure_when_runs_record_work(self):  # an n/a run beside it is skipped
        done = mf.make_run("s0", "pgs", iterations=4)
        done["counters"]["work"] = 40.0
        na = mf.make_run("s0", "mprgp-box", status="not_applicable", history=False)
        folder = mf.write_results(self.tmp, [done, na])
        res = loader.load_results(folder)
        paths = convergence.plot_convergence(res, os.path.join(folder, "figures"))
        self.assertIn(os.path.join(folder, "figures", "convergence_work.png"), paths)
        # without a work column in any run there is no work figure
        plain = mf.write_results(os.path.join(self.tmp, "plain"), [mf.make_run("s0", "a")])
        paths = convergence.plot_convergence(loader.load_results(plain), os.path.join(plain, "figures"))
        self.assertFalse(any("convergence_work" in p for p in paths))

    def test_empty_folder_is_an_error(self):
        self.assertEqual(convergence.main.__module__, "plots.convergence")
        os.makedirs(os.path.join(self.tmp, "runs"))
        import contextlib
        with contextlib.redirect_stderr(io.StringIO()) as err:
            self.assertEqual(convergence.main([self.tmp]), 2)
        self.assertIn("no runs", err.getvalue())


class TestProfiles(TempDirCase):
    def hand_made(self):
        # problem p0: a 1 s, b 2 s; p1: a 4 s, b 2 s; p2: a 1 s, b fails (KKT 1e-1)
        recs = [mf.make_run("p0", "a", solve_s=1.0, history=False), mf.make_run("p0", "b", solve_s=2.0, history=False),
                mf.make_run("p1", "a", solve_s=4.0, history=False), mf.make_run("p1", "b", solve_s=2.0, history=False),
                mf.make_run("p2", "a", solve_s=1.0, history=False),
                mf.make_run("p2", "b", solve_s=3.0, final_accuracy=1e-1, status="max_iterations", history=False)]
        return loader.load_results(mf.write_results(self.tmp, recs))

    def test_shifted_geomean_by_hand(self):
        self.assertAlmostEqual(profiles.shifted_geomean([1, 4, 1], 10), (11 * 14 * 11) ** (1 / 3) - 10, places=12)
        self.assertAlmostEqual(profiles.shifted_geomean([2.0, 2.0], 0), 2.0, places=12)
        self.assertTrue(math.isnan(profiles.shifted_geomean([], 10)))
        with self.assertRaises(ValueError):
            profiles.shifted_geomean([-20.0], 10)

    def test_known_ratios_profiles_and_geomean(self):
        res = self.hand_made()
        numbers = profiles.compute(res, shift=10)
        cost = profiles.cost_matrix(numbers["tiers"], 1e-6)
        ratios = profiles.performance_ratios(cost)
        self.assertEqual(ratios.loc["p0"].tolist(), [1.0, 2.0])
        self.assertEqual(ratios.loc["p1"].tolist(), [2.0, 1.0])
        self.assertEqual(ratios.loc["p2", "a"], 1.0)
        self.assertTrue(math.isinf(ratios.loc["p2", "b"]))
        prof = profiles.performance_profile(ratios, [1.0, 2.0])
        self.assertAlmostEqual(prof.loc[1.0, "a"], 2 / 3)
        self.assertAlmostEqual(prof.loc[1.0, "b"], 1 / 3)
        self.assertAlmostEqual(prof.loc[2.0, "a"], 1.0)
        self.assertAlmostEqual(prof.loc[2.0, "b"], 2 / 3)
        # success: b reaches 1e-2 on all three? no: its KKT is 1e-1 on p2
        self.assertAlmostEqual(numbers["success"].loc["b", 1e-6], 2 / 3)
        # the fixture's tol is 1e-6: the 1e-8 tier asks for more than the runs were asked for
        self.assertNotIn(1e-8, numbers["success"].columns)
        self.assertEqual(numbers["dropped_tiers"], [1e-8])
        # shifted geomean: a = (11*14*11)^(1/3) - 10; b's failure counts at the time limit (10 s)
        self.assertEqual(numbers["penalty_s"], 10.0)
        self.assertAlmostEqual(numbers["sgm"].loc["a", 1e-6], (11 * 14 * 11) ** (1 / 3) - 10, places=9)
        self.assertAlmostEqual(numbers["sgm"].loc["b", 1e-6], (12 * 12 * 20) ** (1 / 3) - 10, places=9)
        data = profiles.data_profile(profiles.cost_matrix(numbers["tiers"], 1e-6, "a_products"), [10.0])
        self.assertAlmostEqual(data.loc[10.0, "a"], 1.0)  # 10 A-products each

    def test_not_applicable_runs_leave_the_denominators(self):
        # p0: a 1 s, b 2 s; p1: a 4 s, b n/a (a problem class b does not take); p2: a 1 s, b fails
        na = mf.make_run("p1", "b", solve_s=0.0, final_accuracy=float("nan"), status="not_applicable", history=False)
        recs = [mf.make_run("p0", "a", solve_s=1.0, history=False), mf.make_run("p0", "b", solve_s=2.0, history=False),
                mf.make_run("p1", "a", solve_s=4.0, history=False), na,
                mf.make_run("p2", "a", solve_s=1.0, history=False),
                mf.make_run("p2", "b", solve_s=3.0, final_accuracy=1e-1, status="max_iterations", history=False)]
        res = loader.load_results(mf.write_results(self.tmp, recs))
        numbers = profiles.compute(res, shift=10)
        self.assertAlmostEqual(numbers["success"].loc["b", 1e-6], 0.5)  # 1 of 2 judged runs, not 1 of 3
        self.assertEqual(numbers["success"].loc["b", "n/a"], 1)
        self.assertEqual(numbers["success"].loc["a", "n/a"], 0)
        # b's mean: p0 at 2 s, p2 at the penalty 10 s; p1 left out
        self.assertAlmostEqual(numbers["sgm"].loc["b", 1e-6], math.sqrt(12 * 20) - 10, places=9)
        self.assertAlmostEqual(numbers["sgm"].loc["a", 1e-6], (11 * 14 * 11) ** (1 / 3) - 10, places=9)
        # normalised to the best solver of the tier
        self.assertAlmostEqual(numbers["sgm_ratio"].loc["a", 1e-6], 1.0)
        self.assertAlmostEqual(numbers["sgm_ratio"].loc["b", 1e-6],
                               (math.sqrt(12 * 20) - 10) / ((11 * 14 * 11) ** (1 / 3) - 10), places=9)
        tt = numbers["tiers"]
        ratios = profiles.performance_ratios(profiles.cost_matrix(tt, 1e-6))
        prof = profiles.performance_profile(ratios, [1.0, 2.0], profiles.excluded_matrix(tt, 1e-6))
        self.assertAlmostEqual(prof.loc[1.0, "a"], 1.0)  # best on p0 and p2, alone on p1
        self.assertAlmostEqual(prof.loc[1.0, "b"], 0.0)
        self.assertAlmostEqual(prof.loc[2.0, "b"], 0.5)  # p0 at ratio 2 of its 2 judged problems
        data = profiles.data_profile(profiles.cost_matrix(tt, 1e-6, "a_products"), [10.0],
                                     profiles.excluded_matrix(tt, 1e-6))
        self.assertAlmostEqual(data.loc[10.0, "b"], 0.5)

    def test_shift_scaled_to_the_data_is_printed(self):
        # times to the 1e-2 .. 1e-6 tiers reached: a 1, 4, 1 s and b 2, 2 s at each of three tiers:
        # median 2 s, shift 0.2 s
        recs = [mf.make_run("p0", "a", solve_s=1.0, history=False), mf.make_run("p0", "b", solve_s=2.0, history=False),
                mf.make_run("p1", "a", solve_s=4.0, history=False), mf.make_run("p1", "b", solve_s=2.0, history=False),
                mf.make_run("p2", "a", solve_s=1.0, history=False)]
        folder = mf.write_results(self.tmp, recs)
        self.assertAlmostEqual(profiles.data_shift([1, 4, 1, 2, 2]), 0.2)
        self.assertEqual(profiles.data_shift([]), 1e-6)
        numbers = profiles.compute(loader.load_results(folder))
        self.assertAlmostEqual(numbers["shift_s"], 0.2)
        with redirect_stdout(io.StringIO()) as out:
            self.assertEqual(profiles.main([folder]), 0)
        self.assertIn("shift of the geometric mean = 0.2 s (0.1 x the median time-to-tier reached)", out.getvalue())
        with open(os.path.join(folder, "profiles.md"), encoding="utf-8") as f:
            md = f.read()
        self.assertIn("shift = 0.2 s = 0.1 x the median time-to-tier reached", md)
        self.assertIn("Tiers tighter than the runs' tol (1.00e-06) are left out: 1e-08.", md)

    def test_time_to_tier_counts_setup(self):
        # the history is solve-only (8 iterations over 8 s); setup took 0.5 s
        rec = mf.make_run("p", "a", iterations=8, solve_s=8.0, setup_s=0.5, final_accuracy=10 ** -8.5)
        res = loader.load_results(mf.write_results(self.tmp, [rec]))
        with_setup = profiles.tier_table(res, [1e-2])
        self.assertAlmostEqual(with_setup.iloc[0]["time_s"], 2.5, places=9)
        solve_only = profiles.tier_table(res, [1e-2], include_setup=False)
        self.assertAlmostEqual(solve_only.iloc[0]["time_s"], 2.0, places=9)
        # the last row never passes the run's total time
        h = res.history("p", "a")
        t = loader.history_time(h, res.runs.iloc[0])
        self.assertAlmostEqual(t[0], 0.5)
        self.assertAlmostEqual(t[-1], 8.5)

    def test_data_profile_budgets_in_work_units(self):
        # a factorising solver: 2 A-products but 40 work units; the data profile reads work
        fact = mf.make_run("p0", "f", iterations=2, history=False)
        fact["counters"]["work"] = 40.0
        cheap = mf.make_run("p0", "c", iterations=10, history=False)
        cheap["counters"]["work"] = 10.0
        res = loader.load_results(mf.write_results(self.tmp, [fact, cheap]))
        numbers = profiles.compute(res, shift=1)
        self.assertEqual(numbers["work_column"], "work")
        work = profiles.cost_matrix(numbers["tiers"], 1e-6, "work")
        self.assertEqual(work.loc["p0", "f"], 40.0)
        data = profiles.data_profile(work, [10.0, 40.0])
        self.assertEqual(data.loc[10.0, "f"], 0.0)
        self.assertEqual(data.loc[10.0, "c"], 1.0)
        self.assertEqual(data.loc[40.0, "f"], 1.0)

    def test_time_to_tier_from_history(self):
        # KKT decays by 10^-1.0625 per iteration over 8 iterations spread on 8 s: below 1e-2 first at
        # iteration 2 (t = 2 s), below 1e-8 first at iteration 8
        rec = mf.make_run("p", "a", iterations=8, solve_s=8.0, final_accuracy=10 ** -8.5)
        res = loader.load_results(mf.write_results(self.tmp, [rec]))
        tt = profiles.tier_table(res)
        row = tt[tt["tier"] == 1e-2].iloc[0]
        self.assertAlmostEqual(row["time_s"], 2.0, places=9)
        self.assertEqual(row["a_products"], 2)
        self.assertAlmostEqual(tt[tt["tier"] == 1e-8].iloc[0]["time_s"], 8.0, places=9)

    def test_solved_relaxation_is_judged_on_the_original_qp(self):
        # b met tol only on a problem it changed (decoupled rows) on p1; its error e on the original
        # QP is 1e-3: it reaches the 1e-2 tier but fails 1e-4 and 1e-6, and both solvers are judged on
        # the same two problems (issue 24: no solver ranked on a subset of its own choosing).
        relax = mf.make_run("p1", "b", solve_s=2.0, final_accuracy=1e-3, history=False)
        relax["status"], relax["solver_status"] = "solved_relaxation", "converged"
        recs = [mf.make_run("p0", "a", solve_s=1.0, history=False), mf.make_run("p0", "b", solve_s=2.0, history=False),
                mf.make_run("p1", "a", solve_s=4.0, history=False), relax]
        res = loader.load_results(mf.write_results(self.tmp, recs))
        numbers = profiles.compute(res, shift=10)
        self.assertAlmostEqual(numbers["success"].loc["b", 1e-6], 0.5)  # 1 of 2 judged problems
        self.assertAlmostEqual(numbers["success"].loc["b", 1e-2], 1.0)  # e = 1e-3 <= 1e-2 on the original QP
        self.assertEqual(numbers["success"].loc["b", "judged"], 2)
        self.assertEqual(numbers["success"].loc["a", "judged"], 2)
        self.assertEqual(numbers["success"].loc["b", "solved_relaxation"], 1)
        self.assertEqual(numbers["success"].loc["a", "solved_relaxation"], 0)
        # b at 1e-6: 2 s on p0, the penalty time on p1; sgm with shift 10
        penalty = numbers["penalty_s"]
        self.assertAlmostEqual(numbers["sgm"].loc["b", 1e-6], math.sqrt(12 * (penalty + 10)) - 10, places=9)
        tt = numbers["tiers"]
        ratios = profiles.performance_ratios(profiles.cost_matrix(tt, 1e-6))
        prof = profiles.performance_profile(ratios, [1.0], profiles.excluded_matrix(tt, 1e-6))
        self.assertAlmostEqual(prof.loc[1.0, "b"], 0.0)  # p0: 2 s vs a's 1 s; p1 not reached
        self.assertAlmostEqual(prof.loc[1.0, "a"], 1.0)  # best on both
        prof2 = profiles.performance_profile(profiles.performance_ratios(profiles.cost_matrix(tt, 1e-2)), [1.0],
                                             profiles.excluded_matrix(tt, 1e-2))
        self.assertAlmostEqual(prof2.loc[1.0, "b"], 0.5)  # p1: b's 2 s beats a's 4 s at e <= 1e-2
        hon = profiles.status_honesty(res.runs).set_index("label")
        self.assertEqual(hon.loc["b", "converged"], 2)
        self.assertEqual(hon.loc["b", "confirmed"], 1)
        self.assertEqual(hon.loc["b", "relaxation"], 1)

    def test_status_honesty_and_markdown(self):
        recs = [mf.make_run("p0", "a"), mf.make_run("p1", "a"),
                mf.make_run("p2", "a", confirmed=False, final_accuracy=3e-6),
                mf.make_run("p0", "b", status="max_iterations", final_accuracy=1e-3)]
        folder = mf.write_results(self.tmp, recs)
        res = loader.load_results(folder)
        hon = profiles.status_honesty(res.runs).set_index("label")
        self.assertEqual(hon.loc["a", "converged"], 3)
        self.assertEqual(hon.loc["a", "confirmed"], 2)
        self.assertAlmostEqual(hon.loc["a", "share"], 2 / 3)
        self.assertTrue(math.isnan(hon.loc["b", "share"]))  # never claimed convergence
        with redirect_stdout(io.StringIO()) as out:
            self.assertEqual(profiles.main([folder, "--shift", "1"]), 0)
        self.assertIn("shift of the geometric mean = 1 s", out.getvalue())
        with open(os.path.join(folder, "profiles.md"), encoding="utf-8") as f:
            md = f.read()
        self.assertIn("shift = 1 s", md)
        self.assertIn("| a | 3 | 3 | 2 | 0 | 67% |", md)
        self.assertIn("p2 / a: error 3.00e-06", md)
        for stem in ("profiles_performance", "profiles_data"):
            self.assertTrue(os.path.isfile(os.path.join(folder, "figures", stem + ".pdf")))

    def test_two_runs_of_one_solver_under_one_label_stay_apart(self):
        # the stress table writes label "cg" for both cg and cg:precond=ichol; the file names differ
        folder = mf.write_results(self.tmp, [mf.make_run("p0", "cg", solve_s=1.0, history=False)])
        ichol = mf.make_run("p0", "cg", solve_s=3.0, history=False)
        with open(os.path.join(folder, "runs", "p0__cg:precond=ichol.json"), "w", encoding="utf-8") as f:
            json.dump(ichol, f)
        os.remove(os.path.join(folder, "summary.csv"))
        res = loader.load_results(folder)
        self.assertEqual(sorted(res.runs["label"]), ["cg", "cg:precond=ichol"])
        numbers = profiles.compute(res, shift=1)
        self.assertEqual(list(numbers["success"]["judged"]), [1, 1])

    def test_solvers_with_uncounted_work_leave_the_data_profiles(self):
        recs = [mf.make_run("p0", "a", solver="mprgp"), mf.make_run("p0", "ip", solver="ipopt")]
        folder = mf.write_results(self.tmp, recs)
        with redirect_stdout(io.StringIO()):
            self.assertEqual(profiles.main([folder]), 0)
        with open(os.path.join(folder, "profiles.md"), encoding="utf-8") as f:
            md = f.read()
        self.assertIn("Left out of the data profiles (work not counted in full): `ip`: Ipopt's MUMPS "
                      "factorisations and solves are not counted.", md)
        self.assertIn("| ip | 100% |", md)  # still in the success table and the time profiles


def _lab(hex_colour):
    """CIELAB (D65) of an sRGB colour, for colour distances."""
    lin = [c / 12.92 if c <= 0.04045 else ((c + 0.055) / 1.055) ** 2.4
           for c in (int(hex_colour[i:i + 2], 16) / 255 for i in (1, 3, 5))]
    x = (0.4124 * lin[0] + 0.3576 * lin[1] + 0.1805 * lin[2]) / 0.95047
    y = 0.2126 * lin[0] + 0.7152 * lin[1] + 0.0722 * lin[2]
    z = (0.0193 * lin[0] + 0.1192 * lin[1] + 0.9505 * lin[2]) / 1.08883
    f = lambda v: v ** (1 / 3) if v > 0.008856 else 7.787 * v + 16 / 116  # noqa: E731
    return (116 * f(y) - 16, 500 * (f(x) - f(y)), 200 * (f(y) - f(z)))


class TestFigureRules(unittest.TestCase):
    def test_one_colour_and_marker_per_solver(self):
        from plots import figutil
        self.assertEqual(figutil.solver_style("pgs"), {"color": "#CC79A7", "marker": "D", "linestyle": "-"})
        colours = [figutil.SOLVER_STYLES[s][0] for s in figutil.SOLVER_STYLES]
        markers = [figutil.SOLVER_STYLES[s][1] for s in figutil.SOLVER_STYLES]
        self.assertEqual(len(set(colours)), len(colours))
        self.assertEqual(len(set(markers)), len(markers))
        self.assertNotIn("x", markers)  # the not-converged mark
        # colours apart: CIELAB distance >= 15 between any two fixed styles (bullet-dantzig's old
        # hashed colour was within 10 of mprgp's blue)
        for (a, ca), (b, cb) in itertools.combinations([(s, figutil.SOLVER_STYLES[s][0]) for s in figutil.SOLVER_STYLES], 2):
            self.assertGreater(math.dist(_lab(ca), _lab(cb)), 15.0, (a, b))
        # a label of a known solver keeps the solver's colour, with a marker and line style of its own
        # (issue 46: every label a distinct (colour, marker) pair)
        variant = figutil.solver_style("mprgp-ichol", "mprgp")
        self.assertEqual(variant["color"], figutil.SOLVER_STYLES["mprgp"][0])
        self.assertNotIn(variant["marker"], markers)
        self.assertNotEqual(variant["linestyle"], "-")
        # a new solver: the same style every time, with a marker no registered solver has
        for name in ("my-solver", "another-qp", "x"):
            style = figutil.solver_style(name)
            self.assertEqual(style, figutil.solver_style(name))
            self.assertNotIn(style["marker"], markers)

    def test_every_registered_solver_has_a_fixed_style(self):
        cb = os.environ.get("CB_CONTACTBENCH")
        if not cb or not os.path.isfile(cb):
            self.skipTest("CB_CONTACTBENCH (the contactbench binary) not set: ctest sets it")
        import subprocess
        from plots import figutil
        listed = json.loads(subprocess.run([cb, "solvers", "--json"], capture_output=True, text=True, check=True).stdout)
        # `command` runs whatever program a suite names: each of its labels is a different solver
        # and takes a spare style of its own (solver_style's rule for a new solver), not one fixed colour.
        missing = [s["name"] for s in listed
                   if s["name"] not in figutil.SOLVER_STYLES and not s.get("needs_settings", False)]
        self.assertEqual(missing, [], "add a fixed style to plots/figutil.py SOLVER_STYLES")

    def test_titles_and_relaxation_labels(self):
        import pandas as pd
        from plots import figutil
        self.assertEqual(figutil.panel_title("plane-s1", 375.0, 50), "plane-s1 (n = 375, m = 50)")
        self.assertEqual(figutil.panel_title("plane-s1", float("nan"), None), "plane-s1")
        runs = pd.DataFrame({"label": ["cg", "mprgp", "pgs"], "solved_problem": ["unconstrained", "decoupled", None]})
        self.assertEqual(figutil.display_label("cg", runs), "cg (J ignored: relaxation)")
        self.assertEqual(figutil.display_label("mprgp", runs), "mprgp (decoupled rows)")
        self.assertEqual(figutil.display_label("pgs", runs), "pgs")


class TestStability(TempDirCase):
    def test_heat_map_and_marks(self):
        path = os.path.join(self.tmp, "stability.csv")
        with open(path, "w") as f:
            # the header harness/stress.cpp writes
            f.write("solver,case,severity,status,accuracy,tol,violation,nonfinite,monotone,time_s,iterations,"
                    "status_confirmed,message,family,n,m,criterion,m_solved\n"
                    "mprgp,stiff,2,converged,1e-7,1e-6,0,false,true,0.1,10,true,,plane,30,4,kkt,4\n"
                    "ica,stiff,2,converged,1e-3,1e-6,0,false,false,0.1,10,false,\"x, y\",plane,30,4,native,4\n"
                    "mprgp,mm-units,3,diverged,nan,1e-6,0,true,false,0.1,10,false,,plane,30,4,,4\n")
        with redirect_stdout(io.StringIO()):
            self.assertEqual(stability.main([self.tmp]), 0)
        self.assertTrue(os.path.isfile(os.path.join(self.tmp, "figures", "stability.png")))
        df = stability.read_table(self.tmp)
        cols = {r: stability.find_column(df, r) for r in stability.CANDIDATES}
        self.assertEqual(stability.cell_marks(df.iloc[1], cols), "!~")
        self.assertEqual(stability.cell_marks(df.iloc[2], cols), "N~")
        self.assertEqual(stability.cell_marks(df.iloc[0], cols), "")
        self.assertEqual(cols["error"], "accuracy")

    def test_stiff_family_figure_from_kept_histories(self):
        # Two stiff cases (family "stiff-slab") and one other; runs/ holds the stiff runs' records.
        with open(os.path.join(self.tmp, "stability.csv"), "w") as f:
            f.write("solver,case,severity,status,accuracy,tol,violation,nonfinite,monotone,time_s,iterations,"
                    "status_confirmed,message,family,n,m,criterion,m_solved\n"
                    "mprgp,slab-stiff-1e12,3,converged,1e-9,1e-8,0,false,true,0.3,2,true,,stiff-slab,9,2,kkt,2\n"
                    "mprgp:precond=ichol,slab-stiff-1e4,1,converged,1e-9,1e-8,0,false,true,0.3,2,true,,stiff-slab,"
                    "9,2,kkt,2\n"
                    "mprgp,baseline-plane,0,converged,1e-9,1e-8,0,false,true,0.3,2,true,,baseline,9,2,kkt,2\n")
        os.makedirs(os.path.join(self.tmp, "runs"))
        cols = ["iteration", "time_s", "a_products", "step", "stationarity", "primal", "dual", "complementarity",
                "gap", "accuracy", "objective", "native_residual", "active_set"]
        for case, label in (("slab-stiff-1e12", "mprgp"), ("slab-stiff-1e4", "mprgp:precond=ichol"),
                            ("baseline-plane", "mprgp")):
            rows = [[k, 0.1 * (k + 1), k, "cg", 0, 0, 0, 0, 0, 10.0 ** -(3 * k), 0, 0, 1] for k in range(3)]
            with open(os.path.join(self.tmp, "runs", f"{case}__{label}.json"), "w") as f:
                json.dump({"time": {"setup_s": 0.5}, "history": {"columns": cols, "rows": rows}}, f)
        df = stability.read_table(self.tmp)
        hist = stability.stiff_histories(self.tmp, df)
        self.assertEqual(sorted(hist), ["slab-stiff-1e12", "slab-stiff-1e4"])  # not the baseline case
        curve = hist["slab-stiff-1e4"]["mprgp:precond=ichol"]
        self.assertEqual(list(curve["time_s"].round(6)), [0.6, 0.7, 0.8])  # setup added
        self.assertEqual(list(curve["error"]), [1.0, 1e-3, 1e-6])
        self.assertEqual(stability._case_key("slab-stiff-1e4") < stability._case_key("slab-stiff-1e12"), True)
        with redirect_stdout(io.StringIO()):
            self.assertEqual(stability.main([self.tmp]), 0)
        self.assertTrue(os.path.isfile(os.path.join(self.tmp, "figures", "stiff_family.png")))

    def test_missing_columns_named(self):
        import pandas as pd
        with self.assertRaisesRegex(ValueError, "case, error"):
            stability.plot_stability(pd.DataFrame({"solver": ["a"]}), self.tmp)


class TestVerdicts(unittest.TestCase):
    def test_published_fair(self):
        v = claims.verdict_published_fair
        self.assertEqual(v(True, True), claims.HOLDS)
        self.assertEqual(v(True, False), claims.HOLDS_AS_PUBLISHED)
        self.assertEqual(v(False, False), claims.DOES_NOT_HOLD)
        self.assertEqual(v(None, None), claims.NOT_MEASURED)
        self.assertEqual(v(True, None), claims.HOLDS_AS_PUBLISHED)
        self.assertEqual(claims.verdict_threshold(float("nan"), 1.0), claims.NOT_MEASURED)
        self.assertEqual(claims.verdict_threshold(0.5, 1.0, greater=False), claims.HOLDS)

    def test_first_reach_and_settle_time(self):
        from plots import figutil
        import pandas as pd
        # ICA-like: 0 at the start, up, then down for good at t = 3
        h = pd.DataFrame({"time_s": [0.0, 1.0, 2.0, 3.0, 4.0], "r": [0.0, 1.0, 0.5, 0.01, 0.001]})
        self.assertEqual(figutil.first_reach(h, "r", 0.01), 0.0)
        self.assertEqual(figutil.settle_time(h, "r", 0.01), 3.0)
        self.assertTrue(math.isnan(figutil.settle_time(h, "r", 1e-4)))
        self.assertEqual(figutil.settle_time(h, "r", 2.0), 0.0)

    def test_fig8_relative_error(self):
        from plots import fig8
        import pandas as pd
        err = fig8.relative_error(pd.Series([0.0, -0.9, -0.99, -1.0]), -1.0)
        self.assertEqual(err.tolist()[0], 1.0)
        self.assertAlmostEqual(err[2], 0.01)
        self.assertEqual(fig8.iterations_to(err, [0, 1, 2, 3], 0.05), 2)


class TestReport(TempDirCase):
    def test_missing_inputs_are_reported_not_faked(self):
        ctx = PaperContext(out=self.tmp, data=None)
        ctx.reasons["fig10"] = "no scene file scenes/longcube.json"
        outcomes = report.produce_all(ctx, log=lambda *_: None)
        self.assertTrue(all(o.missing for o in outcomes))
        path = report.write_report(ctx, outcomes, {})
        with open(path, encoding="utf-8") as f:
            text = f.read()
        self.assertIn("not produced: no scene file scenes/longcube.json", text)
        rows = [l for l in text.splitlines() if l.startswith("| ") and "**" in l]
        self.assertEqual(len(rows), len(report.EXPECTED_CLAIMS))
        self.assertTrue(all("**not measured**" in r for r in rows))
        self.assertFalse(os.path.isdir(os.path.join(self.tmp, "figures")) and
                         any(f.endswith(".png") for f in os.listdir(os.path.join(self.tmp, "figures"))))


class TestReproduce(TempDirCase):
    """reproduce.py end to end with a stand-in contactbench (tests/python/fixtures/fake_contactbench.py)."""

    def setUp(self):
        super().setUp()
        self.scenes = os.path.join(self.tmp, "scenes")
        os.makedirs(self.scenes)
        for name in ("two_dinos_1303", "two_dinos_1493", "longcube"):
            with open(os.path.join(self.scenes, name + ".json"), "w") as f:
                f.write("{}")

    def test_missing_binary_reports_reason(self):
        out = os.path.join(self.tmp, "out")
        with redirect_stdout(io.StringIO()):
            reproduce.main(["--contactbench", os.path.join(self.tmp, "nope"), "--out", out, "--scenes", self.scenes])
        with open(os.path.join(out, "report.md"), encoding="utf-8") as f:
            text = f.read()
        self.assertIn("not produced: contactbench binary not found", text)

    def test_simulations_and_runs_are_cached(self):
        out = os.path.join(self.tmp, "out")
        ctx = PaperContext(out=out, quick=True)
        runner = reproduce.Runner(FAKE_CB, None, os.path.join(self.tmp, "log"))
        scene = os.path.join(self.scenes, "two_dinos_1303.json")
        with redirect_stdout(io.StringIO()):
            sim = reproduce.simulate(runner, ctx, "two_dinos_1303", scene, 12, None, False)
            self.assertIsNotNone(sim)
            reproduce.simulate(runner, ctx, "two_dinos_1303", scene, 12, None, False)
            snaps = reproduce.snapshots_of(ctx, "two_dinos_1303")
            self.assertEqual(reproduce.pick_frame(snaps, 11), [snaps.iloc[11]["path"]])
            tpl = os.path.join(ROOT, "suites", "paper", "fig11.json")
            reproduce.run_suite(runner, ctx, "fig11", tpl, reproduce.pick_frame(snaps, 11), False)
            reproduce.run_suite(runner, ctx, "fig11", tpl, reproduce.pick_frame(snaps, 11), False)
        self.assertEqual(runner.steps[1], "simulate two_dinos_1303: cached (12 frames)")
        rounds = reproduce.TIMED_SUITES["fig11"]
        self.assertEqual(rounds, 8)
        self.assertTrue(runner.steps[2].startswith("run fig11: exit 0"))
        for k in range(2, rounds + 1):  # a timed suite runs in rounds, each cached like the first
            self.assertTrue(runner.steps[1 + k].startswith(f"run fig11 round {k}/{rounds}: exit 0"), runner.steps)
            self.assertEqual(runner.steps[2 + rounds + k - 1], f"run fig11 round {k}/{rounds}: cached")
        self.assertEqual(runner.steps[2 + rounds], "run fig11: cached")
        self.assertEqual(ctx.rounds["fig11"][0], os.path.join(out, "runs", "fig11"))
        self.assertEqual(ctx.rounds["fig11"][1:], [os.path.join(out, "rounds", "fig11", str(k)) for k in range(2, 9)])
        with open(os.path.join(out, "suites", "fig11.json"), encoding="utf-8") as f:
            suite = json.load(f)
        with open(os.path.join(out, "suites", "fig11.round2.json"), encoding="utf-8") as f:
            second = json.load(f)
        self.assertEqual(second["solvers"], suite["solvers"][::-1])  # the order alternates between rounds
        self.assertEqual(suite["time_limit_s"], reproduce.QUICK_TIME_LIMIT_S)
        self.assertTrue(os.path.isabs(suite["snapshots"][0]))

    def test_simulation_cache_is_keyed_on_every_input(self):
        """The stand-in meshes of `make demo` are not reused by `make reproduce` with other inputs:
        a changed mesh file, data source or simulator version simulates again (issue 15)."""
        out = os.path.join(self.tmp, "out")
        ctx = PaperContext(out=out, quick=True)
        scene = os.path.join(self.scenes, "two_dinos_1303.json")
        mesh = os.path.join(self.tmp, "dino.off")
        with open(mesh, "w") as f:
            f.write("OFF stand-in\n")
        data = os.path.join(self.tmp, "paper-data")
        os.makedirs(data)
        old_env = dict(os.environ)
        os.environ["FAKE_CB_MESH"] = mesh
        try:
            with redirect_stdout(io.StringIO()):
                runner = reproduce.Runner(FAKE_CB, None, os.path.join(self.tmp, "log"))
                sim = lambda d=None: reproduce.simulate(runner, ctx, "two_dinos_1303", scene, 12, d, False)  # noqa: E731
                sim()
                sim()                                   # cached
                with open(mesh, "a") as f:
                    f.write("another mesh\n")
                sim()                                   # mesh file changed
                sim(data)                               # data source changed
                sim(data)                               # cached
                os.environ["FAKE_CB_SIMULATOR_VERSION"] = "2"
                runner2 = reproduce.Runner(FAKE_CB, None, os.path.join(self.tmp, "log2"))
                reproduce.simulate(runner2, ctx, "two_dinos_1303", scene, 12, data, False)  # new simulator
        finally:
            os.environ.clear()
            os.environ.update(old_env)
        kinds = [s.split(":")[1].strip().split(" ")[0] for s in runner.steps]
        self.assertEqual(kinds, ["exit", "cached", "exit", "exit", "cached"])
        self.assertTrue(runner2.steps[0].startswith("simulate two_dinos_1303: exit 0"))

    def test_suite_cache_is_keyed_on_the_binary(self):
        """A rebuilt contactbench resumes the suite (the harness redoes runs whose identity changed)."""
        out = os.path.join(self.tmp, "out")
        ctx = PaperContext(out=out, quick=True)
        cb = os.path.join(self.tmp, "contactbench")
        with open(cb, "w") as f:  # a binary of its own, so that it can be "rebuilt"
            f.write(f'#!/bin/sh\nexec /usr/bin/python3 "{FAKE_CB}" "$@"\n')
        os.chmod(cb, 0o755)
        with redirect_stdout(io.StringIO()):
            runner = reproduce.Runner(cb, None, os.path.join(self.tmp, "log"))
            scene = os.path.join(self.scenes, "two_dinos_1303.json")
            reproduce.simulate(runner, ctx, "two_dinos_1303", scene, 12, None, False)
            snaps = reproduce.pick_frame(reproduce.snapshots_of(ctx, "two_dinos_1303"), 11)
            tpl = os.path.join(ROOT, "suites", "paper", "fig11.json")
            reproduce.run_suite(runner, ctx, "fig11", tpl, snaps, False)
            reproduce.run_suite(runner, ctx, "fig11", tpl, snaps, False)
            with open(cb, "a") as f:
                f.write("# rebuilt\n")
            reproduce.run_suite(runner, ctx, "fig11", tpl, snaps, False)
        rounds = reproduce.TIMED_SUITES["fig11"]
        self.assertEqual(runner.steps[1 + rounds], "run fig11: cached")
        self.assertTrue(runner.steps[1 + 2 * rounds].startswith("run fig11: exit 0"), runner.steps)
        self.assertTrue(runner.steps[2 + 2 * rounds].startswith(f"run fig11 round 2/{rounds}: exit 0"), runner.steps)


class TestQuickReproduction(unittest.TestCase):
    """README's `make demo` step (reproduce --quick, no authors' data, the stand-in contactbench) run
    once for the class: its output is checked as written (a copy), and README's sequence goes on from
    it (a quick reproduction draws every figure: ~10 s of CPU each time)."""

    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.mkdtemp(prefix="cb_plots_quick_")
        cls.scenes = os.path.join(cls.tmp, "scenes")
        os.makedirs(cls.scenes)
        for name in ("two_dinos_1303", "two_dinos_1493", "longcube"):
            with open(os.path.join(cls.scenes, name + ".json"), "w") as f:
                f.write("{}")
        cls.out = os.path.join(cls.tmp, "out")
        cls.args = ["--contactbench", FAKE_CB, "--out", cls.out, "--scenes", cls.scenes, "--quick", "--no-profiles"]
        with redirect_stdout(io.StringIO()) as log:  # make demo: no authors' data
            cls.demo_status = reproduce.main(cls.args + ["--data", os.path.join(cls.tmp, "absent")])
        cls.demo_log = log.getvalue()
        cls.demo_copy = os.path.join(cls.tmp, "demo-copy")
        shutil.copytree(cls.out, cls.demo_copy, symlinks=True)
        with open(os.path.join(cls.out, "reproduce.json"), encoding="utf-8") as f:
            cls.demo_meta = json.load(f)

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.tmp, ignore_errors=True)

    def test_quick_run_produces_every_figure_and_claim(self):
        self.assertEqual(self.demo_status, 0)
        out = self.demo_copy  # the demo's output as it was written
        figs = os.path.join(out, "figures")
        for stem in ("fig6_decoupling_time", "fig8_mprgp_vs_cg", "fig9_preconditioning", "fig10_mprgp_vs_ica",
                     "fig11_scaling"):
            for ext in ("png", "pdf"):
                self.assertTrue(os.path.getsize(os.path.join(figs, f"{stem}.{ext}")) > 1000, stem)
        self.assertTrue(os.path.isfile(os.path.join(figs, "table1.csv")))
        with open(os.path.join(out, "report.md"), encoding="utf-8") as f:
            text = f.read()
        rows = [l for l in text.splitlines() if l.startswith("| ") and "**" in l]
        self.assertEqual(len(rows), len(report.EXPECTED_CLAIMS))
        allowed = {claims.HOLDS, claims.HOLDS_AS_PUBLISHED, claims.HOLDS_NATIVE_ONLY, claims.DOES_NOT_HOLD,
                   claims.NOT_MEASURED, claims.INCONCLUSIVE_QUICK}
        for r in rows:
            verdict = r.rsplit("**", 2)[1]
            self.assertIn(verdict, allowed)
            if verdict == claims.INCONCLUSIVE_QUICK:  # with the reason a full run could reverse it
                self.assertIn("** (quick mode: ", r)
        # the quick resolutions (7818 and 8958 DOF) are too close for the growth claim
        self.assertIn("**inconclusive (quick)** (quick mode: the resolutions judged are 1.15x apart", text)
        with open(os.path.join(out, "claims.json"), encoding="utf-8") as f:
            saved = json.load(f)
        self.assertEqual([c["key"] for c in saved][:len(report.EXPECTED_CLAIMS)],
                         [k for k, _, _ in report.EXPECTED_CLAIMS])
        # the fake's ICA is ~17x slower than its MPRGP at the smallest size: computed, not typed in
        low_res = next(c for c in saved if c["key"] == "fig11-ica-low-res")
        self.assertEqual(low_res["verdict"], claims.DOES_NOT_HOLD)
        # every row says the problem it is judged on; timed rows carry the rounds' interval
        for c in saved:
            self.assertTrue(c["judged_on"], c["key"])
            self.assertIn(c["verdict"], claims.VERDICTS)
        for key in ("fig6-decoupling", "fig10-ica-10x", "fig11-ica-low-res"):
            c = next(c for c in saved if c["key"] == key)
            self.assertEqual(c["samples"], reproduce.TIMED_SUITES[key.split("-")[0]], key)
            self.assertLessEqual(c["interval"][0], c["estimate"])
            self.assertLessEqual(c["estimate"], c["interval"][1])
        # the fake's long cube has contact from frame 3: Table 1 judges only those frames
        dominates = next(c for c in saved if c["key"] == "table1-cg-dominates")
        self.assertIn("frames with contact rows", dominates["judged_on"])
        self.assertEqual(len(os.listdir(os.path.join(out, "rounds", "fig6"))), reproduce.TIMED_SUITES["fig6"] - 1)
        self.assertIn("not simulated: dragon_stair", text)
        # the fake's ica-published runs (stop=native) are `unconfirmed`: the report says what that means
        self.assertIn(loader.UNCONFIRMED_MEANING, text)
        self.assertNotIn("KKT", text)  # the measure is the accuracy error e (docs/accuracy.md)
        self.assertIn("quick", self.demo_log)
        # issue 46: the reproduction's HTML page, its path said at the end
        self.assertTrue(os.path.isfile(os.path.join(out, "report", "index.html")))
        self.assertIn(f"report: {os.path.join(self.out, 'report', 'index.html')}", self.demo_log)

    def test_readme_sequence_judges_no_run_on_the_stand_in_meshes(self):
        """README's sequence (issue 43): `make demo` (reproduce --quick without the authors' data: stand-in
        meshes), then `make paper-data`, then `make reproduce QUICK=1`. The scenes are simulated again into
        the same paths with other content, so no suite's cached results may be reused: every judged run's
        snapshot hash is that of the authors'-data snapshot now at its path, and the report names them."""
        self.assertEqual(self.demo_status, 0)  # make demo (setUpClass)
        out, demo, args = self.out, self.demo_meta, self.args
        data = os.path.join(self.tmp, "paper-data")
        os.makedirs(os.path.join(data, "figures"))
        with redirect_stdout(io.StringIO()):
            self.assertEqual(reproduce.main(args + ["--data", data]), 0)  # after make paper-data
        with open(os.path.join(out, "reproduce.json"), encoding="utf-8") as f:
            meta = json.load(f)
        self.assertFalse([s for s in meta["steps"] if s.startswith("run ") and s.endswith(": cached")], meta["steps"])
        judged = 0
        for suite, snaps in meta["judged"].items():
            self.assertNotEqual(snaps, demo["judged"][suite], suite)  # same paths, other content
            for path, key in snaps.items():
                self.assertEqual(key["source"], f"authors' data {data}", path)
                self.assertEqual(key["sha256"], reproduce.file_sha(path), path)
            folders = [os.path.join(out, "runs", suite)] + round_folders(out, suite)
            for folder in folders:
                for run in os.listdir(os.path.join(folder, "runs")):
                    with open(os.path.join(folder, "runs", run), encoding="utf-8") as f:
                        snap = json.load(f)["snapshot"]
                    with open(snap["path"], "rb") as f:  # the record's hash is that of the file judged now
                        self.assertEqual(snap["hash"], hashlib.sha256(f.read()).hexdigest()[:16], run)
                    self.assertEqual(snap["meta"]["data"], data, run)
                    judged += 1
        self.assertGreater(judged, 50)
        with open(os.path.join(out, "report.md"), encoding="utf-8") as f:
            text = f.read()
        self.assertIn("## Snapshots judged", text)
        table = text.split("## Snapshots judged")[1].split("##")[0]
        self.assertNotIn("stand-in meshes", table)
        first = next(iter(meta["judged"]["fig11"].items()))
        self.assertIn(f"| fig11 | {os.path.basename(first[0])} | {first[1]['sha256']} | authors' data {data} |", table)
        with redirect_stdout(io.StringIO()):  # the same content again: every suite is reused
            self.assertEqual(reproduce.main(args + ["--data", data]), 0)
        with open(os.path.join(out, "reproduce.json"), encoding="utf-8") as f:
            again = json.load(f)
        self.assertEqual([s for s in again["steps"] if s.startswith("run ") and not s.endswith(": cached")], [])


class TestSuiteTemplates(unittest.TestCase):
    KEYS = {"name", "snapshots", "generate", "solvers", "tol", "time_limit_s", "repeat", "history_max",
            "reference", "decouple", "decouple_seed", "chain"}

    def test_templates_follow_the_schema(self):
        folder = os.path.join(ROOT, "suites", "paper")
        names = sorted(f for f in os.listdir(folder) if f.endswith(".json"))
        self.assertEqual(names, ["fig10.json", "fig11.json", "fig6.json", "fig8.json", "table1.json"])
        for name in names:
            with open(os.path.join(folder, name), encoding="utf-8") as f:
                suite = json.load(f)
            self.assertLessEqual(set(suite), self.KEYS, name)
            labels = [s["label"] for s in suite["solvers"]]
            self.assertEqual(len(labels), len(set(labels)), name)
            for s in suite["solvers"]:
                self.assertIn(s["solver"], {"mprgp", "mprgp-coupled", "mprgp-box", "ica", "pgs", "active-set", "cg"})


if __name__ == "__main__":
    unittest.main()
