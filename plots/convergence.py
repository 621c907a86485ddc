#!/usr/bin/python3
"""Convergence plots of a results folder: the common relative KKT error against time, iterations
and A-products; one panel per snapshot, one line per solver label.

usage: convergence.py RESULTS_DIR [--out FIGDIR] [--max-panels N] [--column kkt_rel]
Writes FIGDIR (default RESULTS_DIR/figures)/convergence_{time,iterations,a_products}.{png,pdf}.
"""
from __future__ import annotations

import argparse
import os
import sys
from typing import List


from plots import figutil  # noqa: E402
from plots.figutil import plt  # noqa: E402
from plots.loader import Results, load_results  # noqa: E402

AXES = (("time_s", "time [s] (solver only)", "time"),
        ("iteration", "iterations", "iterations"),
        ("a_products", "A-products", "a_products"))


def plot_convergence(results: Results, out_dir: str, column: str = "kkt_rel",
                     max_panels: int = 12) -> List[str]:
    """Writes the three convergence figures; returns the paths written."""
    snapshots = results.snapshots()
    labels = results.labels()
    shown = snapshots[:max_panels]
    colours = {label: f"C{i % 10}" for i, label in enumerate(labels)}
    written = []
    for x, xlabel, stem in AXES:
        rows, cols = figutil.grid(max(1, len(shown)))
        fig, axes = plt.subplots(rows, cols, figsize=(4.2 * cols, 3.3 * rows), squeeze=False)
        for ax in axes.flat[len(shown):]:
            ax.axis("off")
        for ax, snap in zip(axes.flat, shown):
            drawn = 0
            for label in labels:
                h = results.history(snap, label)
                if h.empty or x not in h or column not in h:
                    run = results.runs[(results.runs["snapshot"] == snap) & (results.runs["label"] == label)]
                    if run.empty:
                        continue
                    # no history: the final point alone, so the run is still visible
                    r = run.iloc[0]
                    xv = {"time_s": r.get("time_s"), "iteration": r.get("iterations"),
                          "a_products": r.get("a_products")}[x]
                    ax.plot([xv], figutil.positive([r.get(column)]), "o", color=colours[label], label=label)
                    drawn += 1
                    continue
                ax.plot(h[x], figutil.positive(h[column]), "-", color=colours[label], label=label, lw=1.3)
                drawn += 1
            ax.set_yscale("log")
            if x == "time_s":
                ax.set_xscale("symlog", linthresh=1e-4)
                ax.set_xlim(left=0)
            ax.set_title(snap if len(snap) < 40 else snap[:37] + "...", fontsize=8)
            ax.set_xlabel(xlabel)
            ax.set_ylabel("error e on the original QP (fraction of scene size)" if column == "kkt_rel" else column)
            ax.grid(True, which="both", alpha=0.3)
            if drawn:
                ax.legend(fontsize=7)
        title = f"{results.suite.get('name', os.path.basename(os.path.normpath(results.path)))}: {column} vs {xlabel}"
        if len(snapshots) > len(shown):
            title += f" (first {len(shown)} of {len(snapshots)} snapshots)"
        fig.suptitle(title, fontsize=10)
        fig.tight_layout()
        written += figutil.save_figure(fig, out_dir, f"convergence_{stem}")
    return written


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("results", help="a results folder (contactbench run --out DIR)")
    parser.add_argument("--out", help="figure folder (default RESULTS/figures)")
    parser.add_argument("--max-panels", type=int, default=12)
    parser.add_argument("--column", default="kkt_rel", help="history column on the y axis")
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
    for path in plot_convergence(results, out, args.column, args.max_panels):
        print(path)
    return 0


if __name__ == "__main__":
    sys.exit(main())
