"""An interval for a timed quantity measured in repeated, interleaved rounds (docs/work.md "Claims").

A timing on a shared machine moves with the load; the ratio of two solvers' times measured in the
same round (one right after the other, the order alternating between rounds) moves much less, but
still moves. The rounds give R values of the judged quantity (e.g. a time ratio); the interval is
the distribution-free confidence interval of their median from order statistics: with the values
sorted, [x_(k), x_(R+1-k)] holds the median with probability 1 - 2 P(Binomial(R, 1/2) < k), for
any distribution of the noise. It is the bootstrap's answer without its resampling noise: the same
values always give the same interval, so the same runs always give the same verdict.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Iterable, Optional

#: the coverage an interval must have at least (with 5 rounds: [min, max], 93.75%)
CONFIDENCE = 0.9


def median_coverage(rounds: int, k: int) -> float:
    """P(x_(k) <= median <= x_(rounds+1-k)) for `rounds` independent values of any continuous law."""
    below = sum(math.comb(rounds, i) for i in range(k)) / 2.0 ** rounds
    return 1.0 - 2.0 * below


def min_rounds(confidence: float = CONFIDENCE) -> int:
    """The fewest rounds whose [min, max] reaches `confidence` (5 for 0.9)."""
    r = 1
    while median_coverage(r, 1) < confidence:
        r += 1
    return r


@dataclass
class MedianInterval:
    estimate: float        #: the median of the values
    low: float
    high: float
    coverage: float        #: the exact coverage of [low, high] (>= the confidence asked for)
    samples: int           #: the finite values used


def median_interval(values: Iterable[float], confidence: float = CONFIDENCE) -> Optional[MedianInterval]:
    """The median of the finite values and the narrowest order-statistic interval with coverage >=
    `confidence`; None when there are too few values for that coverage (min_rounds)."""
    v = sorted(float(x) for x in values if x is not None and math.isfinite(float(x)))
    r = len(v)
    if r == 0 or median_coverage(r, 1) < confidence:
        return None
    k = 1
    while k + 1 <= (r + 1) // 2 and median_coverage(r, k + 1) >= confidence:
        k += 1
    mid = r // 2
    estimate = v[mid] if r % 2 else 0.5 * (v[mid - 1] + v[mid])
    return MedianInterval(estimate, v[k - 1], v[r - k], median_coverage(r, k), r)
