"""Small helpers shared by the plot scripts: saving figures, reading curves off histories."""
from __future__ import annotations

import math
import os
from typing import List

import matplotlib

if not os.environ.get("MPLBACKEND"):
    matplotlib.use("Agg")  # scripts run headless (make demo, CI)
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

#: accuracy tiers on the common relative KKT error (DESIGN.md "Metrics")
TIERS = (1e-2, 1e-4, 1e-6, 1e-8)


def save_figure(fig, folder: str, stem: str) -> List[str]:
    """Writes folder/stem.png and folder/stem.pdf; returns both paths."""
    os.makedirs(folder, exist_ok=True)
    paths = []
    for ext in ("png", "pdf"):
        path = os.path.join(folder, f"{stem}.{ext}")
        fig.savefig(path, dpi=110 if ext == "png" else None)
        paths.append(path)
    plt.close(fig)
    return paths


def positive(values) -> np.ndarray:
    """Values for a log axis: non-positive and non-finite entries become NaN (gaps, not lies)."""
    arr = np.asarray(values, dtype=float)
    arr = np.where(np.isfinite(arr) & (arr > 0), arr, np.nan)
    return arr


def first_reach(history: pd.DataFrame, column: str, threshold: float, x: str = "time_s") -> float:
    """The first value of x at which history[column] <= threshold, or NaN when never reached."""
    if history is None or history.empty or column not in history or x not in history:
        return float("nan")
    vals = pd.to_numeric(history[column], errors="coerce").to_numpy()
    xs = pd.to_numeric(history[x], errors="coerce").to_numpy()
    hit = np.nonzero(np.isfinite(vals) & (vals <= threshold))[0]
    return float(xs[hit[0]]) if hit.size else float("nan")


def settle_time(history: pd.DataFrame, column: str, threshold: float, x: str = "time_s") -> float:
    """The x from which history[column] stays <= threshold to the end, or NaN when the last value
    is above it. Unlike first_reach, a solver whose residual dips and rises again (ICA's
    stationarity is 0 at its unconstrained start) is not credited for the dip."""
    if history is None or history.empty or column not in history or x not in history:
        return float("nan")
    vals = pd.to_numeric(history[column], errors="coerce").to_numpy()
    xs = pd.to_numeric(history[x], errors="coerce").to_numpy()
    ok = np.isfinite(vals) & (vals <= threshold)
    if not ok[-1]:
        return float("nan")
    above = np.nonzero(~ok)[0]
    return float(xs[above[-1] + 1]) if above.size else float(xs[0])


def fmt(value, digits: int = 3) -> str:
    """A number for a table cell; NaN/None as an em dash."""
    if value is None:
        return "—"
    if isinstance(value, str):
        return value
    try:
        v = float(value)
    except (TypeError, ValueError):
        return str(value)
    if math.isnan(v):
        return "—"
    if math.isinf(v):
        return "∞" if v > 0 else "-∞"
    if v != 0 and (abs(v) < 1e-3 or abs(v) >= 1e5):
        return f"{v:.{digits - 1}e}"
    if float(v).is_integer() and abs(v) < 1e9:
        return str(int(v))
    return f"{v:.{digits}g}"


def grid(count: int, max_cols: int = 4):
    """(rows, cols) for `count` panels."""
    cols = max(1, min(max_cols, count))
    rows = max(1, math.ceil(count / cols))
    return rows, cols
