"""A figure script run on its own judges its timed claims on every round, as the report does.

Run from tests/python: MPLBACKEND=Agg /usr/bin/python3 -m unittest test_reproduce_rounds
"""
import io
import os
import shutil
import sys
import tempfile
import unittest
from contextlib import redirect_stdout

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, ROOT)
os.environ.setdefault("MPLBACKEND", "Agg")

from plots import claims, fig11, report, reproduce, table1  # noqa: E402
from plots.paper_context import PaperContext, round_folders, standalone_context, standalone_rounds  # noqa: E402

FAKE_CB = os.path.join(HERE, "fixtures", "fake_contactbench.py")


class TestStandaloneRounds(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.mkdtemp(prefix="cb_rounds_")

    def tearDown(self):
        shutil.rmtree(self.tmp, ignore_errors=True)

    def folder(self, *parts, finished=True):
        path = os.path.join(self.tmp, *parts)
        os.makedirs(path)
        if finished:
            with open(os.path.join(path, "summary.csv"), "w") as f:
                f.write("snapshot,label\n")
        return path

    def test_rounds_beside_the_results_in_numeric_order_finished_only(self):
        first = self.folder("out", "runs", "fig11")
        for k in ("2", "3", "10"):
            self.folder("out", "rounds", "fig11", k)
        self.folder("out", "rounds", "fig11", "4", finished=False)  # interrupted: no summary.csv
        self.folder("out", "rounds", "fig11", "notes")
        expected = [os.path.join(self.tmp, "out", "rounds", "fig11", k) for k in ("2", "3", "10")]
        self.assertEqual(round_folders(os.path.join(self.tmp, "out"), "fig11"), expected)
        self.assertEqual(standalone_rounds(first, []), [first] + expected)
        # explicit --round folders win; a folder outside the runs/ layout has no rounds of its own
        self.assertEqual(standalone_rounds(first, ["/x/2"]), [first, "/x/2"])
        other = self.folder("elsewhere", "fig11")
        self.assertEqual(standalone_rounds(other, []), [other])
        ctx = standalone_context([other, "--round", expected[0], "--round", expected[1]], "fig11", "t")
        self.assertEqual(ctx.rounds["fig11"], [other] + expected[:2])
        self.assertEqual(standalone_context([other], "fig11", "t").rounds, {})

    def test_standalone_fig11_gives_the_reports_interval(self):
        # eight rounds of the fig11 suite with the stand-in contactbench, laid out as reproduce.py does
        scene = os.path.join(self.tmp, "two_dinos_1303.json")
        with open(scene, "w") as f:
            f.write("{}")
        out = os.path.join(self.tmp, "out")
        ctx = PaperContext(out=out, quick=True)
        runner = reproduce.Runner(FAKE_CB, None, os.path.join(self.tmp, "log"))
        with redirect_stdout(io.StringIO()):
            reproduce.simulate(runner, ctx, "two_dinos_1303", scene, 12, None, False)
            snaps = reproduce.pick_frame(reproduce.snapshots_of(ctx, "two_dinos_1303"), 11)
            reproduce.run_suite(runner, ctx, "fig11", os.path.join(ROOT, "suites", "paper", "fig11.json"), snaps, False)
        rounds = reproduce.TIMED_SUITES["fig11"]
        # every contactbench step says its wall and CPU time (CPU: the child's, from os.times)
        first = next(s for s in runner.steps if s.startswith("run fig11:"))
        self.assertRegex(first, r"^run fig11: exit 0 in \d+\.\d s \(CPU \d+\.\d s\)$")
        from_report = report.context_from_out(out, None, quick=True)
        self.assertEqual(len(from_report.rounds["fig11"]), rounds)
        alone = standalone_context([os.path.join(out, "runs", "fig11"), "--out", os.path.join(self.tmp, "alone")],
                                   "fig11", "t")
        self.assertEqual(alone.rounds["fig11"], from_report.rounds["fig11"])
        with redirect_stdout(io.StringIO()):
            want = {c.key: c for c in fig11.produce(from_report).claims}
            got = {c.key: c for c in fig11.produce(alone).claims}
        low = got["fig11-ica-low-res"]
        self.assertEqual(low.samples, rounds)
        self.assertLessEqual(low.interval[0], low.estimate)
        self.assertLessEqual(low.estimate, low.interval[1])
        for key, c in want.items():
            self.assertEqual((got[key].verdict, got[key].estimate, got[key].interval, got[key].samples),
                             (c.verdict, c.estimate, c.interval, c.samples), key)

    def test_quick_fig11_on_close_resolutions_is_inconclusive_with_its_reason(self):
        # issue 43: the quick mode's two coarsest resolutions (7818 and 8958 DOF, 1.15x apart) cannot
        # show a growth a full run could not reverse; the full-mode verdict on the same runs is decided
        out = os.path.join(self.tmp, "out")
        ctx = PaperContext(out=out, quick=True)
        runner = reproduce.Runner(FAKE_CB, None, os.path.join(self.tmp, "log"))
        snaps = []
        with redirect_stdout(io.StringIO()):
            for key in ("two_dinos_1303", "two_dinos_1493"):
                scene = os.path.join(self.tmp, key + ".json")
                with open(scene, "w") as f:
                    f.write("{}")
                reproduce.simulate(runner, ctx, key, scene, 12, None, False)
                snaps += reproduce.pick_frame(reproduce.snapshots_of(ctx, key), 11)
            reproduce.run_suite(runner, ctx, "fig11", os.path.join(ROOT, "suites", "paper", "fig11.json"), snaps, False)
            quick = {c.key: c for c in fig11.produce(ctx).claims}
            ctx.quick = False
            full = {c.key: c for c in fig11.produce(ctx).claims}
        grows = quick["fig11-advantage-grows"]
        self.assertEqual(grows.verdict, claims.INCONCLUSIVE_QUICK)
        self.assertIn(full["fig11-advantage-grows"].verdict, claims.DECIDED)
        self.assertEqual(grows.reason, "quick mode: the resolutions judged are 1.15x apart (7818 and 8958 DOF), under "
                                       f"2x; the quick run found '{full['fig11-advantage-grows'].verdict}'")
        # every ratio is stated: at the smallest DOF count, at the largest, and the growth between
        self.assertRegex(grows.ours, r"^published: ICA/MPRGP at 7818 DOF [0-9.]+ \[[0-9.]+, [0-9.]+\]x, at 8958 DOF "
                                     r"[0-9.]+ \[[0-9.]+, [0-9.]+\]x, growth [0-9.]+ \[[0-9.]+, [0-9.]+\]x; fair: ")
        # the low-resolution claim rests on one resolution: not withdrawn by the span
        self.assertEqual(quick["fig11-ica-low-res"].verdict, full["fig11-ica-low-res"].verdict)

    def test_quick_fig11_final_error_within_a_margin_of_the_level(self):
        import pandas as pd
        runs = pd.DataFrame([
            {"label": "mprgp-fair", "n": 7818, "accuracy": 1e-7, "status": "converged", "snapshot": "a"},
            {"label": "ica-fair", "n": 7818, "accuracy": 0.00999, "status": "converged", "snapshot": "a"},
            {"label": "mprgp-fair", "n": 81000, "accuracy": 1e-7, "status": "converged", "snapshot": "b"},
            {"label": "ica-fair", "n": 81000, "accuracy": 0.05, "status": "max_iterations", "snapshot": "b"}])
        why = fig11.quick_reasons(runs)
        text = "quick mode: ica-fair at 7818 DOF ends at e 0.00999, within 2x of the level 0.01 its fair time is measured to"
        self.assertEqual(why, {"grows": [text], "low": [text]})  # 10.4x apart: the span is wide enough


    def test_table1_quotes_the_authors_cold_starts_from_their_data(self):
        data = os.path.join(self.tmp, "paper-data")
        os.makedirs(os.path.join(data, "figures"))
        with open(os.path.join(data, "figures", "fig11_mprgp_vs_ica.csv"), "w") as f:
            f.write("dofs,power_iterations\n7818,700\n24000,655\n81000,980\n")
        self.assertEqual(table1.authors_cold_starts(PaperContext(out=self.tmp, data=data)),
                         "— (Fig. 11 data: cold starts of 655-980 products)")
        self.assertEqual(table1.authors_cold_starts(PaperContext(out=self.tmp, data=None)), "—")


if __name__ == "__main__":
    unittest.main()
