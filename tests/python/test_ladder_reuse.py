"""tools/ladder.sh reuses a cached simulation folder only when it is the scene's own (R9 of the
hostile audit: any folder holding a simulation.json was reused, whatever its scene or version), and
recognises the scene by content, not by file time (a fresh clone's scene files are newer than any
simulation made before the clone)."""
import json
import os
import shutil
import subprocess
import sys
import tempfile
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(ROOT, "tools"))

import ladder_reuse  # noqa: E402

CB = os.environ.get("CB_CONTACTBENCH") or os.path.join(ROOT, "build", "bin", "contactbench")
WHOLE_RUN = {"scene": "density_10", "simulator_version": 4, "frames_done": 2, "blow_up": False, "solver": "mprgp"}


class TestLadderReuse(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.mkdtemp(prefix="cb_ladder_")
        self.scene = os.path.join(self.tmp, "density_10.json")
        with open(self.scene, "w", encoding="utf-8") as f:
            json.dump({"name": "density_10", "frames": 2}, f)
        self.sim = os.path.join(self.tmp, "simulation.json")

    def tearDown(self):
        shutil.rmtree(self.tmp, ignore_errors=True)

    def write(self, record, scene_hash=None):
        with open(self.sim, "w", encoding="utf-8") as f:
            json.dump(record, f)
        if scene_hash is not None:  # what `simulate` keeps: a magic line, one JSON line, then vectors
            with open(os.path.join(self.tmp, "resume.state"), "wb") as f:
                f.write(b"cb-resume 1\n" + json.dumps({"identity": {"scene_file": scene_hash}}).encode() + b"\n")
                f.write(bytes(16))

    def test_a_planted_folder_is_stale(self):
        self.write({"scene": "not this one", "simulator_version": "0-stale"})
        reason = ladder_reuse.stale_reason(self.sim, self.scene, 4)
        self.assertTrue(reason.startswith("scene 'not this one', not 'density_10'; simulator version '0-stale', "
                                          "not 4; not a whole two-frame mprgp run; no readable resume.state"), reason)

    def test_the_scenes_own_whole_run_is_reused_until_the_scene_changes(self):
        self.write(WHOLE_RUN, ladder_reuse.content_hash(self.scene))
        self.assertEqual(ladder_reuse.stale_reason(self.sim, self.scene, 4), "")
        self.assertEqual(ladder_reuse.stale_reason(self.sim, self.scene, 5), "simulator version 4, not 5")
        os.utime(self.scene, None)  # touched after the simulation, content unchanged: still the same scene
        os.utime(self.sim, (2000, 2000))
        self.assertEqual(ladder_reuse.stale_reason(self.sim, self.scene, 4), "")
        with open(self.scene, "w", encoding="utf-8") as f:  # edited: another scene
            json.dump({"name": "density_10", "frames": 3}, f)
        self.assertEqual(ladder_reuse.stale_reason(self.sim, self.scene, 4), "the scene file changed since")

    def test_a_resume_state_of_another_format_is_stale(self):
        self.write(WHOLE_RUN)
        with open(os.path.join(self.tmp, "resume.state"), "wb") as f:
            f.write(b"cb-resume 0\n{}\n")
        self.assertEqual(ladder_reuse.stale_reason(self.sim, self.scene, 4),
                         "no readable resume.state to compare the scene with (not a resume state of this version)")

    def test_the_content_hash_is_the_fnv1a_of_the_bytes(self):
        path = os.path.join(self.tmp, "a.txt")
        with open(path, "wb") as f:
            f.write(b"a")
        self.assertEqual(ladder_reuse.content_hash(path), "af63dc4c8601ec8c")  # FNV-1a 64 of "a" (published)

    def test_the_binary_says_its_simulator_version(self):
        out = subprocess.run([CB, "--version", "--json"], capture_output=True, text=True, check=True).stdout
        self.assertIsInstance(json.loads(out)["simulator_version"], int)

    def test_a_real_simulation_is_recognised_by_its_scene_content(self):
        scene = os.path.join(self.tmp, "tiny.json")
        with open(scene, "w", encoding="utf-8") as f:
            json.dump({"name": "tiny", "h": 0.01, "frames": 2,
                       "bodies": [{"box": {"cells": [2, 2, 2], "size": [0.2, 0.2, 0.2]}, "translate": [0, 0.11, 0],
                                   "velocity": [0, -1, 0]}],
                       "obstacles": [{"type": "plane", "normal": [0, 1, 0], "point": [0, 0, 0]}]}, f)
        out = os.path.join(self.tmp, "sim")
        subprocess.run([CB, "simulate", scene, "--frames", "2", "--out", out, "--solver", "mprgp"],
                       capture_output=True, text=True, check=True)
        version = json.loads(subprocess.run([CB, "--version", "--json"], capture_output=True, text=True,
                                            check=True).stdout)["simulator_version"]
        record = os.path.join(out, "simulation.json")
        self.assertEqual(ladder_reuse.stale_reason(record, scene, version), "")
        os.utime(scene, None)
        os.utime(record, (2000, 2000))  # the scene file is newer, as in a fresh clone
        self.assertEqual(ladder_reuse.stale_reason(record, scene, version), "")


if __name__ == "__main__":
    unittest.main()
