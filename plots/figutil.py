"""Small helpers shared by the plot scripts: saving figures, reading curves off histories, and the
figure rules every script follows (docs/work.md "Figures"): one colour and marker per solver in
every figure, one legend outside the panels, the tol line, failed runs marked, n and m in panel
titles, relaxations named in the legend."""
from __future__ import annotations

import math
import os
import sys
import textwrap
import zlib
from typing import Dict, Iterable, List, Optional

import matplotlib

if not os.environ.get("MPLBACKEND"):
    matplotlib.use("Agg")  # scripts run headless (make demo, CI)
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

#: tiers of the accuracy error e, the common measure (docs/accuracy.md; DESIGN.md "Metrics")
TIERS = (1e-2, 1e-4, 1e-6, 1e-8)


#: figures are saved at this resolution: a page column (figure_checks.COLUMN_WIDTH_IN) at 300 dpi
DPI = 300
# Text of every figure at least 7 pt at the printed size (figure_checks.MIN_FONT_PT).
matplotlib.rcParams.update({"font.size": 8, "axes.titlesize": 8, "axes.labelsize": 8, "xtick.labelsize": 7,
                            "ytick.labelsize": 7, "legend.fontsize": 7, "legend.title_fontsize": 7,
                            "figure.titlesize": 9})


def _finish(fig, folder: str, stem: str, tight: bool) -> None:
    """Before saving: overlapping tick labels thinned, then the figure rules checked
    (plots/figure_checks.py): a problem raises with CB_FIGURE_CHECKS=1, else it is printed."""
    try:  # figutil is imported both as plots.figutil and, by scripts run as files, as figutil
        from plots import figure_checks
    except ImportError:
        import figure_checks
    drawn = figure_checks.tidy_ticks(fig)
    found = figure_checks.problems(fig, tight=tight, drawn=drawn)
    if not found:
        return
    where = os.path.join(folder, stem)
    if os.environ.get("CB_FIGURE_CHECKS") == "1":
        plt.close(fig)
        raise figure_checks.FigureCheckError(f"{where}: " + "; ".join(found))
    for problem in found:
        print(f"figure check: {where}: {problem}", file=sys.stderr)


def save_figure(fig, folder: str, stem: str) -> List[str]:
    """Writes folder/stem.png (at DPI) and folder/stem.pdf; returns both paths."""
    os.makedirs(folder, exist_ok=True)
    _finish(fig, folder, stem, tight=False)
    paths = []
    for ext in ("png", "pdf"):
        path = os.path.join(folder, f"{stem}.{ext}")
        fig.savefig(path, dpi=DPI if ext == "png" else None)
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


def grid(count: int, max_cols: int = 2):
    """(rows, cols) for `count` panels (two columns fit a page column at 7 pt)."""
    cols = max(1, min(max_cols, count))
    rows = max(1, math.ceil(count / cols))
    return rows, cols


#: one colour and marker per registered solver (`contactbench solvers --json`), the same in every
#: figure. Colours: Okabe-Ito's colour-blind-safe palette, then Tol's, chosen one by one to stay
#: apart (CIELAB distance > 25 between any two; tests/python/test_plots.py) -- siconos-lemke's
#: old near-black brown beside bullet-dantzig's black was one such pair. Every solver also has a
#: marker of its own, so that no two solvers depend on colour alone.
SOLVER_STYLES: Dict[str, tuple] = {
    "mprgp": ("#0072B2", "o"),            # Okabe-Ito blue
    "mprgp-coupled": ("#E69F00", "s"),    # orange
    "mprgp-box": ("#009E73", "^"),        # bluish green
    "ica": ("#D55E00", "v"),              # vermillion
    "pgs": ("#CC79A7", "D"),              # reddish purple
    "active-set": ("#56B4E9", "P"),       # sky blue
    "cg": ("#555555", "p"),               # dark grey
    "ipopt": ("#332288", "*"),            # Tol indigo
    "siconos-lemke": ("#882255", "h"),    # Tol wine
    "siconos-nsn": ("#DDCC77", "<"),      # Tol sand
    "bullet-dantzig": ("#000000", ">"),   # black
    "tao-pdipm": ("#F0E442", "X"),        # Okabe-Ito yellow
    "tao-tron": ("#AA4499", "d"),         # Tol purple
    "nsgs-friction": ("#EE3377", "H"),    # Tol magenta
    # the frictional entries of issues 45/48: the plain markers are taken, so each has a letter
    "mprgp-tresca-fp": ("#8855FF", "$T$"),      # violet
    "mprgp+ica-friction": ("#445500", "$I$"),   # dark olive
    "siconos-fc3d-nsgs": ("#FF11FF", "$G$"),    # fuchsia
    "siconos-fc3d-nsn": ("#0000FF", "$N$"),     # blue
    "siconos-gfc3d-nsn": ("#00CC00", "$M$"),    # green
    "mprgp+bmf03": ("#7799FF", "$B$"),          # periwinkle
    "mprgp-staggered": ("#117777", "$S$"),      # dark teal
}
#: a label without a fixed style (a user's own solver or a `command` label) gets a (colour, marker)
#: pair of these lists, the first free one from a place chosen by a hash of its name: its colour is
#: at CIELAB distance > 20 from every fixed colour (a user's label once got a light blue beside
#: active-set's sky blue) and its marker is one no registered solver has. A label of a known solver
#: (e.g. "mprgp-ichol" of mprgp) keeps the solver's colour, takes a spare marker and a dashed line.
SPARE_MARKERS = ("8", "1", "2", "3", "4", "+", "|")
SPARE_COLOURS = ("#661100", "#BBBBBB", "#EE8866", "#997700", "#117733", "#CC6677", "#999933", "#004488")
_VARIANT_STYLES = ("--", ":", "-.", (0, (5, 1, 1, 1)))
#: styles given to labels without a fixed one in this process: no two labels share a pair
_ASSIGNED: Dict[str, dict] = {}


def _hash(name: str) -> int:
    return zlib.crc32(name.encode("utf-8"))


def solver_style(label: str, solver: Optional[str] = None) -> dict:
    """Matplotlib keyword arguments (color, marker, linestyle) of a solver label: the fixed style
    of SOLVER_STYLES for a solver's own name; else the first (colour, marker) pair not yet given
    to another label, searched from a place chosen by a hash of the label (the same pair every time
    unless two labels of one figure want the same one: assign_styles settles that by name order)."""
    if label in SOLVER_STYLES:
        colour, marker = SOLVER_STYLES[label]
        return {"color": colour, "marker": marker, "linestyle": "-"}
    if label in _ASSIGNED:
        return dict(_ASSIGNED[label])
    taken = {(s["color"], s["marker"]) for s in _ASSIGNED.values()}
    used_colours = {s["color"] for s in _ASSIGNED.values()}
    h = _hash(label)
    if solver in SOLVER_STYLES:
        colour = SOLVER_STYLES[solver][0]
        pairs = [(colour, SPARE_MARKERS[(h + k) % len(SPARE_MARKERS)]) for k in range(len(SPARE_MARKERS))]
        linestyle = _VARIANT_STYLES[h % len(_VARIANT_STYLES)]
    else:
        nc, nm = len(SPARE_COLOURS), len(SPARE_MARKERS)
        pairs = [(SPARE_COLOURS[(h + k) % nc], SPARE_MARKERS[((h >> 8) + k // nc) % nm]) for k in range(nc * nm)]
        fresh = [p for p in pairs if p[0] not in used_colours]  # a colour of its own while there is one
        pairs = fresh + pairs
        linestyle = "-"
    free = [p for p in pairs if p not in taken] or pairs
    style = {"color": free[0][0], "marker": free[0][1], "linestyle": linestyle}
    _ASSIGNED[label] = style
    return dict(style)


def assign_styles(labels: Iterable[str], solvers: Optional[Dict[str, str]] = None) -> Dict[str, dict]:
    """label -> style for the labels of one figure or page, distinct (colour, marker) pairs; the
    labels without a fixed style are settled in name order, so the result does not depend on the
    order the labels come in."""
    solvers = solvers or {}
    labels = list(dict.fromkeys(str(lab) for lab in labels))
    for lab in sorted(labels):
        solver_style(lab, solvers.get(lab))
    return {lab: solver_style(lab, solvers.get(lab)) for lab in labels}


#: solvers whose work the harness cannot count in full (docs/work.md, docs/peers.md): they are left
#: out of work-based figures (data profiles, convergence against work) with this note
WORK_NOT_COUNTED: Dict[str, str] = {
    "ipopt": "Ipopt's MUMPS factorisations and solves are not counted",
    "tao-pdipm": "MUMPS's factorisations inside TAO are not counted",
    "tao-tron": "the Krylov iterations inside PETSc's TRON are not counted",
    "siconos-lemke": "the pivots inside Siconos's Lemke are not counted (only forming W = J A^-1 J')",
    "siconos-nsn": "the Newton iterations inside Siconos are not counted (only forming W = J A^-1 J')",
    "bullet-dantzig": "the pivots inside Bullet's Dantzig solver are not counted (only forming W = J A^-1 J')",
    "command": "an external program works in its own process: its work is not counted (null in its record)",
}


def work_left_out(labels: Iterable[str], solvers: Dict[str, str]) -> Dict[str, str]:
    """label -> why its work is not counted, for the labels of WORK_NOT_COUNTED's solvers."""
    return {lab: WORK_NOT_COUNTED[solvers.get(lab, lab)] for lab in labels
            if solvers.get(lab, lab) in WORK_NOT_COUNTED}


def solver_colour(solver: str) -> str:
    """The fixed colour of a solver (SOLVER_STYLES; hashed for other names)."""
    return solver_style(solver)["color"]


def label_solvers(runs: pd.DataFrame) -> Dict[str, str]:
    """label -> solver name, from the runs table."""
    if runs is None or runs.empty or "label" not in runs or "solver" not in runs:
        return {}
    return {str(k): str(v) for k, v in runs.groupby("label", sort=False)["solver"].first().items()}


def display_label(label: str, runs: pd.DataFrame) -> str:
    """The legend text of a label: relaxations are named ("cg (J ignored: relaxation)"), so that a
    solver that did not solve the contact problem is not read as one that did."""
    if runs is None or runs.empty or "solved_problem" not in runs:
        return label
    solved = set(runs.loc[runs["label"] == label, "solved_problem"].dropna().astype(str))
    if "unconstrained" in solved:
        return f"{label} (J ignored: relaxation)"
    if "decoupled" in solved:
        return f"{label} (decoupled rows)"
    return label


def panel_title(snapshot: str, n=None, m=None, width: int = 40) -> str:
    """A panel title with the problem's size: "id (n = 375, m = 50)"."""
    name = snapshot if len(snapshot) < width else snapshot[:width - 3] + "..."
    size = []
    for key, value in (("n", n), ("m", m)):
        try:
            if value is not None and not math.isnan(float(value)):
                size.append(f"{key} = {int(value)}")
        except (TypeError, ValueError):
            pass
    return f"{name} ({', '.join(size)})" if size else name


def draw_tol(ax, tol, label: str = "tol") -> None:
    """The runs' tolerance as a horizontal line (an error axis)."""
    try:
        t = float(tol)
    except (TypeError, ValueError):
        return
    if math.isfinite(t) and t > 0:
        ax.axhline(t, color="black", lw=0.8, ls="--", alpha=0.6, label=f"{label} = {t:g}" if label == "tol" else label,
                   zorder=1)


def legend_outside(fig, axes: Iterable, title: Optional[str] = None, notes: Iterable = ()) -> None:
    """One legend for the whole figure, below the panels (entries of every panel, each once).
    `notes` are extra legend handles (e.g. the failed-run mark). Call after drawing, before saving."""
    handles, labels = [], []
    for ax in axes:
        for h, lab in zip(*ax.get_legend_handles_labels()):
            if lab not in labels and not lab.startswith("_"):
                handles.append(h)
                labels.append(lab)
    for h in notes:
        if h.get_label() not in labels:
            handles.append(h)
            labels.append(h.get_label())
    if not handles:
        return
    # below the panels, so that the figure keeps its page-column width (long entries wrapped)
    labels = [textwrap.fill(lab, 44) for lab in labels]
    widest = max(len(line) for lab in labels for line in lab.splitlines())
    cols = 3 if widest <= 30 else 2 if widest <= 44 else 1  # about 7 in of 7 pt text a row
    fig.legend(handles, labels, loc="upper center", bbox_to_anchor=(0.5, 0.0), fontsize=7, title=title,
               frameon=False, ncol=max(1, min(cols, len(handles))))


#: the one legend entry for the mark on a run whose status is not `converged` (every figure)
NOT_CONVERGED_LABEL = "x: status not `converged` (e above tol on the original QP, or stopped; final point)"
#: matplotlib keywords of that mark (drawn without a label: failed_mark() is its legend entry)
FAILED_MARK = {"color": "black", "marker": "x", "ls": "none", "markersize": 7, "zorder": 5}


def failed_mark(**kwargs):
    """The legend handle of the mark on runs that did not converge."""
    from matplotlib.lines import Line2D
    return Line2D([], [], label=NOT_CONVERGED_LABEL, **{**FAILED_MARK, **kwargs})


def save_figure_outside(fig, folder: str, stem: str) -> List[str]:
    """save_figure with the bounding box grown to hold a legend placed outside the panels."""
    os.makedirs(folder, exist_ok=True)
    _finish(fig, folder, stem, tight=True)
    paths = []
    for ext in ("png", "pdf"):
        path = os.path.join(folder, f"{stem}.{ext}")
        fig.savefig(path, dpi=DPI if ext == "png" else None, bbox_inches="tight")
        paths.append(path)
    plt.close(fig)
    return paths
