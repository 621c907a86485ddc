#!/usr/bin/python3
"""Convergence plots of a results folder: the accuracy error e on the original QP against time,
iterations, A-products and work units; one panel per snapshot (n and m in its title), one line
per solver label in the solver's fixed colour and marker (plots/figutil.py), one legend outside
the panels, the runs' tol drawn, and an x on the final point of every run that did not converge.

usage: convergence.py RESULTS_DIR [--out FIGDIR] [--max-panels N] [--column accuracy] [--solve-only]
Writes FIGDIR (default RESULTS_DIR/figures)/convergence_{time,iterations,a_products,work}.{png,pdf}
(work only when the runs record work units).
"""
from __future__ import annotations

import argparse
import os
import sys
from typing import List


import numpy as np  # noqa: E402

from plots import figutil  # noqa: E402
from plots.figutil import plt  # noqa: E402
from plots.loader import UNMEASURED_STATUSES, Results, history_time, load_results  # noqa: E402
from plots.record_schema import current_column_names  # noqa: E402

AXES = (("time_s", "time [s] (setup + solve)", "time"),
        ("iteration", "iterations (count)", "iterations"),
        ("a_products", "A-products (count)", "a_products"),
        ("work", "work [A-product equivalents]", "work"))
#: the y label of the accuracy error (a relative measure: docs/accuracy.md)
E_LABEL = "e on the original QP [1]"

#: final run columns standing in for a history column when a run has no history
_FINAL = {"time_s": "time_s", "iteration": "iterations", "a_products": "a_products", "work": "work"}


def _converged(run) -> bool:
    return str(run.get("status", "")) == "converged"


def plot_convergence(results: Results, out_dir: str, column: str = "accuracy",
                     max_panels: int = 12, include_setup: bool = True) -> List[str]:
    """Writes the convergence figures; returns the paths written."""
    snapshots = results.snapshots()
    labels = results.labels()
    shown = snapshots[:max_panels]
    solvers = figutil.label_solvers(results.runs)
    display = {label: figutil.display_label(label, results.runs) for label in labels}
    styles = figutil.assign_styles(labels, solvers)
    runs = results.runs.set_index(["snapshot", "label"], drop=False)
    tol = float(np.nanmax(results.runs["accuracy_tol"])) if "accuracy_tol" in results.runs and \
        results.runs["accuracy_tol"].notna().any() else float("nan")
    has_work = "work" in results.runs and results.runs["work"].notna().any()
    no_work = figutil.work_left_out(labels, solvers)
    written = []
    for x, xlabel, stem in AXES:
        if x == "work" and not has_work:
            continue
        if x == "time_s" and not include_setup:
            xlabel = "time [s] (solve only)"
        rows, cols = figutil.grid(max(1, len(shown)))
        # a page column wide (7 in at 300 dpi), two panels a row
        fig, axes = plt.subplots(rows, cols, figsize=(7.0 if cols > 1 else 3.5, 2.6 * rows), squeeze=False)
        for ax in axes.flat[len(shown):]:
            ax.axis("off")
        for ax, snap in zip(axes.flat, shown):
            n = m = None
            for label in labels:
                if (snap, label) not in runs.index:
                    continue
                run = runs.loc[(snap, label)]
                if hasattr(run, "iloc") and getattr(run, "ndim", 1) > 1:
                    run = run.iloc[0]
                n, m = run.get("n"), run.get("m")
                if run.get("status") in UNMEASURED_STATUSES:
                    continue  # n/a, refused or never run: there is no curve to draw
                if x == "work" and label in no_work:
                    continue  # its work is not counted in full: a curve would understate it
                style = styles[label]
                h = results.history(snap, label)
                if h.empty or x not in h or column not in h:
                    xv, yv = [run.get(_FINAL[x])], figutil.positive([run.get(column)])
                    ax.plot(xv, yv, ls="none", marker=style["marker"], color=style["color"], label=display[label],
                            clip_on=False)
                else:
                    xv = history_time(h, run, include_setup) if x == "time_s" else h[x].to_numpy(dtype=float)
                    yv = figutil.positive(h[column])
                    ax.plot(xv, yv, color=style["color"], ls=style["linestyle"], lw=1.3, label=display[label],
                            marker=style["marker"], markevery=[len(yv) - 1], markersize=4)
                    # the final point's marker is drawn whole, even at the axes' edge
                    ax.plot([np.asarray(xv, dtype=float)[-1]], [yv[-1]], ls="none", marker=style["marker"],
                            color=style["color"], markersize=4, clip_on=False)
                if not _converged(run) and len(yv):
                    ax.plot([np.asarray(xv, dtype=float)[-1]], [yv[-1]], ls="none", marker="x", color="black",
                            markersize=6, zorder=5, clip_on=False)
            ax.set_yscale("log")
            if x == "time_s":
                ax.set_xscale("log")  # times from the start of setup are > 0: no "0" tick
            if column == "accuracy":
                figutil.draw_tol(ax, tol)
            ax.set_title(figutil.panel_title(snap, n, m, width=32), fontsize=7)
            ax.set_xlabel(xlabel)
            ax.set_ylabel(E_LABEL if column == "accuracy" else f"{column} [1]")
            ax.grid(True, which="both", alpha=0.3)
        title = f"{results.suite.get('name', os.path.basename(os.path.normpath(results.path)))}: {column} vs {xlabel}"
        if len(snapshots) > len(shown):
            title += f" (first {len(shown)} of {len(snapshots)} snapshots)"
        if x == "work" and no_work:
            title += ("\nleft out, their work is not counted in full (docs/work.md \"Figures\"): "
                      + ", ".join(no_work))
        fig.suptitle(title, fontsize=8)
        fig.tight_layout()
        figutil.legend_outside(fig, axes.flat, notes=[figutil.failed_mark()])
        written += figutil.save_figure_outside(fig, out_dir, f"convergence_{stem}")
    return written


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("results", help="a results folder (contactbench run --out DIR)")
    parser.add_argument("--out", help="figure folder (default RESULTS/figures)")
    parser.add_argument("--max-panels", type=int, default=12)
    parser.add_argument("--column", default="accuracy", help="history column on the y axis")
    parser.add_argument("--solve-only", action="store_true", help="time axis without setup")
    args = parser.parse_args(argv)
    try:
        results = load_results(args.results)
    except (FileNotFoundError, ValueError) as err:
        print(f"convergence.py: {err}", file=sys.stderr)
        return 2
    if results.runs.empty:
        print(f"convergence.py: {args.results}: no runs", file=sys.stderr)
        return 2
    out = args.out or os.path.join(args.results, "figures")
    column = current_column_names([args.column], "--column")[0]  # an old column name, with a warning
    for path in plot_convergence(results, out, column, args.max_panels, not args.solve_only):
        print(path)
    return 0


if __name__ == "__main__":
    sys.exit(main())
