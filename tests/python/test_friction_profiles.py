"""The frictional suite's profiles and claim (plots/friction_profiles.py) on a small synthetic record set:
the profile values (share solved within tau), a failed run counted as failed, n/a runs out of the
denominator, the measure deciding what "solved" means, frictionless labels left out, and the claim row.

Run from tests/python: /usr/bin/python3 -m unittest test_friction_profiles
"""
import json
import os
import sys
import tempfile
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(os.path.dirname(HERE)))

from plots import claims, friction_profiles as fp  # noqa: E402


def record(snapshot, label, status, time_s, fclib, e, solver=None):
    return {"snapshot": {"id": snapshot}, "label": label, "solver": solver or label, "status": status,
            "solver_status": status, "iterations": 1, "time": {"total_s": time_s, "repeat": 1},
            "accuracy": {"max": e}, "fclib_error": fclib, "tol": 1e-8}


def write_folder(root, records):
    os.makedirs(os.path.join(root, "runs"), exist_ok=True)
    for r in records:
        with open(os.path.join(root, "runs", f"{r['snapshot']['id']}__{r['label']}.json"), "w") as f:
            json.dump(r, f)
    return root


#: P1: a 1 s, b 2 s; P2: a 4 s, b 1 s; P3: b is faster but stops at FCLIB error 1e-5 (failed by
#: FCLIB's measure, solved by e); P4: b does not apply. c is frictionless (solved_relaxation).
RECORDS = [
    record("P1", "a", "converged", 1.0, 1e-9, 1e-9), record("P1", "b", "converged", 2.0, 1e-9, 1e-9),
    record("P2", "a", "converged", 4.0, 1e-9, 1e-9), record("P2", "b", "converged", 1.0, 1e-9, 1e-9),
    record("P3", "a", "converged", 1.0, 1e-9, 1e-9), record("P3", "b", "max_iterations", 0.5, 1e-5, 1e-9),
    record("P4", "a", "converged", 2.0, 1e-9, 1e-9), record("P4", "b", "not_applicable", 0.0, None, None),
    record("P1", "c", "solved_relaxation", 0.1, 1e-3, 1e-3), record("P2", "c", "solved_relaxation", 0.1, 1e-3, 1e-3),
]


class TestFrictionProfiles(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory()
        self.runs = fp.read_records(write_folder(self.tmp.name, RECORDS))

    def tearDown(self):
        self.tmp.cleanup()

    def test_records_are_read_with_both_errors(self):
        p3b = self.runs[(self.runs["snapshot"] == "P3") & (self.runs["label"] == "b")].iloc[0]
        self.assertEqual((p3b["fclib"], p3b["e"]), (1e-5, 1e-9))
        self.assertAlmostEqual(p3b["time_s"], 0.5, places=12)  # the fixture's time, read back

    def test_profile_values_by_fclib_error_and_a_failed_run_counts_as_failed(self):
        runs = self.runs[self.runs["label"] != "c"]
        prof = fp.profile(runs, 1e-8, "fclib", [1.0, 2.0, 4.0, 1e6])
        # a: ratios P1 1, P2 4, P3 1, P4 1 over 4 problems
        self.assertEqual(list(prof["a"]), [0.75, 0.75, 1.0, 1.0])
        # b: ratios P1 2, P2 1, P3 failed (never counts, even at tau = 1e6); P4 n/a: 3 problems judged
        self.assertEqual(list(prof["b"]), [1 / 3, 2 / 3, 2 / 3, 2 / 3])

    def test_the_measure_decides_what_solved_means(self):
        runs = self.runs[self.runs["label"] != "c"]
        prof = fp.profile(runs, 1e-8, "e", [1.0, 2.0])
        # by e, b solved P3 in 0.5 s: best there, and a's 1 s is a ratio of 2
        self.assertEqual(list(prof["a"]), [0.5, 0.75])  # P1, P4 at 1; P3 at 2; P2 at 4
        self.assertEqual(list(prof["b"]), [2 / 3, 1.0])

    def test_frictionless_labels(self):
        self.assertEqual(fp.frictionless_labels(self.runs), ["c"])

    def claim(self, mprgp_times, siconos_times, mprgp_fclib=1e-9):
        rounds = []
        for tm, ts in zip(mprgp_times, siconos_times):
            recs = [record(p, "mprgp-x", "converged", tm, mprgp_fclib, 1e-9) for p in ("F1", "F2")]
            recs += [record(p, "siconos-y", "converged", ts, 1e-9, 1e-9) for p in ("F1", "F2")]
            recs += [record(p, "siconos-z", "converged", 3 * ts, 1e-9, 1e-9) for p in ("F1", "F2")]
            # a frictionless MPRGP, fastest and below tol on F1: no candidate of the MPRGP side
            recs += [record("F1", "mprgp-coupled", "solved_relaxation", 1e-3, 1e-9, 1e-9, solver="mprgp-coupled"),
                     record("F2", "mprgp-coupled", "solved_relaxation", 1e-3, 1e-3, 1e-3, solver="mprgp-coupled")]
            with tempfile.TemporaryDirectory() as d:
                rounds.append(fp.read_records(write_folder(d, recs)))
        return fp.claim_row(rounds, 1e-8, "fclib", ["F1", "F2"], penalty=10.0, shift=0.0, problems_text="F1, F2")

    def test_claim_holds_when_every_round_is_faster_than_the_best_siconos(self):
        c = self.claim([0.5, 0.4, 0.6, 0.5, 0.45], [1.0] * 5)
        self.assertEqual(c.verdict, claims.HOLDS)
        self.assertAlmostEqual(c.estimate, 0.5)
        self.assertEqual(c.interval, [0.4, 0.6])
        self.assertIn("mprgp-x / siconos-y", c.ours)  # the best Siconos label, not siconos-z

    def test_claim_is_inconclusive_when_the_interval_straddles_one(self):
        self.assertEqual(self.claim([0.5, 0.9, 1.1, 1.2, 0.8], [1.0] * 5).verdict, claims.INCONCLUSIVE)

    def test_claim_with_mprgp_failing_the_tolerance_does_not_hold(self):
        c = self.claim([0.1] * 5, [1.0] * 5, mprgp_fclib=1e-6)  # fast, but never at 1e-8: penalty 10 s
        self.assertEqual(c.verdict, claims.DOES_NOT_HOLD)
        self.assertAlmostEqual(c.estimate, 10.0)

    def test_claim_with_too_few_rounds_is_inconclusive(self):
        c = self.claim([0.5] * 3, [1.0] * 3)
        self.assertEqual(c.verdict, claims.INCONCLUSIVE)
        self.assertIn("5 needed", c.reason)


if __name__ == "__main__":
    unittest.main()
