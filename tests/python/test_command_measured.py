"""An external program's numbers are measured, not believed (issue 41), through the binary
(env CB_CONTACTBENCH), with the small programs of fixtures/measured_program.py:

1. its work is not counted: `a_products` and `work` are null (never 0), `work_counted` false,
   compare accepts it, and the work-based figures leave it out with a note;
2. its times never exceed the child's wall time measured by the harness: a solve_s beyond it,
   or a history row beyond its solve_s, is refused as garbage;
3. stop=native holds it to the default accuracy like every solver (its tol is in its own units);
4. garbage output (a size line of 2^31 rows), an oversized history and one whose replay passes
   the time limit end as `diverged` with `garbage: true` and the reason, final (not retried).

Run from tests/python: /usr/bin/python3 -m unittest -v test_command_measured
"""
import json
import os
import resource
import shutil
import subprocess
import sys
import tempfile
import unittest

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, ROOT)
os.environ.setdefault("MPLBACKEND", "Agg")

from plots import figutil, loader  # noqa: E402

CB = os.environ.get("CB_CONTACTBENCH", os.path.join(ROOT, "build", "bin", "contactbench"))
PROG = os.path.join(HERE, "fixtures", "measured_program.py")
PY = "/usr/bin/python3"


def limit_memory():
    # 4 GiB of address space: a program's 2^31-row size line must not make the harness allocate 16 GiB.
    resource.setrlimit(resource.RLIMIT_AS, (4 << 30, 4 << 30))


def run(args):
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1")
    return subprocess.run([CB] + args, capture_output=True, text=True, env=env, timeout=300, preexec_fn=limit_memory)


class Measured(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.mkdtemp(prefix="cb_measured_")
        os.environ["CB_CACHE"] = os.path.join(cls.tmp, "cache")
        cls.snap = os.path.join(cls.tmp, "plane.qpsnap")
        r = run(["generate", "plane", "--out", cls.snap, "--seed", "5", "--param", "nx=3", "--param", "ny=2",
                 "--param", "nz=3"])
        assert r.returncode == 0, r.stderr
        exact = os.path.join(cls.tmp, "exact")
        r = run(["solve", cls.snap, "--solver", "active-set", "--set", "tol=1e-10", "--save-solution", exact])
        assert r.returncode == 0, r.stderr
        with open(os.path.join(exact, "x.mtx")) as f:
            lines = [ln for ln in f.read().splitlines() if ln and not ln.startswith("%")]
        cls.x_star = np.array([float(v) for v in lines[1:]])
        cls.exact = os.path.join(cls.tmp, "exact.npy")
        np.save(cls.exact, cls.x_star)

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.tmp, ignore_errors=True)

    def solve(self, mode, *args, sets=(), time_limit="30"):
        record = os.path.join(self.tmp, "run.json")
        if os.path.exists(record):
            os.remove(record)
        argv = [PY, PROG, mode, "{settings}"] + list(args)
        extra = []
        for s in sets:
            extra += ["--set", s]
        r = run(["solve", self.snap, "--solver", "command", "--set", "argv=" + json.dumps(argv), "--json", record,
                 "--time-limit", time_limit, "--history"] + extra)
        self.assertEqual(r.returncode, 0, r.stderr)
        with open(record) as f:
            return json.load(f)

    def assert_garbage(self, rec, needle):
        self.assertEqual(rec["status"], "diverged")
        self.assertTrue(rec["info"]["command"]["garbage"])
        self.assertIn(needle, rec["info"]["command"]["garbage_reason"])
        self.assertIn("command: the program's output is unusable: ", rec["message"])
        self.assertIn(needle, rec["message"])

    # 1. work not counted
    def test_work_is_null_not_zero_and_left_out_of_work_figures(self):
        rec = self.solve("claim", self.exact)
        self.assertEqual(rec["status"], "converged")
        self.assertIs(rec["work_counted"], False)
        self.assertIsNone(rec["counters"]["a_products"])
        self.assertIsNone(rec["counters"]["work"])
        cols = rec["history"]["columns"]
        for row in rec["history"]["rows"]:
            self.assertIsNone(row[cols.index("a_products")])
            self.assertIsNone(row[cols.index("work")])
        # A registry solver's run is counted.
        r = run(["solve", self.snap, "--solver", "pgs", "--json", os.path.join(self.tmp, "pgs.json")])
        self.assertEqual(r.returncode, 0, r.stderr)
        with open(os.path.join(self.tmp, "pgs.json")) as f:
            pgs = json.load(f)
        self.assertIs(pgs["work_counted"], True)
        self.assertGreater(pgs["counters"]["a_products"], 0)
        # The plots read it as "not counted" and leave it out of the work-based figures.
        row = loader.flatten_run(rec)
        self.assertTrue(np.isnan(row["a_products"]))
        self.assertTrue(np.isnan(row["work"]))
        self.assertTrue(loader.history_frame(rec)["work"].isna().all())
        self.assertIn("command", figutil.WORK_NOT_COUNTED)
        self.assertEqual(list(figutil.work_left_out(["prog", "pgs"], {"prog": "command", "pgs": "pgs"})), ["prog"])

    def test_compare_accepts_work_not_counted(self):
        folders = []
        for name in ("base", "new"):
            d = os.path.join(self.tmp, "cmp-" + name)
            os.makedirs(os.path.join(d, "runs"), exist_ok=True)
            rec = self.solve("claim", self.exact)
            rec["label"], rec["snapshot"]["id"] = "prog", "plane"
            with open(os.path.join(d, "runs", "plane__prog.json"), "w") as f:
                json.dump(rec, f)
            folders.append(d)
        r = run(["compare", folders[0], folders[1]])
        self.assertEqual(r.returncode, 0, r.stdout + r.stderr)
        # A baseline recorded before (a_products 0) against a run that is not counted: not a regression.
        with open(os.path.join(folders[0], "runs", "plane__prog.json")) as f:
            old = json.load(f)
        # (as 1556c21 wrote it: every work counter 0, no work_counted field)
        for counter, value in old["counters"].items():
            if value is None:
                old["counters"][counter] = 0
        old["counters"]["a_products"], old["counters"]["work"] = 0, 0.0
        del old["work_counted"]
        with open(os.path.join(folders[0], "runs", "plane__prog.json"), "w") as f:
            json.dump(old, f)
        r = run(["compare", folders[0], folders[1]])
        self.assertEqual(r.returncode, 0, r.stdout + r.stderr)

    def test_compact_record_accepts_work_not_counted(self):
        # The perf gate's CSV: a row with work_counted 0 has empty work cells; compare does not
        # judge them. The same empty cells without it are a counter that vanished: a regression.
        header = "snapshot,label,status,iterations,a_products,work,accuracy,tol,work_counted\n"
        base = os.path.join(self.tmp, "base.csv")
        with open(base, "w") as f:
            f.write(header + "plane,prog,converged,4,0,0,1e-07,1e-06,\n")
        for cell, rc in (("0", 0), ("", 3)):
            new = os.path.join(self.tmp, "new.csv")
            with open(new, "w") as f:
                f.write(header + "plane,prog,converged,4,,,1e-07,1e-06,%s\n" % cell)
            r = run(["compare", base, new])
            self.assertEqual(r.returncode, rc, r.stdout + r.stderr)

    # 2. times
    def test_solve_s_beyond_the_wall_time_is_refused(self):
        rec = self.solve("self_solve_s", "1000", self.exact)
        self.assert_garbage(rec, "/solve_s: setup_s + solve_s = 1000 s exceeds the child's wall time measured by "
                                 "the harness")
        self.assertEqual(rec["info"]["command"]["time_self_s"], None)

    def test_history_time_beyond_solve_s_is_refused(self):
        rec = self.solve("late_history", self.exact)
        self.assert_garbage(rec, "/history/0/time_s: 5 s is beyond the program's solve_s, 0.01 s")

    def test_history_times_stay_within_the_child_wall_time(self):
        rec = self.solve("history", "3", self.exact)
        self.assertEqual(rec["status"], "converged")
        cmd = rec["info"]["command"]
        cols = rec["history"]["columns"]
        replayed = [row[cols.index("time_s")] for row in rec["history"]["rows"] if row[cols.index("step")] == "outer"]
        self.assertEqual(len(replayed), 3)
        # Rows at the program's time 0 (no solve_s reported) land where the child ended on the
        # harness's clock: after its start-up, never beyond its wall time.
        for t in replayed:
            self.assertAlmostEqual(t, cmd["time_prepare_s"] + cmd["time_child_wall_s"], delta=1e-9)

    # 3. stop=native
    def test_stop_native_holds_the_program_to_the_default_accuracy(self):
        # x* moved by 1e-3 of its scale: e far above 1e-6, far below the program's own tol 0.1.
        point = os.path.join(self.tmp, "near.npy")
        np.save(point, self.x_star + 1e-3 * np.abs(self.x_star).max())
        rec = self.solve("claim", point, sets=("stop=native", "tol=0.1"))
        self.assertEqual(rec["solver_status"], "converged")
        self.assertEqual(rec["accuracy_tol"], 1e-6)
        self.assertGreater(rec["accuracy"]["max"], 1e-6)
        self.assertLess(rec["accuracy"]["max"], 0.1)
        self.assertEqual(rec["status"], "unconfirmed")

    # 4. garbage, final
    def test_huge_size_line_is_garbage_not_an_internal_error(self):
        rec = self.solve("huge_mtx")
        n = rec["snapshot"]["n"]
        self.assert_garbage(rec, "x.mtx: x: line 2: the size line declares '2147483646 1 0', expected %d x 1" % n)

    def test_oversized_history_is_garbage(self):
        rec = self.solve("history", "40000", self.exact)
        self.assert_garbage(rec, "/history: 40000 rows, more than the 20000 a program may report")

    def test_replay_past_the_time_limit_is_cut_there(self):
        # 19000 rows, each naming an x of 90,000 entries that the harness reads (and every 10th
        # it measures): a replay of many seconds against a limit of 3 s, while the program itself
        # ends in well under a second.
        big = os.path.join(self.tmp, "big.qpsnap")
        r = run(["generate", "plane", "--out", big, "--seed", "5", "--param", "nx=30", "--param", "ny=30",
                 "--param", "nz=30"])
        self.assertEqual(r.returncode, 0, r.stderr)
        from plots.qpsnap import read_qpsnap
        zeros = os.path.join(self.tmp, "zeros.npy")
        np.save(zeros, np.zeros(len(read_qpsnap(big)["arrays"]["x0"])))
        record = os.path.join(self.tmp, "big.json")
        argv = [PY, PROG, "history", "{settings}", "19000", zeros]
        r = run(["solve", big, "--solver", "command", "--set", "argv=" + json.dumps(argv), "--json", record,
                 "--time-limit", "3", "--history"])
        self.assertEqual(r.returncode, 0, r.stderr)
        with open(record) as f:
            rec = json.load(f)
        self.assert_garbage(rec, "rows passed the time limit of 3 s after")
        kept = len(rec["info"]["command"]["program_history"])
        self.assertLess(kept, 19000)

    def test_garbage_in_a_suite_is_final_and_not_retried(self):
        suite = os.path.join(self.tmp, "suite.json")
        with open(suite, "w") as f:
            json.dump({"name": "garbage", "allow_commands": True, "snapshots": [self.snap], "time_limit_s": 30,
                       "solvers": [{"label": "prog", "solver": "command",
                                    "settings": {"argv": [PY, PROG, "huge_mtx", "{settings}"]}}]}, f)
        out = os.path.join(self.tmp, "suite-out")
        r = run(["run", suite, "--out", out])
        self.assertEqual(r.returncode, 0, r.stderr)
        with open(os.path.join(out, "runs", "plane__prog.json")) as f:
            rec = json.load(f)
        self.assertEqual(rec["status"], "diverged")
        self.assertIs(rec["final"], True)
        self.assertTrue(rec["info"]["command"]["garbage"])
        r = run(["run", suite, "--out", out])
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertIn("done before, skipped", r.stderr)


if __name__ == "__main__":
    unittest.main()
