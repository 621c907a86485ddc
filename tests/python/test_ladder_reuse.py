"""tools/ladder.sh reuses a cached simulation folder only when it is the scene's own (R9 of the
hostile audit: any folder holding a simulation.json was reused, whatever its scene or version)."""
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


class TestLadderReuse(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.mkdtemp(prefix="cb_ladder_")
        self.scene = os.path.join(self.tmp, "density_10.json")
        with open(self.scene, "w", encoding="utf-8") as f:
            json.dump({"name": "density_10", "frames": 2}, f)
        os.utime(self.scene, (1000, 1000))
        self.sim = os.path.join(self.tmp, "simulation.json")

    def tearDown(self):
        shutil.rmtree(self.tmp, ignore_errors=True)

    def write(self, record):
        with open(self.sim, "w", encoding="utf-8") as f:
            json.dump(record, f)

    def test_a_planted_folder_is_stale(self):
        self.write({"scene": "not this one", "simulator_version": "0-stale"})
        self.assertEqual(ladder_reuse.stale_reason(self.sim, self.scene, 4),
                         "scene 'not this one', not 'density_10'; simulator version '0-stale', not 4; "
                         "not a whole two-frame mprgp run")

    def test_the_scenes_own_whole_run_is_reused_until_the_scene_changes(self):
        self.write({"scene": "density_10", "simulator_version": 4, "frames_done": 2, "blow_up": False,
                    "solver": "mprgp"})
        self.assertEqual(ladder_reuse.stale_reason(self.sim, self.scene, 4), "")
        self.assertEqual(ladder_reuse.stale_reason(self.sim, self.scene, 5), "simulator version 4, not 5")
        os.utime(self.scene, None)  # edited now, after the simulation
        os.utime(self.sim, (2000, 2000))
        self.assertEqual(ladder_reuse.stale_reason(self.sim, self.scene, 4), "the scene file changed since")

    def test_the_binary_says_its_simulator_version(self):
        binary = os.environ.get("CB_CONTACTBENCH") or os.path.join(ROOT, "build", "bin", "contactbench")
        out = subprocess.run([binary, "--version", "--json"], capture_output=True, text=True, check=True).stdout
        self.assertIsInstance(json.loads(out)["simulator_version"], int)


if __name__ == "__main__":
    unittest.main()
