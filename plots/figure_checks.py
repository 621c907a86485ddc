"""What a referee checks in a figure (issue 46), measured on the drawn matplotlib figure.

problems(fig) lists, one line each: tick labels whose boxes intersect, a "0" (or 10^-inf) tick on a
log axis, an axis label without a unit (a bracket or parenthesis: "[s]", "(count)", "[1]"), text
smaller than MIN_FONT_PT, a figure wider than a page column (COLUMN_WIDTH_IN), and text outside
the figure (clipped) when the figure is saved without a tight bounding box.

tidy_ticks(fig) removes overlaps before saving: minor tick labels go first, then major ticks are
thinned. figutil's save functions call both; with CB_FIGURE_CHECKS=1 in the environment a problem
raises FigureCheckError (the figure tests and `make demo` use it), else problems are printed.
"""
from __future__ import annotations

import re
from typing import List

from matplotlib.ticker import LogLocator, MaxNLocator, NullFormatter

#: a page column at 300 dpi: figures are at most this wide (inches)
COLUMN_WIDTH_IN = 7.0
#: the smallest text at that size (points)
MIN_FONT_PT = 7.0
_UNIT = re.compile(r"\[[^\]]+\]|\([^)]+\)")
_NUMERIC = re.compile(r"^[$\\mathdefault{\s\-−+]*[0-9.]")
_ZERO = re.compile(r"^\$?(\\mathdefault\{)?(0|0\.0|10\^\{-\\infty\})\}?\$?$")


class FigureCheckError(Exception):
    """A figure breaks a rule of figure_checks (the message lists every problem)."""


def _tick_texts(axis):
    """The tick labels drawn: visible, not empty, at a tick inside the axis's view interval."""
    lo, hi = sorted(axis.get_view_interval())
    span = (hi - lo) * 1e-9
    out = []
    for tick in axis.get_major_ticks() + axis.get_minor_ticks():
        for label in (tick.label1, tick.label2):
            if label.get_visible() and label.get_text().strip() and lo - span <= tick.get_loc() <= hi + span:
                out.append(label)
    return out


def _overlaps(texts, renderer) -> List[tuple]:
    boxes = [(t, t.get_window_extent(renderer)) for t in texts]
    found = []
    for i in range(len(boxes)):
        for j in range(i + 1, len(boxes)):
            a, b = boxes[i][1], boxes[j][1]
            # touching is not overlapping: a pixel of slack for rounding
            if a.x0 < b.x1 - 1 and b.x0 < a.x1 - 1 and a.y0 < b.y1 - 1 and b.y0 < a.y1 - 1:
                found.append((boxes[i][0].get_text(), boxes[j][0].get_text()))
    return found


def _axes(fig):
    return [ax for ax in fig.axes if ax.get_visible() and ax.axison]


def tidy_ticks(fig) -> bool:
    """Removes overlapping tick labels: the minor labels of an axis first, then fewer major ticks.
    True when the figure is left as last drawn (no label removed in the last pass): problems() then
    needs no draw of its own."""
    for _ in range(3):
        fig.canvas.draw()
        renderer = fig.canvas.get_renderer()
        changed = False
        for ax in _axes(fig):
            for axis in (ax.xaxis, ax.yaxis):
                if not _overlaps(_tick_texts(axis), renderer):
                    continue
                changed = True
                minor = [t for t in _tick_texts(axis) if t in {k.label1 for k in axis.get_minor_ticks()}]
                if minor:
                    axis.set_minor_formatter(NullFormatter())
                elif axis.get_scale() == "log":
                    axis.set_major_locator(LogLocator(base=10, numticks=4))
                else:
                    axis.set_major_locator(MaxNLocator(nbins=4))
        if not changed:
            return True
    return False


def problems(fig, tight: bool = True, drawn: bool = False) -> List[str]:
    """Every rule the figure breaks (an empty list: none). drawn=True: the figure is unchanged since
    its last draw (tidy_ticks returned True), so that draw's text boxes are measured (a draw of a
    full-page figure costs ~0.1-0.3 s, and every saved figure passes here)."""
    if not drawn:
        fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    found = []
    width = fig.get_tightbbox(renderer).width if tight else fig.get_figwidth()  # inches, as saved
    if width > COLUMN_WIDTH_IN + 1e-6:
        found.append(f"{width:.2f} in wide: more than a page column ({COLUMN_WIDTH_IN} in)")
    fig_box = fig.bbox
    for k, ax in enumerate(_axes(fig)):
        name = f"panel {k + 1}" + (f" ({ax.get_title()})" if ax.get_title() else "")
        for which, axis, label in (("x", ax.xaxis, ax.get_xlabel()), ("y", ax.yaxis, ax.get_ylabel())):
            texts = _tick_texts(axis)
            for a, b in _overlaps(texts, renderer):
                found.append(f"{name}: {which} tick labels '{a}' and '{b}' overlap")
            if axis.get_scale() in ("log", "symlog"):
                for t in texts:
                    if _ZERO.match(t.get_text().strip()):
                        found.append(f"{name}: a '0' tick on the log {which} axis")
            if not any(_NUMERIC.match(t.get_text().strip()) for t in texts):
                continue  # categorical ticks (solver or case names): no unit to give
            if texts and label and not _UNIT.search(label):
                found.append(f"{name}: the {which} axis label '{label}' has no unit")
            if texts and not label:
                found.append(f"{name}: the {which} axis has no label")
    for text in fig.findobj(lambda a: hasattr(a, "get_fontsize") and hasattr(a, "get_text")):
        if not text.get_visible() or not str(text.get_text()).strip():
            continue
        if text.get_fontsize() < MIN_FONT_PT - 1e-6:
            found.append(f"text '{str(text.get_text())[:40]}' is {text.get_fontsize():g} pt (< {MIN_FONT_PT:g})")
        if not tight:
            box = text.get_window_extent(renderer)
            if box.x0 < fig_box.x0 - 1 or box.x1 > fig_box.x1 + 1 or box.y0 < fig_box.y0 - 1 or box.y1 > fig_box.y1 + 1:
                found.append(f"text '{str(text.get_text())[:40]}' is clipped by the figure's edge")
    return sorted(set(found), key=found.index)
