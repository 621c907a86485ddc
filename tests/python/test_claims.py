"""The verdict rules of plots/claims.py and the interval of plots/intervals.py, on synthetic timings.

Run from tests/python: /usr/bin/python3 -m unittest test_claims
"""
import math
import os
import random
import sys
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(os.path.dirname(HERE)))

from plots import claims, intervals  # noqa: E402


class TestQuickMargin(unittest.TestCase):
    """Quick mode withdraws a decided verdict a full run could reverse (issue 43)."""

    def claim(self, verdict, threshold, direction=claims.ABOVE, estimate=None, interval=None):
        return claims.Claim(key="k", claim="c", source="s", paper="p", verdict=verdict, threshold=threshold,
                            direction=direction, estimate=estimate, interval=interval)

    def test_an_interval_near_its_threshold_is_withdrawn_with_the_reason(self):
        c = claims.quick_margin_guard(self.claim(claims.HOLDS, 1.0, estimate=1.2, interval=[1.1, 1.3]))
        self.assertEqual(c.verdict, claims.INCONCLUSIVE_QUICK)
        self.assertEqual(c.reason, "quick mode: the interval [1.1, 1.3] lies within 1.25x of the threshold 1, a margin "
                                   "a full run could cross; the quick run found 'holds'")
        below = claims.quick_margin_guard(self.claim(claims.DOES_NOT_HOLD, 10.0, estimate=8.5, interval=[8.2, 9.0]))
        self.assertEqual(below.verdict, claims.INCONCLUSIVE_QUICK)  # 10 / 9.0 = 1.11

    def test_a_wide_margin_a_count_and_undecided_rows(self):
        wide = claims.quick_margin_guard(self.claim(claims.HOLDS, 1.0, estimate=3.0, interval=[2.0, 4.0]))
        self.assertEqual(wide.verdict, claims.HOLDS)
        count = claims.quick_margin_guard(self.claim(claims.HOLDS, 40, claims.BELOW, estimate=38))
        self.assertEqual(count.verdict, claims.INCONCLUSIVE_QUICK)
        self.assertIn("the count 38 lies within 1.25x of the threshold 40", count.reason)
        for verdict in (claims.INCONCLUSIVE, claims.NOT_MEASURED):
            self.assertEqual(claims.quick_margin_guard(self.claim(verdict, 1.0, estimate=1.01)).verdict, verdict)
        self.assertIn(claims.INCONCLUSIVE_QUICK, claims.VERDICTS)


class TestMedianInterval(unittest.TestCase):
    def test_coverage_by_hand(self):
        # 5 rounds: P(all 5 on one side of the median) = 2 / 32, so [min, max] covers it with 30/32
        self.assertAlmostEqual(intervals.median_coverage(5, 1), 0.9375)
        self.assertAlmostEqual(intervals.median_coverage(4, 1), 0.875)
        # 10 rounds, k = 2: 1 - 2 (1 + 10) / 1024
        self.assertAlmostEqual(intervals.median_coverage(10, 2), 1 - 22 / 1024)
        self.assertEqual(intervals.min_rounds(0.9), 5)

    def test_interval_of_five_and_of_ten(self):
        iv = intervals.median_interval([3.0, 1.0, 2.0, 5.0, 4.0])
        self.assertEqual((iv.estimate, iv.low, iv.high, iv.samples), (3.0, 1.0, 5.0, 5))
        iv = intervals.median_interval(range(1, 11))  # k = 2 keeps coverage 0.979 >= 0.9; k = 3: 0.891
        self.assertEqual((iv.low, iv.high, iv.estimate), (2.0, 9.0, 5.5))
        self.assertAlmostEqual(iv.coverage, 1 - 22 / 1024)

    def test_eight_rounds_leave_out_one_outlier_each_side(self):
        iv = intervals.median_interval(range(1, 9))  # k = 2: 1 - 2 * 9 / 256 = 0.93; k = 3: 0.71
        self.assertEqual((iv.low, iv.high), (2.0, 7.0))
        self.assertAlmostEqual(iv.coverage, 1 - 18 / 256)
        # one round caught by a load spike (30x) does not widen the interval of eight
        spiked = [6.0, 6.5, 7.0, 6.8, 6.2, 7.1, 6.4, 30.0]
        self.assertEqual(claims.judge_rounds(spiked, 10.0).verdict, claims.DOES_NOT_HOLD)
        self.assertEqual(claims.judge_rounds(spiked[3:], 10.0).verdict, claims.INCONCLUSIVE)  # five: [min, max]

    def test_too_few_and_nan_values(self):
        self.assertIsNone(intervals.median_interval([1.0, 2.0, 3.0, 4.0]))
        self.assertIsNone(intervals.median_interval([1.0, float("nan"), 2.0, 3.0, None, 4.0]))

    def test_empirical_coverage_of_the_median(self):
        # lognormal timing noise: the interval holds the true median (1.0) in >= 90% of 2000 trials
        rng = random.Random(7)
        hits = 0
        for _ in range(2000):
            iv = intervals.median_interval([math.exp(rng.gauss(0.0, 0.5)) for _ in range(5)])
            hits += iv.low <= 1.0 <= iv.high
        self.assertGreaterEqual(hits / 2000, 0.91)


class TestJudgeRounds(unittest.TestCase):
    def test_straddling_timings_are_inconclusive(self):
        # ratios around 1.1 from five interleaved rounds: the interval [0.9, 1.3] straddles 1.1
        j = claims.judge_rounds([0.9, 1.05, 1.12, 1.2, 1.3], 1.1)
        self.assertEqual(j.verdict, claims.INCONCLUSIVE)
        self.assertEqual(j.interval, [0.9, 1.3])
        self.assertEqual(j.estimate, 1.12)
        self.assertIn("straddles the threshold 1.1", j.reason)
        self.assertIn("93.8% interval [0.9, 1.3]", j.reason)

    def test_one_side_decides(self):
        self.assertEqual(claims.judge_rounds([5.0, 6.0, 7.0, 5.5, 6.5], 1.1).verdict, claims.HOLDS)
        self.assertEqual(claims.judge_rounds([0.5, 0.6, 0.7, 0.55, 0.65], 1.1).verdict, claims.DOES_NOT_HOLD)
        below = claims.judge_rounds([0.5, 0.6, 0.7, 0.55, 0.65], 1.0, claims.BELOW)
        self.assertEqual(below.verdict, claims.HOLDS)
        # the threshold itself inside the interval's end is not "one side"
        self.assertEqual(claims.judge_rounds([1.1, 2, 3, 4, 5], 1.1).verdict, claims.INCONCLUSIVE)

    def test_same_ratios_in_another_order_give_the_same_verdict(self):
        values = [0.697, 1.2, 1.02, 0.95, 1.1]
        first = claims.judge_rounds(values, 1.0)
        for seed in range(5):
            shuffled = values[:]
            random.Random(seed).shuffle(shuffled)
            again = claims.judge_rounds(shuffled, 1.0)
            self.assertEqual((again.verdict, again.interval, again.estimate),
                             (first.verdict, first.interval, first.estimate))

    def test_noisy_rounds_rarely_land_on_the_wrong_side(self):
        # a true ratio of 1.05 near the threshold 1.0, 20% noise per round: the five-round verdict
        # is wrong ("does not hold") only when all five rounds fall below the median, 1/32 of the
        # time at most; mostly it says "inconclusive"
        rng = random.Random(3)
        counts = {}
        trials = 2000
        for _ in range(trials):
            v = claims.judge_rounds([1.05 * math.exp(rng.gauss(0, 0.2)) for _ in range(5)], 1.0).verdict
            counts[v] = counts.get(v, 0) + 1
        self.assertGreater(counts.get(claims.INCONCLUSIVE, 0) / trials, 0.85)
        self.assertLessEqual(counts.get(claims.DOES_NOT_HOLD, 0) / trials, 1 / 32)
        # a true ratio 3x above its threshold is decided every time
        far = {claims.judge_rounds([3.0 * math.exp(rng.gauss(0, 0.2)) for _ in range(5)], 1.0).verdict
               for _ in range(500)}
        self.assertEqual(far, {claims.HOLDS})

    def test_missing_rounds_and_single_timing(self):
        j = claims.judge_rounds([2.0], 1.0)
        self.assertEqual(j.verdict, claims.INCONCLUSIVE)
        self.assertIn("1 round(s) measured it (5 needed for a 90% interval)", j.reason)
        j = claims.judge_rounds([2.0, float("nan"), 2.1, None, 2.2], 1.0)
        self.assertEqual(j.verdict, claims.INCONCLUSIVE)
        self.assertIn("2 round(s) did not", j.reason)
        j = claims.judge_rounds([float("nan")] * 5, 1.0)
        self.assertEqual((j.verdict, j.reason), (claims.NOT_MEASURED, "no round measured the quantity"))

    def test_lower_bounds_decide_only_above(self):
        # ICA never reached the level in two rounds: those ratios are lower bounds
        bounds = [False, True, False, True, False]
        self.assertEqual(claims.judge_rounds([12, 11, 13, 14, 15], 10, lower_bounds=bounds).verdict, claims.HOLDS)
        j = claims.judge_rounds([2, 3, 2.5, 3.5, 2.2], 10, lower_bounds=bounds)
        self.assertEqual(j.verdict, claims.INCONCLUSIVE)
        self.assertIn("lower bound", j.reason)


class TestCombine(unittest.TestCase):
    def test_published_and_fair(self):
        c = claims.combine_published_fair
        self.assertEqual(c(claims.DOES_NOT_HOLD, claims.HOLDS), claims.HOLDS)
        self.assertEqual(c(claims.HOLDS, claims.DOES_NOT_HOLD), claims.HOLDS_AS_PUBLISHED)
        self.assertEqual(c(claims.HOLDS, claims.NOT_MEASURED), claims.HOLDS_AS_PUBLISHED)
        self.assertEqual(c(claims.HOLDS, claims.INCONCLUSIVE), claims.INCONCLUSIVE)
        self.assertEqual(c(claims.INCONCLUSIVE, claims.DOES_NOT_HOLD), claims.DOES_NOT_HOLD)
        self.assertEqual(c(claims.NOT_MEASURED, claims.NOT_MEASURED), claims.NOT_MEASURED)
        self.assertEqual(c(claims.HOLDS, claims.DOES_NOT_HOLD, claims.HOLDS_NATIVE_ONLY), claims.HOLDS_NATIVE_ONLY)

    def test_counts_are_deterministic(self):
        self.assertEqual(claims.judge_count(0.95, 0.9).verdict, claims.HOLDS)
        self.assertEqual(claims.judge_count(40, 40, claims.BELOW).verdict, claims.HOLDS)
        j = claims.judge_count(float("nan"), 0.9, reason_missing="no frame with contact rows")
        self.assertEqual((j.verdict, j.reason), (claims.NOT_MEASURED, "no frame with contact rows"))

    def test_claim_record_carries_the_judgement(self):
        j = claims.judge_rounds([5.0, 6.0, 7.0, 5.5, 6.5], 1.1)
        c = claims.Claim(key="k", claim="c", source="s", paper="p", judged_on="frames with contact rows",
                         verdict=j.verdict).decided_by(j, 1.1)
        d = c.to_dict()
        self.assertEqual((d["estimate"], d["interval"], d["threshold"], d["samples"], d["direction"]),
                         (6.0, [5.0, 7.0], 1.1, 5, claims.ABOVE))
        self.assertAlmostEqual(d["coverage"], 0.9375)
        self.assertIn(d["verdict"], claims.VERDICTS)
        self.assertEqual(j.text(), "6 [5, 7]")


class TestClaimRulesOnConstructedRuns(unittest.TestCase):
    def test_fig8_measures_a_relaxation_against_its_own_optimum(self):
        import pandas as pd
        from plots import fig8
        # decoupled mprgp: its objective passes through the coupled QP's F* = -1 at iteration 2 and
        # settles at its own optimum -1.2; against -1 it would "reach 1e-4" at the crossing
        h = pd.DataFrame({"iteration": [0, 1, 2, 3, 4], "objective": [0.0, -0.8, -1.0, -1.19, -1.2]})
        run = pd.Series({"status": "solved_relaxation", "solved_problem": "decoupled", "reference_objective": -1.0,
                         "objective": -1.2})
        f_star, source = fig8.own_optimum(run, h)
        self.assertEqual((f_star, source), (-1.2, "its decoupled QP's minimum"))
        err = fig8.relative_error(h["objective"], f_star)
        self.assertEqual(fig8.iterations_to(err, h["iteration"], 1e-4), 4)
        self.assertEqual(fig8.iterations_to(fig8.relative_error(h["objective"], -1.0), h["iteration"], 1e-4), 2)
        # a run that solved the original QP is measured against the reference
        orig = pd.Series({"status": "converged", "solved_problem": float("nan"), "reference_objective": -1.2,
                          "objective": -1.2})
        self.assertEqual(fig8.own_optimum(orig, h), (-1.2, "reference"))

    def test_fig8_fair_reading_counts_a_floor_as_not_reached(self):
        from plots import fig8
        j = fig8.fair_judgement(float("nan"), float("nan"), 7.4e-3, 5e-2)
        self.assertEqual(j.verdict, claims.NOT_MEASURED)
        self.assertIn("neither run brought e below 0.0001 on the original QP (final e: mprgp 0.0074", j.reason)
        only = fig8.fair_judgement(30, float("nan"), 1e-6, 5e-2)
        self.assertEqual(only.verdict, claims.HOLDS)
        self.assertIsNone(only.estimate)  # no ratio: not a made-up 0.0 in the claim row
        self.assertEqual(only.reason, "only mprgp brought e below 0.0001 on the original QP (30 iterations); "
                                      "cg-jacobi never did (final e 0.05)")
        self.assertEqual(fig8.fair_judgement(float("nan"), 40, 7.4e-3, 1e-6).verdict, claims.DOES_NOT_HOLD)
        self.assertEqual(fig8.fair_judgement(50, 40, 1e-6, 1e-6).verdict, claims.HOLDS)      # 1.25 <= 1.5
        self.assertEqual(fig8.fair_judgement(70, 40, 1e-6, 1e-6).verdict, claims.DOES_NOT_HOLD)  # 1.75

    def test_fig6_judges_only_frames_with_contact_both_solved(self):
        import pandas as pd
        from plots import fig6
        rows = []
        for frame, m in enumerate([0, 0, 5, 7]):
            for label, t, status in (("mprgp", 1.0, "converged" if m == 0 else "solved_relaxation"),
                                     ("coupled-fair", 3.0, "converged" if frame != 3 else "max_iterations")):
                rows.append({"snapshot": f"f{frame}", "label": label, "frame": frame, "m": m, "time_s": t,
                             "status": status, "accuracy": 0.01 if m else 1e-7})
        runs = pd.DataFrame(rows)
        frames, with_contact, left_out = fig6.judged_frames(runs, "coupled-fair")
        self.assertEqual((list(frames["snapshot"]), with_contact, left_out), (["f2"], 2, 1))
        self.assertEqual(fig6.time_ratio(runs, "coupled-fair"), (3.0, 1))
        no_contact = runs.assign(m=0)
        self.assertTrue(math.isnan(fig6.time_ratio(no_contact, "coupled-fair")[0]))

    def test_table1_says_which_frames_of_each_scene_it_judged(self):
        from plots import table1
        rows = [{"scene": "longcube", "runs": 20, "frames_run": 20, "frames": 100, "contact_runs": 8},
                {"scene": "bunny_glass"}]  # not run: not listed
        self.assertEqual(table1.frames_run(rows), "longcube: 20 of 100 frames, 8 with contact")


if __name__ == "__main__":
    unittest.main()
