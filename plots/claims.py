"""A claim of the paper set beside the authors' data and our measurement, with a computed verdict."""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field
from typing import List, Optional

HOLDS = "holds"
HOLDS_AS_PUBLISHED = "holds only as published"
HOLDS_NATIVE_ONLY = "holds only on native residuals"
DOES_NOT_HOLD = "does not hold"
NOT_MEASURED = "not measured"


@dataclass
class Claim:
    """One row of the report's claims table. Numbers are computed; `paper` quotes paper.txt."""
    key: str                    #: stable id, e.g. "fig6-decoupling"
    claim: str                  #: the claim in words
    source: str                 #: where the paper says it (section / figure)
    paper: str                  #: the paper's number or words
    authors: str = "—"          #: what the authors' data (`make paper-data`) shows
    ours: str = "—"             #: what we measured
    verdict: str = NOT_MEASURED
    rule: str = ""              #: how the verdict was computed
    notes: List[str] = field(default_factory=list)

    def to_dict(self) -> dict:
        return asdict(self)


def _ok(x) -> bool:
    return x is not None and not (isinstance(x, float) and math.isnan(x))


def verdict_published_fair(published_ok: Optional[bool], fair_ok: Optional[bool]) -> str:
    """holds (fair comparison passes), holds only as published, does not hold, not measured."""
    if fair_ok is None and published_ok is None:
        return NOT_MEASURED
    if fair_ok:
        return HOLDS
    if fair_ok is None:
        return HOLDS_AS_PUBLISHED if published_ok else DOES_NOT_HOLD
    return HOLDS_AS_PUBLISHED if published_ok else DOES_NOT_HOLD


def verdict_threshold(value: Optional[float], threshold: float, greater: bool = True) -> str:
    """holds when value >= threshold (greater) or value <= threshold; not measured for NaN/None."""
    if not _ok(value):
        return NOT_MEASURED
    ok = value >= threshold if greater else value <= threshold
    return HOLDS if ok else DOES_NOT_HOLD
