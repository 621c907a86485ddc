"""An interrupted `contactbench simulate` (SIGKILL mid-run) leaves a clearly incomplete folder whose
tables agree: only steps.csv.partial and frames.csv.partial, every frame of frames.csv.partial with
its rows in steps.csv.partial, no simulation.json (issue 15). Issue 43: the same command resumes it
from its last whole frame, and the result equals an uninterrupted run's bit for bit (SIGKILL and
SIGINT); SIGINT/SIGTERM stop on a whole frame and say where; a second simulate into a busy folder
exits 2; an earlier output is never deleted without --fresh. Needs CB_CONTACTBENCH (set by ctest)."""
import csv
import filecmp
import json
import os
import re
import shutil
import signal
import subprocess
import tempfile
import time
import unittest

CB = os.environ.get("CB_CONTACTBENCH", "")


@unittest.skipUnless(CB and os.access(CB, os.X_OK), "CB_CONTACTBENCH not set")
class TestInterruptedSimulation(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.mkdtemp(prefix="cb_test_interrupt_")

    def tearDown(self):
        shutil.rmtree(self.tmp, ignore_errors=True)

    def test_killed_simulation_leaves_consistent_partial_tables(self):
        scene = os.path.join(self.tmp, "fall.json")
        with open(scene, "w") as f:
            json.dump({"name": "fall", "h": 0.01, "frames": 100000,
                       "bodies": [{"box": {"cells": [3, 3, 3], "size": [0.3, 0.3, 0.3]},
                                   "translate": [0, 0.2, 0], "velocity": [0, -1, 0]}],
                       "obstacles": [{"type": "plane", "normal": [0, 1, 0], "point": [0, 0, 0]}],
                       "output": {"strip_frames": 0}}, f)
        out = os.path.join(self.tmp, "out")
        proc = subprocess.Popen([CB, "simulate", scene, "--out", out], stdout=subprocess.DEVNULL,
                                stderr=subprocess.DEVNULL)
        frames = os.path.join(out, "frames.csv.partial")
        deadline = time.time() + 120
        try:
            while time.time() < deadline:  # wait until a few frames are recorded, then kill
                if os.path.isfile(frames) and sum(1 for _ in open(frames)) > 5:
                    break
                time.sleep(0.05)
        finally:
            proc.send_signal(signal.SIGKILL)
            proc.wait()
        self.assertFalse(os.path.exists(os.path.join(out, "steps.csv")))
        self.assertFalse(os.path.exists(os.path.join(out, "frames.csv")))
        self.assertFalse(os.path.exists(os.path.join(out, "simulation.json")))
        with open(frames) as f:
            rows = list(csv.DictReader(f))
        with open(os.path.join(out, "steps.csv.partial")) as f:
            steps = list(csv.DictReader(f))
        recorded = [int(r["frame"]) for r in rows]
        self.assertGreater(len(recorded), 4)
        self.assertEqual(recorded, list(range(len(recorded))))          # whole rows, in order
        step_frames = sorted({int(r["frame"]) for r in steps})
        # steps are appended first: at most the frame being recorded is ahead of frames.csv
        self.assertEqual(step_frames[:len(recorded)], recorded)
        self.assertLessEqual(len(step_frames), len(recorded) + 1)
        for r in steps:  # each step row names a snapshot that is on disk, whole
            self.assertTrue(os.path.isfile(r["snapshot"]), r["snapshot"])



def write_scene(path, frames, cells=4):
    with open(path, "w") as f:
        json.dump({"name": "fall", "h": 0.01, "frames": frames,
                   "bodies": [{"box": {"cells": [cells] * 3, "size": [0.3, 0.3, 0.3]},
                               "translate": [0, 0.2, 0], "velocity": [0, -1, 0]}],
                   "obstacles": [{"type": "plane", "normal": [0, 1, 0], "point": [0, 0, 0]}],
                   "output": {"strip_frames": 4}}, f)


def wait_for_rows(proc, path, rows, seconds=120):
    """Until `path` has more than `rows` lines (the simulation is under way), or the process ended."""
    deadline = time.time() + seconds
    while time.time() < deadline and proc.poll() is None:
        if os.path.isfile(path) and sum(1 for _ in open(path)) > rows:
            return
        time.sleep(0.01)


#: steps.csv columns that are the same on every run (times and memory peaks are not; the snapshot
#: column names the output folder)
DETERMINISTIC = ["frame", "step", "newton_iteration", "solver", "status", "solver_status", "iterations", "accuracy",
                 "accuracy_solved", "rows", "rows_solved"]


@unittest.skipUnless(CB and os.access(CB, os.X_OK), "CB_CONTACTBENCH not set")
class TestResume(unittest.TestCase):
    FRAMES = 150

    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.mkdtemp(prefix="cb_test_resume_")
        cls.scene = os.path.join(cls.tmp, "fall.json")
        write_scene(cls.scene, cls.FRAMES)
        cls.whole = os.path.join(cls.tmp, "whole")
        done = subprocess.run([CB, "simulate", cls.scene, "--out", cls.whole], capture_output=True, text=True)
        assert done.returncode == 0, done.stderr

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.tmp, ignore_errors=True)

    def assert_same_as_whole(self, out):
        self.assertTrue(filecmp.cmp(os.path.join(self.whole, "frames.csv"), os.path.join(out, "frames.csv"),
                                    shallow=False))
        snaps = sorted(os.listdir(os.path.join(self.whole, "snapshots")))
        self.assertEqual(len(snaps), self.FRAMES)
        self.assertEqual(sorted(os.listdir(os.path.join(out, "snapshots"))), snaps)
        for name in snaps:  # every QP bit for bit
            self.assertTrue(filecmp.cmp(os.path.join(self.whole, "snapshots", name),
                                        os.path.join(out, "snapshots", name), shallow=False), name)
        self.assertTrue(filecmp.cmp(os.path.join(self.whole, "fall_strip.png"), os.path.join(out, "fall_strip.png"),
                                    shallow=False))

        def steps(folder):
            with open(os.path.join(folder, "steps.csv")) as f:
                return [[r[c] for c in DETERMINISTIC] for r in csv.DictReader(f)]
        self.assertEqual(steps(out), steps(self.whole))
        with open(os.path.join(out, "simulation.json")) as f:
            self.assertEqual(json.load(f)["frames_done"], self.FRAMES)
        self.assertEqual([n for n in os.listdir(out) if n.endswith(".partial")], [])

    def interrupt(self, out, sig):
        proc = subprocess.Popen([CB, "simulate", self.scene, "--out", out], stdout=subprocess.DEVNULL,
                                stderr=subprocess.PIPE, text=True)
        wait_for_rows(proc, os.path.join(out, "frames.csv.partial"), 8)
        proc.send_signal(sig)
        _, err = proc.communicate()
        return proc.returncode, err

    def resume(self, out):
        done = subprocess.run([CB, "simulate", self.scene, "--out", out], capture_output=True, text=True)
        self.assertEqual(done.returncode, 0, done.stderr)
        return done.stderr

    def test_killed_run_resumes_to_the_uninterrupted_frames(self):
        out = os.path.join(self.tmp, "killed")
        rc, _ = self.interrupt(out, signal.SIGKILL)
        self.assertEqual(rc, -signal.SIGKILL)
        with open(os.path.join(out, "frames.csv.partial")) as f:
            recorded = sum(1 for _ in f) - 1
        self.assertLess(recorded, self.FRAMES)
        err = self.resume(out)
        self.assertRegex(err, r"simulate: resuming .*killed after frame \d+ \(\d+ of 150 frames whole\)")
        self.assertNotIn("frame 0000 ", err)  # the whole frames are not stepped again
        self.assert_same_as_whole(out)

    def test_sigint_stops_on_a_whole_frame_and_says_where(self):
        out = os.path.join(self.tmp, "sigint")
        rc, err = self.interrupt(out, signal.SIGINT)
        self.assertEqual(rc, 130, err)
        last = err.strip().splitlines()[-1]
        m = re.fullmatch(r"simulate: stopped by signal 2 after frame (\d+): (\d+) whole frames in (.*) "
                         r"\(steps.csv.partial, frames.csv.partial\); the same command resumes it", last)
        self.assertIsNotNone(m, last)
        self.assertEqual((int(m.group(1)) + 1, m.group(3)), (int(m.group(2)), out))
        with open(os.path.join(out, "frames.csv.partial")) as f:  # a complete prefix, nothing beyond it
            self.assertEqual([int(r["frame"]) for r in csv.DictReader(f)], list(range(int(m.group(2)))))
        self.assertRegex(err, r"elapsed \d+\.\ds ETA \d+\.\ds")  # long runs say how long is left
        err = self.resume(out)
        self.assertIn(f"after frame {m.group(1)} ({m.group(2)} of 150 frames whole)", err)
        self.assert_same_as_whole(out)
        again = self.resume(out)  # the same command once more: nothing to do, nothing deleted
        self.assertIn("already holds this simulation, 150 frames (--fresh simulates again)", again)
        self.assert_same_as_whole(out)

    def test_a_second_simulate_into_a_busy_folder_exits_2(self):
        out = os.path.join(self.tmp, "busy")
        first = subprocess.Popen([CB, "simulate", self.scene, "--out", out], stdout=subprocess.DEVNULL,
                                 stderr=subprocess.DEVNULL)
        try:
            wait_for_rows(first, os.path.join(out, "frames.csv.partial"), 2)
            self.assertIsNone(first.poll())
            second = subprocess.run([CB, "simulate", self.scene, "--out", out, "--fresh"], capture_output=True,
                                    text=True)
            self.assertEqual(second.returncode, 2)
            self.assertEqual(second.stderr.strip().splitlines()[-1],
                             f"contactbench simulate: error: {out}: another `contactbench simulate` (pid {first.pid}) "
                             "is writing to this folder; wait for it to finish or use another --out")
        finally:
            first.send_signal(signal.SIGTERM)
            first.wait()
        self.assertEqual(first.returncode, 143)

    def test_an_earlier_output_is_never_deleted_without_fresh(self):
        out = os.path.join(self.tmp, "earlier")
        shutil.copytree(self.whole, out)
        other = os.path.join(self.tmp, "other.json")
        write_scene(other, self.FRAMES, cells=3)
        before = sorted(os.listdir(os.path.join(out, "snapshots")))
        done = subprocess.run([CB, "simulate", other, "--out", out], capture_output=True, text=True)
        self.assertEqual(done.returncode, 2)
        self.assertEqual(done.stderr.strip().splitlines()[-1],
                         f"contactbench simulate: error: {out}: --out: holds a simulation of other inputs (changed: "
                         "scene_file); --fresh discards it, or use another --out")
        self.assertEqual(sorted(os.listdir(os.path.join(out, "snapshots"))), before)
        os.remove(os.path.join(out, "resume.state"))  # output of an older contactbench: no state to compare
        done = subprocess.run([CB, "simulate", other, "--out", out], capture_output=True, text=True)
        self.assertEqual(done.returncode, 2)
        self.assertEqual(done.stderr.strip().splitlines()[-1],
                         f"contactbench simulate: error: {out}: --out: holds an earlier simulation's output "
                         "(simulation.json, steps.csv, frames.csv, fall_strip.png, 150 snapshots); --fresh discards it, "
                         "or use another --out")
        fresh = subprocess.run([CB, "simulate", other, "--out", out, "--fresh", "--frames", "3"], capture_output=True,
                               text=True)
        self.assertEqual(fresh.returncode, 0, fresh.stderr)
        self.assertEqual(len(os.listdir(os.path.join(out, "snapshots"))), 3)



@unittest.skipUnless(CB and os.access(CB, os.X_OK), "CB_CONTACTBENCH not set")
class TestChainsLockAndStop(unittest.TestCase):
    """`chains` takes the folder's lock, never deletes an earlier run without --fresh, stops on
    SIGTERM after a whole frame of every chain and says the same command resumes it; the resumed
    run's outputs equal an uninterrupted run's bit for bit; other inputs are refused naming them."""

    @classmethod
    def setUpClass(cls):
        # The uninterrupted run both resume tests compare with (the same command for both).
        cls.scene = os.path.join(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))),
                                 "scenes", "demo.json")
        cls.tmp = tempfile.mkdtemp(prefix="cb_test_chains_")
        cls.whole = os.path.join(cls.tmp, "whole")
        subprocess.run([CB, "chains", cls.scene, "--frames", "150", "--out", cls.whole], check=True, capture_output=True)

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.tmp, ignore_errors=True)

    def test_busy_earlier_and_stopped(self):
        scene = os.path.join(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))),
                             "scenes", "demo.json")
        with tempfile.TemporaryDirectory() as tmp:
            out = os.path.join(tmp, "ch")
            first = subprocess.Popen([CB, "chains", scene, "--frames", "100000", "--out", out],
                                     stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
            try:
                deadline = time.time() + 120
                while time.time() < deadline and first.poll() is None and not os.path.isfile(os.path.join(out, ".lock")):
                    time.sleep(0.01)
                time.sleep(0.5)
                second = subprocess.run([CB, "chains", scene, "--frames", "2", "--out", out, "--fresh"],
                                        capture_output=True, text=True)
                self.assertEqual(second.returncode, 2)
                self.assertEqual(second.stderr.strip().splitlines()[-1],
                                 f"contactbench chains: error: {out}: another `contactbench chains` (pid {first.pid}) is "
                                 "writing to this folder; wait for it to finish or use another --out")
            finally:
                first.send_signal(signal.SIGTERM)
                _, err = first.communicate()
            self.assertEqual(first.returncode, 143, err)
            m = re.search(r"chains: stopped by signal 15 after frame (\d+): (.*)/chains.csv holds frames 0 to (\d+) "
                          r"of every chain; no chains.json \(the same command resumes them\)", err)
            self.assertIsNotNone(m, err[-500:])
            self.assertEqual(m.group(2), out)
            with open(os.path.join(out, "chains.csv")) as f:
                rows = list(csv.DictReader(f))
            frames = sorted({int(r["frame"]) for r in rows})
            self.assertEqual(frames, list(range(int(m.group(1)) + 1)))
            self.assertEqual(len(rows), 5 * len(frames))  # every chain's row of every whole frame
            again = subprocess.run([CB, "chains", scene, "--frames", "2", "--out", out], capture_output=True, text=True)
            self.assertEqual(again.returncode, 2)
            self.assertEqual(again.stderr.strip().splitlines()[-1],
                             f"contactbench chains: error: {out}: --out: holds a chains run of other inputs "
                             "(changed: frames); --fresh discards it, or use another --out")
            self.assertEqual(len(open(os.path.join(out, "chains.csv")).read().splitlines()), len(rows) + 1)

    def test_resumed_chains_equal_an_uninterrupted_run(self):
        scene, whole = self.scene, self.whole
        outputs = ["chains.csv", "chains.json", "demo_largest_difference.png", "demo_largest_penetration.png"]
        with tempfile.TemporaryDirectory() as tmp:
            out = os.path.join(tmp, "resumed")
            cmd = [CB, "chains", scene, "--frames", "150"]
            first = subprocess.Popen(cmd + ["--out", out], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                                     text=True)
            state = os.path.join(out, "chains.state")
            try:  # SIGINT once three frames are whole (the header's frames_done)
                deadline = time.time() + 120
                while time.time() < deadline and first.poll() is None:
                    try:
                        with open(state, "rb") as f:
                            head = json.loads(f.read().split(b"\n")[1])
                        if head["frames_done"] >= 3:
                            break
                    except (OSError, ValueError, IndexError):
                        pass
                    time.sleep(0.002)
            finally:
                first.send_signal(signal.SIGINT)
                _, err = first.communicate()
            self.assertEqual(first.returncode, 130, err[-500:])
            m = re.search(r"chains: stopped by signal 2 after frame (\d+): ", err)
            self.assertIsNotNone(m, err[-500:])
            stopped = int(m.group(1))
            self.assertLess(stopped, 149)
            self.assertFalse(os.path.exists(os.path.join(out, "chains.json")))
            # Other inputs are refused, naming what changed, and leave the run as it was.
            changed = os.path.join(tmp, "demo.json")
            with open(scene) as f:
                text = f.read()
            with open(changed, "w") as f:
                f.write(text + "\n")
            for extra, what in [(["--h", "0.005"], "h, steps_per_frame"), (["--orders", "authors"], "chains"),
                                (["--decouple-seed", "3"], "decouple_seed"), (["--exact", "pgs"], "chains")]:
                r = subprocess.run(cmd + ["--out", out] + extra, capture_output=True, text=True)
                self.assertEqual(r.returncode, 2, r.stderr)
                self.assertEqual(r.stderr.strip().splitlines()[-1],
                                 f"contactbench chains: error: {out}: --out: holds a chains run of other inputs "
                                 f"(changed: {what}); --fresh discards it, or use another --out")
            r = subprocess.run([CB, "chains", changed, "--frames", "150", "--out", out], capture_output=True, text=True)
            self.assertEqual(r.returncode, 2, r.stderr)
            self.assertIn("(changed: scene_file)", r.stderr.strip().splitlines()[-1])
            again = subprocess.run(cmd + ["--out", out], capture_output=True, text=True)
            self.assertEqual(again.returncode, 0, again.stderr[-500:])
            self.assertIn(f"chains: resuming {out} after frame {stopped} ({stopped + 1} of 150 frames whole)",
                          again.stderr)
            for name in outputs:
                self.assertTrue(filecmp.cmp(os.path.join(whole, name), os.path.join(out, name), shallow=False), name)
            self.assertFalse(os.path.exists(state))  # removed once chains.json is written
            # A finished run is refused without --fresh.
            done = subprocess.run(cmd + ["--out", out], capture_output=True, text=True)
            self.assertEqual(done.returncode, 2)
            self.assertIn("holds an earlier chains run's output (chains.json, chains.csv, demo_largest_difference.png,"
                          " demo_largest_penetration.png)", done.stderr)

    def test_killed_chains_resume_equal_an_uninterrupted_run(self):
        """SIGKILL: chains.csv.partial and chains.state are left; the same command resumes them."""
        scene, whole = self.scene, self.whole
        with tempfile.TemporaryDirectory() as tmp:
            out = os.path.join(tmp, "killed")
            cmd = [CB, "chains", scene, "--frames", "150"]
            first = subprocess.Popen(cmd + ["--out", out], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
            state = os.path.join(out, "chains.state")
            try:
                deadline = time.time() + 120
                while time.time() < deadline and first.poll() is None:
                    try:
                        with open(state, "rb") as f:
                            if json.loads(f.read().split(b"\n")[1])["frames_done"] >= 3:
                                break
                    except (OSError, ValueError, IndexError):
                        pass
                    time.sleep(0.002)
            finally:
                first.kill()
                first.wait()
            self.assertEqual(first.returncode, -signal.SIGKILL)
            self.assertTrue(os.path.isfile(os.path.join(out, "chains.csv.partial")))
            self.assertFalse(os.path.exists(os.path.join(out, "chains.csv")))
            again = subprocess.run(cmd + ["--out", out], capture_output=True, text=True)
            self.assertEqual(again.returncode, 0, again.stderr[-500:])
            self.assertIn(f"chains: resuming {out} after frame ", again.stderr)
            for name in ["chains.csv", "chains.json", "demo_largest_difference.png", "demo_largest_penetration.png"]:
                self.assertTrue(filecmp.cmp(os.path.join(whole, name), os.path.join(out, name), shallow=False), name)
            self.assertFalse(os.path.exists(os.path.join(out, "chains.csv.partial")))


if __name__ == "__main__":
    unittest.main()
