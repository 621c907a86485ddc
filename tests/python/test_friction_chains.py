"""plots/friction_chains.py: the drift table from constructed frictional chains (numbers checked by
hand), and a failing `contactbench chains` run reported with its exit status."""
import csv
import os
import sys
import tempfile
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "plots"))

import friction_chains  # noqa: E402

COLUMNS = ["frame", "chain", "solver", "status", "accuracy", "travel_rel", "drift_rel", "steps_not_solved"]


def write_chains(folder: str, chains: dict) -> None:
    """chains: label -> (solver, [(status, accuracy, travel_rel, drift_rel) per frame])."""
    os.makedirs(folder, exist_ok=True)
    with open(os.path.join(folder, "chains.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(COLUMNS)
        frames = max(len(rows) for _, rows in chains.values())
        for frame in range(frames):
            for label, (solver, rows) in chains.items():
                status, e, travel, drift = rows[frame]
                w.writerow([frame, label, solver, status, e, travel, drift, 0 if status == "converged" else 1])


class TableTest(unittest.TestCase):
    def test_drift_per_frame_is_the_end_over_the_frames(self):
        with tempfile.TemporaryDirectory() as tmp:
            write_chains(tmp, {
                "exact": ("nsgs", [("converged", 1e-10, 0.0, 0.0), ("converged", 2e-11, 1e-6, 0.0)]),
                "bmf03": ("mprgp+bmf03", [("stalled", 0.5, 0.1, 0.3), ("stalled", 0.25, 0.2, 0.2)]),
            })
            lines = friction_chains.table({"incline": tmp}).splitlines()
        self.assertEqual(len(lines), 4)
        self.assertEqual(lines[2], "| incline | 2 | exact (nsgs) | converged 2 | 1e-10 | 0 | 0 | 0 | 0.0001 |")
        # end drift 20%, largest 30%, per frame 20% / 2 frames, travel 20%
        self.assertEqual(lines[3], "| incline | 2 | bmf03 (mprgp+bmf03) | stalled 2 | 0.5 | 20 | 30 | 10 | 20 |")

    def test_a_failing_chains_run_is_reported_with_its_status(self):
        with tempfile.TemporaryDirectory() as tmp:
            fake = os.path.join(tmp, "cb")
            with open(fake, "w") as f:
                f.write("#!/bin/sh\necho 'scene.json: /mu: broken' >&2\nexit 2\n")
            os.chmod(fake, 0o755)
            rc = friction_chains.main(["scene.json", "--out", os.path.join(tmp, "out"), "--cb", fake])
            self.assertEqual(rc, 2)
            with open(os.path.join(tmp, "out", "scene.log")) as f:
                self.assertEqual(f.read(), "scene.json: /mu: broken\n")
            self.assertFalse(os.path.exists(os.path.join(tmp, "out", "friction_chains.md")))


if __name__ == "__main__":
    unittest.main()
