"""A claim of the paper set beside the authors' data and our measurement, with a computed verdict.

The record (docs/work.md "Claims" describes every field): what the claim says and where, the
problem it is judged on, the judged quantity's estimate with its interval and threshold, and the
verdict with its reason. A figure script (or another module: the decoupling and scale figures add
their rows the same way) fills a Claim and hands it to the report through FigureOutcome.claims.

Verdicts, one vocabulary for the whole report:
- holds / does not hold: decided; for a timed quantity only when its whole interval is on one
  side of the threshold;
- holds only as published / holds only on native residuals: the fair reading does not hold (or
  was not measured) while the authors' setting or measure does;
- inconclusive: measured, but the interval straddles the threshold (or there is one timing only):
  `reason` says which;
- not measured: nothing to judge on (no runs, or no case that exercises the claim, e.g. no frame
  with contact rows in QUICK): `reason` says why;
- inconclusive (quick): quick mode only, a verdict a full run could reverse (its interval or count
  within QUICK_MARGIN of the threshold, or a figure's own reason: resolutions too close, a final
  error crossing its level by a hair): `reason` says which, and what the quick run found.
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field
from typing import Iterable, List, Optional

from plots.intervals import CONFIDENCE, median_interval, min_rounds

HOLDS = "holds"
HOLDS_AS_PUBLISHED = "holds only as published"
HOLDS_NATIVE_ONLY = "holds only on native residuals"
DOES_NOT_HOLD = "does not hold"
INCONCLUSIVE = "inconclusive"
NOT_MEASURED = "not measured"
INCONCLUSIVE_QUICK = "inconclusive (quick)"
#: every verdict a claim row may carry
VERDICTS = (HOLDS, HOLDS_AS_PUBLISHED, HOLDS_NATIVE_ONLY, DOES_NOT_HOLD, INCONCLUSIVE, NOT_MEASURED, INCONCLUSIVE_QUICK)
#: verdicts that decide the claim one way or the other (quick mode may withdraw them)
DECIDED = (HOLDS, HOLDS_AS_PUBLISHED, HOLDS_NATIVE_ONLY, DOES_NOT_HOLD)
#: quick mode: a decided quantity (its interval's nearer end, or a count) within this factor of its
#: threshold is one that a full run, on other problems (coarse stand-ins, few frames), could put on
#: the other side
QUICK_MARGIN = 1.25
#: how the threshold is read: the claim holds when the quantity is above it, or below it
ABOVE, BELOW = "above", "below"


@dataclass
class Judgement:
    """The verdict on one quantity, with what it rests on."""
    verdict: str
    estimate: Optional[float] = None        #: the point estimate (median over the rounds)
    interval: Optional[List[float]] = None  #: [low, high]; None for a deterministic count or one timing
    coverage: Optional[float] = None        #: the interval's exact coverage (intervals.py)
    samples: int = 0                        #: rounds (or values) behind the estimate
    reason: str = ""                        #: why inconclusive / not measured ("" when decided)

    def text(self, digits: int = 3) -> str:
        """"6.2x [5.1, 7.4] (5 rounds)" style, for the `ours` column."""
        if self.estimate is None or not math.isfinite(self.estimate):
            return "—"
        out = f"{self.estimate:.{digits}g}"
        if self.interval is not None:
            out += f" [{self.interval[0]:.{digits}g}, {self.interval[1]:.{digits}g}]"
        return out


@dataclass
class Claim:
    """One row of the report's claims table. Numbers are computed; `paper` quotes paper.txt."""
    key: str                    #: stable id, e.g. "fig6-decoupling"
    claim: str                  #: the claim in words
    source: str                 #: where the paper says it (section / figure)
    paper: str                  #: the paper's number or words
    authors: str = "—"          #: what the authors' data (`make paper-data`) shows
    ours: str = "—"             #: what we measured (estimates with their intervals)
    verdict: str = NOT_MEASURED  #: one of VERDICTS
    rule: str = ""              #: how the verdict was computed (threshold, interval, which reading decides)
    notes: List[str] = field(default_factory=list)
    judged_on: str = ""         #: the problem(s) and measure the verdict is judged on, and the cases left out
    estimate: Optional[float] = None         #: the deciding quantity's point estimate
    interval: Optional[List[float]] = None   #: its interval [low, high] (timed quantities)
    coverage: Optional[float] = None         #: the interval's coverage
    threshold: Optional[float] = None        #: the value the quantity is compared with
    direction: str = ABOVE      #: ABOVE: holds when the quantity is above the threshold; BELOW: below
    samples: int = 0            #: rounds behind the estimate (0: a deterministic count)
    reason: str = ""            #: why the verdict is inconclusive or not measured

    def to_dict(self) -> dict:
        return asdict(self)

    def decided_by(self, judgement: Judgement, threshold: float, direction: str = ABOVE) -> "Claim":
        """Copies a judgement's numbers (and reason) into the row; the verdict is set by the caller,
        which may combine several readings (combine_published_fair)."""
        self.estimate, self.interval, self.coverage = judgement.estimate, judgement.interval, judgement.coverage
        self.samples, self.threshold, self.direction = judgement.samples, threshold, direction
        if judgement.reason and not self.reason:
            self.reason = judgement.reason
        return self


def _ok(x) -> bool:
    return x is not None and not (isinstance(x, float) and math.isnan(x))


def _side(low: float, high: float, threshold: float, direction: str) -> str:
    above = direction == ABOVE
    if low > threshold:
        return HOLDS if above else DOES_NOT_HOLD
    if high < threshold:
        return DOES_NOT_HOLD if above else HOLDS
    return INCONCLUSIVE


def verdict_interval(low: Optional[float], high: Optional[float], threshold: float, direction: str = ABOVE) -> str:
    """holds / does not hold when [low, high] is wholly on one side of the threshold (strictly),
    inconclusive when it straddles it, not measured without numbers."""
    if not _ok(low) or not _ok(high):
        return NOT_MEASURED
    return _side(float(low), float(high), threshold, direction)


def judge_rounds(values: Iterable[Optional[float]], threshold: float, direction: str = ABOVE,
                 confidence: float = CONFIDENCE, lower_bounds: Iterable[bool] = ()) -> Judgement:
    """The verdict on a timed quantity from one value per interleaved round (NaN/None = not
    measured in that round). `lower_bounds[i]` marks a value that is only a lower bound (a solver
    that never reached the level: its whole run time); then only "above" can be decided."""
    vals = [None if v is None else float(v) for v in values]
    bounds = list(lower_bounds) + [False] * (len(vals) - len(list(lower_bounds)))
    finite = [v for v in vals if v is not None and math.isfinite(v)]
    if not finite:
        return Judgement(NOT_MEASURED, samples=0, reason="no round measured the quantity")
    missing = len(vals) - len(finite)
    iv = median_interval(finite, confidence)
    if iv is None:
        est = sorted(finite)[len(finite) // 2]
        return Judgement(INCONCLUSIVE, estimate=est, samples=len(finite),
                         reason=f"{len(finite)} round(s) measured it ({min_rounds(confidence)} needed for a "
                                f"{100 * confidence:.0f}% interval)" + (f"; {missing} round(s) did not" if missing else ""))
    verdict = _side(iv.low, iv.high, threshold, direction)
    reason = ""
    has_bound = any(b for v, b in zip(vals, bounds) if v is not None and math.isfinite(v))
    if has_bound and verdict != (HOLDS if direction == ABOVE else DOES_NOT_HOLD):
        verdict = INCONCLUSIVE  # a lower bound below the threshold says nothing about the value
        reason = "some rounds give only a lower bound (the slower solver never reached the level) below the threshold"
    elif verdict == INCONCLUSIVE:
        reason = (f"the {100 * iv.coverage:.1f}% interval [{iv.low:.3g}, {iv.high:.3g}] straddles the threshold "
                  f"{threshold:g}")
    return Judgement(verdict, estimate=iv.estimate, interval=[iv.low, iv.high], coverage=iv.coverage,
                     samples=iv.samples, reason=reason)


def judge_count(value: Optional[float], threshold: float, direction: str = ABOVE, inclusive: bool = True,
                reason_missing: str = "no measurement") -> Judgement:
    """The verdict on a deterministic quantity (iterations, counters): no interval is needed, the
    same input gives the same count. inclusive: the threshold itself counts as holding."""
    if not _ok(value) or not math.isfinite(float(value)):
        return Judgement(NOT_MEASURED, reason=reason_missing)
    v = float(value)
    ok = (v >= threshold if inclusive else v > threshold) if direction == ABOVE else \
        (v <= threshold if inclusive else v < threshold)
    return Judgement(HOLDS if ok else DOES_NOT_HOLD, estimate=v, samples=1)


def combine_published_fair(published: str, fair: str, qualified: str = HOLDS_AS_PUBLISHED) -> str:
    """The row's verdict from the two readings: the fair reading decides; when it does not hold
    (or was not measured) and the published one holds, `qualified` ("holds only as published" or
    "holds only on native residuals"); an inconclusive fair reading stays inconclusive."""
    if fair == HOLDS:
        return HOLDS
    if fair == INCONCLUSIVE:
        return INCONCLUSIVE
    if published == HOLDS:
        return qualified
    if fair == NOT_MEASURED:
        return published if published in (DOES_NOT_HOLD, INCONCLUSIVE) else NOT_MEASURED
    return DOES_NOT_HOLD


def combined_reason(published: Judgement, fair: Judgement) -> str:
    """The reason of a row judged on two readings: each reading's, named."""
    parts = [f"fair: {fair.reason}" if fair.reason else "", f"as published: {published.reason}" if published.reason else ""]
    return "; ".join(p for p in parts if p)


def withdraw_quick(claim: "Claim", reason: str) -> "Claim":
    """Quick mode: the row's decided verdict becomes "inconclusive (quick)", the reason naming why a
    full run could reverse it and what the quick run found."""
    if claim.verdict in DECIDED:
        claim.reason = f"{reason}; the quick run found '{claim.verdict}'"
        claim.verdict = INCONCLUSIVE_QUICK
    return claim


def quick_margin_guard(claim: "Claim", margin: float = QUICK_MARGIN) -> "Claim":
    """Quick mode, any row: a decided verdict whose deciding quantity (the interval's nearer end,
    else the estimate) lies within `margin`x of a positive threshold is withdrawn (withdraw_quick)."""
    if claim.verdict not in DECIDED or claim.threshold is None or not claim.threshold > 0:
        return claim
    values = list(claim.interval) if claim.interval is not None else \
        [claim.estimate] if claim.estimate is not None else []
    values = [float(v) for v in values if v is not None and math.isfinite(float(v)) and float(v) > 0]
    if not values:
        return claim
    nearest = min(max(v / claim.threshold, claim.threshold / v) for v in values)
    if nearest < margin:
        what = (f"the interval [{claim.interval[0]:.3g}, {claim.interval[1]:.3g}]" if claim.interval is not None
                else f"the count {claim.estimate:.3g}")
        withdraw_quick(claim, f"quick mode: {what} lies within {margin:g}x of the threshold {claim.threshold:g}, "
                              "a margin a full run could cross")
    return claim


def verdict_published_fair(published_ok: Optional[bool], fair_ok: Optional[bool]) -> str:
    """holds (fair comparison passes), holds only as published, does not hold, not measured."""
    if fair_ok is None and published_ok is None:
        return NOT_MEASURED
    if fair_ok:
        return HOLDS
    return HOLDS_AS_PUBLISHED if published_ok else DOES_NOT_HOLD


def verdict_threshold(value: Optional[float], threshold: float, greater: bool = True) -> str:
    """holds when value >= threshold (greater) or value <= threshold; not measured for NaN/None
    (a deterministic quantity; timed ones go through judge_rounds)."""
    return judge_count(value, threshold, ABOVE if greater else BELOW).verdict
