"""An interrupted `contactbench simulate` (SIGKILL mid-run) leaves a clearly incomplete folder whose
tables agree: only steps.csv.partial and frames.csv.partial, every frame of frames.csv.partial with
its rows in steps.csv.partial, no simulation.json (issue 15). Needs CB_CONTACTBENCH (set by ctest)."""
import csv
import json
import os
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


if __name__ == "__main__":
    unittest.main()
