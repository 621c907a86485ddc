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

from plots import fig11, report, reproduce  # noqa: E402
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


if __name__ == "__main__":
    unittest.main()
