"""The `command` solver and `judge` end to end through the binary (env CB_CONTACTBENCH).

An external program's answer is judged on the original QP like any registry solver's: a crash,
a hang, garbage output and a lie (a wrong x claimed converged, also one at e ~ 1e-4) each get an
honest status; the Python example runs in a suite beside mprgp and active-set and appears in
plots.profiles.

Run from tests/python: /usr/bin/python3 -m unittest -v test_command_solver
"""
import json
import os
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

from plots import loader, profiles  # noqa: E402

CB = os.environ.get("CB_CONTACTBENCH", os.path.join(ROOT, "build", "bin", "contactbench"))
BUILD = os.path.dirname(os.path.dirname(os.path.abspath(CB)))  # the build folder holding bin/ and examples/
FAKE = os.path.join(HERE, "fixtures", "fake_command_solver.py")
PY = "/usr/bin/python3"


def run(args, cwd=None, extra_env=None):
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1", **(extra_env or {}))
    return subprocess.run([CB] + args, capture_output=True, text=True, cwd=cwd, env=env, timeout=300)


def gone_or_zombie(pid):
    """True when `pid` no longer runs (an orphan killed with its group may wait for init to reap it)."""
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().rsplit(")", 1)[1].split()[0] == "Z"
    except FileNotFoundError:
        return True


class CommandCase(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.mkdtemp(prefix="cb_command_")
        os.environ["CB_CACHE"] = os.path.join(cls.tmp, "cache")
        cls.snap = os.path.join(cls.tmp, "plane.qpsnap")
        r = run(["generate", "plane", "--out", cls.snap, "--seed", "5", "--param", "nx=3", "--param", "ny=2",
                 "--param", "nz=3"])
        assert r.returncode == 0, r.stderr
        # The exact solution (active-set to 1e-10) the lying programs start from.
        cls.exact = os.path.join(cls.tmp, "exact")
        r = run(["solve", cls.snap, "--solver", "active-set", "--set", "tol=1e-10", "--save-solution", cls.exact])
        assert r.returncode == 0, r.stderr

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.tmp, ignore_errors=True)

    def solve_with(self, argv, *extra, extra_env=None):
        """`solve --solver command` with argv; returns (completed process, run record)."""
        record = os.path.join(self.tmp, "run.json")
        if os.path.exists(record):
            os.remove(record)
        r = run(["solve", self.snap, "--solver", "command", "--set", "argv=" + json.dumps(argv), "--json", record]
                + list(extra), extra_env=extra_env)
        self.assertEqual(r.returncode, 0, r.stderr)
        with open(record) as f:
            return r, json.load(f)

    def fake(self, mode, *extra, time_limit="20"):
        return self.solve_with([PY, FAKE, mode, "{settings}"] + list(extra), "--time-limit", time_limit)

    def judge_e(self, x_path):
        out = os.path.join(self.tmp, "judge.json")
        r = run(["judge", self.snap, x_path, "--json", out])
        self.assertEqual(r.returncode, 0, r.stderr)
        with open(out) as f:
            return json.load(f)["accuracy"]["max"]


class TestHonestStatuses(CommandCase):
    def test_crash_by_signal_is_diverged_and_says_so(self):
        _, rec = self.fake("abort")
        self.assertEqual(rec["status"], "diverged")
        self.assertTrue(rec["info"]["command"]["crashed"])
        self.assertEqual(rec["info"]["command"]["signal"], 6)
        self.assertIn("the program was killed by signal 6", rec["message"])

    def test_non_zero_exit_reports_status_and_stderr(self):
        _, rec = self.fake("exit3")
        self.assertEqual(rec["status"], "diverged")
        self.assertIn("the program exited with status 3; stderr: fake solver: out of cheese", rec["message"])

    def test_program_that_cannot_start(self):
        _, rec = self.solve_with(["/nonexistent/solver", "{settings}"])
        self.assertEqual(rec["status"], "diverged")
        self.assertIn("could not be started", rec["message"])
        self.assertIn("No such file or directory", rec["message"])

    def test_no_temporary_folder_is_diverged_and_says_so(self):
        # $TMPDIR unusable: the problem cannot be handed over; the run fails, the harness goes on.
        _, rec = self.solve_with([PY, FAKE, "exact", "{settings}"],
                                 extra_env={"TMPDIR": os.path.join(self.tmp, "no-such-folder")})
        self.assertEqual(rec["status"], "diverged")
        self.assertIn("command: cannot find the temporary folder ($TMPDIR)", rec["message"])

    def test_hang_is_killed_at_the_time_limit_with_its_children(self):
        pids = os.path.join(self.tmp, "pids.txt")
        _, rec = self.fake("hang", pids, time_limit="1")
        self.assertEqual(rec["status"], "time_limit")
        self.assertTrue(rec["info"]["command"]["timed_out"])
        self.assertIn("killed at the time limit of 1", rec["message"])
        self.assertLess(rec["info"]["command"]["time_child_wall_s"], 30)  # killed, not waited for (300 s)
        with open(pids) as f:
            for pid in map(int, f.read().split()):
                self.assertTrue(gone_or_zombie(pid), f"pid {pid} survived the kill")

    def test_garbage_output_names_file_and_field(self):
        n = self.fake("maxit")[1]["snapshot"]["n"]
        for mode, needle in [("garbage", "x.txt: line 1: expected a number of x, got 'the'"),
                             ("short", f"x.npy: x: expected {n} entries (n of the snapshot), got {n - 1}"),
                             ("nan", "x.npy: x[0]: not finite (nan)")]:
            with self.subTest(mode=mode):
                _, rec = self.fake(mode)
                self.assertEqual(rec["status"], "diverged")
                self.assertTrue(rec["info"]["command"]["garbage"])
                self.assertIn("the program's output is unusable: ", rec["message"])
                self.assertIn(needle, rec["message"])

    def test_far_lie_is_unconfirmed(self):
        _, rec = self.fake("lie_x0")
        self.assertEqual(rec["solver_status"], "converged")
        self.assertEqual(rec["status"], "unconfirmed")
        self.assertFalse(rec["status_confirmed"])
        self.assertGreater(rec["accuracy"]["max"], 1e-3)

    def test_near_lie_at_e_1e_4_is_unconfirmed(self):
        # x* moved towards x0 by the step s that puts the measure's e at about 1e-4 (found by judge).
        with open(os.path.join(self.exact, "x.mtx")) as f:
            lines = f.read().split("\n")
        x_star = np.array([float(v) for v in lines[2:] if v])  # banner, size line, values
        from plots.qpsnap import read_qpsnap
        x0 = np.array(read_qpsnap(self.snap)["arrays"]["x0"], dtype=float)
        lo, hi, near = 1e-12, 1.0, None
        for _ in range(60):
            s = (lo * hi) ** 0.5
            path = os.path.join(self.tmp, "near.npy")
            np.save(path, x_star + s * (x0 - x_star))
            e = self.judge_e(path)
            if 0.5e-4 <= e <= 2e-4:
                near = e
                break
            lo, hi = (s, hi) if e < 1e-4 else (lo, s)
        self.assertIsNotNone(near, "no step gave e in [5e-5, 2e-4]")
        _, rec = self.fake("claim", path)
        self.assertEqual(rec["solver_status"], "converged")
        self.assertEqual(rec["status"], "unconfirmed")
        self.assertAlmostEqual(rec["accuracy"]["max"], near, delta=1e-12)
        # judge on the same point, with the record, rebuilds the same verdict.
        r = run(["judge", self.snap, path, "--record", os.path.join(self.tmp, "run.json")])
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertIn("status      unconfirmed", r.stdout)
        self.assertIn("verdict     not converged at tol 1e-06", r.stdout)

    def test_right_answer_without_a_status_is_confirmed(self):
        _, rec = self.fake("silent", os.path.join(self.exact, "x.mtx"))
        self.assertEqual(rec["status"], "converged")
        self.assertTrue(rec["lambda_fitted"])
        self.assertLessEqual(rec["accuracy"]["max"], 1e-6)

    def test_honest_max_iterations_passes_through(self):
        _, rec = self.fake("maxit")
        self.assertEqual(rec["status"], "max_iterations")
        self.assertEqual(rec["iterations"], 10000)

    def test_both_times_recorded_and_self_time_on_request(self):
        x = os.path.join(self.exact, "x.mtx")
        _, harness = self.fake("self_time", x)
        cmd = harness["info"]["command"]
        self.assertEqual(cmd["time_source"], "harness")
        self.assertEqual(cmd["time_self_s"], 0.125)
        self.assertEqual(harness["time"]["solve_s"], cmd["time_child_wall_s"])
        r, own = self.solve_with([PY, FAKE, "self_time", "{settings}", x], "--set", "time=self")
        self.assertEqual(own["info"]["command"]["time_source"], "self")
        self.assertEqual(own["time"]["solve_s"], 0.125)

    def test_bad_argv_is_exit_2_naming_the_field(self):
        r = run(["solve", self.snap, "--solver", "command", "--set", "argv=python3 solver.py"])
        self.assertEqual(r.returncode, 2)
        self.assertIn('command: /argv: expected a JSON array of strings, got the string "python3 solver.py"', r.stderr)
        r = run(["solve", self.snap, "--solver", "command", "--set", 'argv=["python3", "solver.py"]'])
        self.assertEqual(r.returncode, 2)
        self.assertIn("command: /argv: must name {settings}, or {snapshot} (or {mtx}) and {out}", r.stderr)


class TestJudgeCli(CommandCase):
    def test_judge_prints_solves_error_and_exits_2_on_bad_solutions(self):
        saved = os.path.join(self.tmp, "pgs_solution")
        r = run(["solve", self.snap, "--solver", "pgs", "--set", "max_iterations=5", "--save-solution", saved])
        self.assertEqual(r.returncode, 0, r.stderr)
        first_part = [ln for ln in r.stdout.splitlines() if ln.startswith("error")][0].split("; tol")[0]
        r = run(["judge", self.snap, saved])
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertIn(first_part, r.stdout)  # e and its parts, as solve printed them
        self.assertIn("verdict     not converged at tol 1e-06 (e > tol)", r.stdout)
        self.assertIn("units       stationarity, primal, dual, complementarity: lengths / l", r.stdout)
        r = run(["judge", self.snap, self.exact])
        self.assertIn("verdict     converged at tol 1e-06 (e <= tol)", r.stdout)
        n = json.loads(run(["info", self.snap, "--json"]).stdout)["n"]
        out = os.path.join(self.tmp, "judged.json")
        bad = os.path.join(self.tmp, "bad.txt")
        with open(bad, "w") as f:
            f.write("1 2 3\n")
        for args, message in [([os.path.join(self.tmp, "missing.npy")], "missing.npy: x: no such file or folder"),
                              ([bad], f"bad.txt: x: expected {n} entries (n of the snapshot), got 3"),
                              ([self.exact, "--lambda", bad], "bad.txt: lambda: expected "),
                              ([self.exact, "--record", bad], "bad.txt: not valid JSON")]:
            with self.subTest(args=args):
                r = run(["judge", self.snap] + args + ["--json", out])
                self.assertEqual(r.returncode, 2, r.stdout)
                self.assertIn(message, r.stderr)
                self.assertFalse(os.path.exists(out))  # no partial output


class TestExampleSuite(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.mkdtemp(prefix="cb_command_suite_")
        os.environ["CB_CACHE"] = os.path.join(self.tmp, "cache")

    def tearDown(self):
        shutil.rmtree(self.tmp, ignore_errors=True)

    def test_suite_must_opt_in(self):
        with open(os.path.join(ROOT, "suites", "command_example.json")) as f:
            suite = json.load(f)
        del suite["allow_commands"]
        path = os.path.join(self.tmp, "no_opt_in.json")
        with open(path, "w") as f:
            json.dump(suite, f)
        r = run(["run", path, "--out", os.path.join(self.tmp, "out")], cwd=ROOT)
        self.assertEqual(r.returncode, 2)
        self.assertIn(path + ": /solvers/2/solver: 'command' runs an external program; the suite must opt in with "
                      '"allow_commands": true', r.stderr)
        self.assertFalse(os.path.exists(os.path.join(self.tmp, "out")))

    def test_python_example_beside_mprgp_and_active_set_judged_on_the_original_qp(self):
        out = os.path.join(self.tmp, "results")
        self.assertTrue(os.path.isfile(os.path.join(BUILD, "examples", "pgd_solver_c")),
                        "build the C example first: cmake --build build --target pgd_solver_c")
        # The suite names build/bin/contactbench (run from the root after `make`): the binary under
        # test instead, in a copy (its snapshots are generated, so no path depends on its folder).
        with open(os.path.join(ROOT, "suites", "command_example.json")) as f:
            suite = json.load(f)
        for entry in suite["solvers"]:
            settings = entry.get("settings", {})
            if "argv" in settings:
                settings["argv"] = [a.replace("build/", BUILD + "/", 1) if a.startswith("build/") else a
                                    for a in settings["argv"]]
        path = os.path.join(self.tmp, "command_example.json")
        with open(path, "w") as f:
            json.dump(suite, f)
        r = run(["run", path, "--out", out], cwd=ROOT)
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertEqual(len(loader.load_results(out).runs), 3 * 5)
        res = loader.load_results(out)
        runs = {(row["snapshot"], row["label"]): row for _, row in res.runs.iterrows()}
        for snap in ("plane-s1", "plane-s2"):
            python = runs[(snap, "pgd-python")]
            self.assertEqual(python["status"], "converged")
            self.assertLessEqual(python["accuracy"], 1e-6)
            # the same optimum as the registry solvers: objectives agree to 1e-8 relative
            exact = runs[(snap, "active-set")]["objective"]
            self.assertLessEqual(abs(python["objective"] - exact), 1e-8 * abs(exact))
            for label in ("pgd-c", "pgs-shell"):  # the C program; the shell script around a command-line tool
                other = runs[(snap, label)]
                self.assertEqual(other["status"], "converged", label)
                self.assertLessEqual(other["accuracy"], 1e-6, label)
                self.assertLessEqual(abs(other["objective"] - exact), 1e-8 * abs(exact), label)
        coupled = runs[("coupled", "pgd-python")]
        self.assertEqual(coupled["status"], "solved_relaxation")  # decoupled by the harness, judged on all rows
        self.assertLess(coupled["rows_after"], coupled["rows_before"])
        self.assertGreater(coupled["accuracy"], 1e-6)
        self.assertLessEqual(coupled["accuracy_solved"], 1e-6)
        self.assertEqual(runs[("coupled", "pgd-c")]["status"], "solved_relaxation")
        numbers = profiles.compute(res)
        for label in ("pgd-python", "pgd-c", "pgs-shell", "mprgp", "active-set"):
            self.assertIn(label, numbers["tiers"]["label"].tolist())
        self.assertEqual(profiles.main([out]), 0)
        with open(os.path.join(out, "profiles.md"), encoding="utf-8") as f:
            self.assertIn("| pgd-python |", f.read())


if __name__ == "__main__":
    unittest.main()
