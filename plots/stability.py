#!/usr/bin/python3
"""Heat map of a stress run: solver x case, colour = log10 of the accuracy error e reached on the
original QP (docs/accuracy.md); a cell is marked "rel" when the run is solved_relaxation (tol met
only on the problem the solver changed), "!" when the solver said "converged" and the measure does
not confirm it (status unconfirmed), N when NaN/Inf appeared, ~ when the objective was not monotone.

With the stress folder's runs/ (histories kept for the stiff families), it also draws
stiff_family.png: the error e against time (setup included) per stiff case, one line per solver
(dashed: no "ichol" in the label), as embedded in stability.md.

usage: stability.py STRESS_DIR_OR_CSV [--out FIGDIR]
Reads STRESS_DIR/stability.csv (or the CSV given; a results folder's summary.csv also works).
Columns are found by name: solver (label | solver), case (case | snapshot | family), error
(accuracy; older files' names are read by plots/record_schema.py), status, status_confirmed, nonfinite,
monotone.
"""
from __future__ import annotations

import argparse
import json
import math
import os
import sys
import textwrap
from typing import List, Optional


import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

from plots import figutil  # noqa: E402
from plots.figutil import plt  # noqa: E402
from plots.loader import _to_bool  # noqa: E402
from plots.record_schema import OLD_COLUMNS, OLD_STABILITY_COLUMNS, current_column_names, with_current_columns  # noqa: E402

CANDIDATES = {
    "solver": ("label", "solver"),
    "case": ("case", "snapshot", "family", "problem"),
    "error": ("accuracy",),
    "status": ("status",),
    "confirmed": ("status_confirmed", "confirmed"),
    "nonfinite": ("nonfinite", "nan_inf", "nonfinite_seen"),
    "monotone": ("monotone",),
}


def find_column(df: pd.DataFrame, role: str) -> Optional[str]:
    for name in CANDIDATES[role]:
        if name in df.columns:
            return name
    return None


def read_table(path: str) -> pd.DataFrame:
    file = os.path.join(path, "stability.csv") if os.path.isdir(path) else path
    if os.path.isdir(path) and not os.path.isfile(file):
        file = os.path.join(path, "summary.csv")
    if not os.path.isfile(file):
        raise FileNotFoundError(f"{path}: no stability.csv (nor summary.csv)")
    return with_current_columns(pd.read_csv(file), file, {**OLD_COLUMNS, **OLD_STABILITY_COLUMNS})


def cell_marks(row: pd.Series, cols: dict) -> str:
    marks = ""
    status = str(row[cols["status"]]).strip().lower() if cols["status"] else ""
    if status == "unconfirmed" or (cols["confirmed"] and status == "converged"
                                   and not _to_bool(row[cols["confirmed"]])):
        marks += "!"
    if cols["nonfinite"] and _to_bool(row[cols["nonfinite"]]):
        marks += "N"
    if cols["monotone"] and not _to_bool(row[cols["monotone"]]):
        marks += "~"
    return marks


def plot_stability(df: pd.DataFrame, out_dir: str, stem: str = "stability") -> List[str]:
    cols = {role: find_column(df, role) for role in CANDIDATES}
    missing = [r for r in ("solver", "case", "error") if not cols[r]]
    if missing:
        raise ValueError(f"stability table lacks the column(s) for {', '.join(missing)}; "
                         f"has {', '.join(df.columns)}")
    solvers = list(dict.fromkeys(df[cols["solver"]].astype(str)))
    cases = list(dict.fromkeys(df[cols["case"]].astype(str)))
    grid = np.full((len(solvers), len(cases)), np.nan)
    text = [["" for _ in cases] for _ in solvers]
    for _, row in df.iterrows():
        i, j = solvers.index(str(row[cols["solver"]])), cases.index(str(row[cols["case"]]))
        err = pd.to_numeric(row[cols["error"]], errors="coerce")
        grid[i, j] = math.log10(err) if np.isfinite(err) and err > 0 else (-16 if err == 0 else np.nan)
        status = str(row[cols["status"]]) if cols["status"] else ""
        short = {"converged": "", "max_iterations": "it", "time_limit": "t", "stalled": "st",
                 "diverged": "div", "infeasible": "inf", "invalid_input": "inv", "not_applicable": "n/a",
                 "solved_relaxation": "rel",
                 "unconfirmed": ""}.get(status, status[:3])
        text[i][j] = (short + cell_marks(row, cols)) if np.isfinite(err) else ("NaN" + cell_marks(row, cols))
    # at most a page column wide (plots/figure_checks.py)
    width = min(7.0, max(5, 0.55 * len(cases) + 2.5))
    fig, ax = plt.subplots(figsize=(width, max(2.5, 0.45 * len(solvers) + 1.5)))
    masked = np.ma.masked_invalid(grid)
    cmap = plt.get_cmap("RdYlGn_r").copy()
    cmap.set_bad("#555555")
    im = ax.imshow(masked, cmap=cmap, vmin=-12, vmax=0, aspect="auto")
    for i in range(len(solvers)):
        for j in range(len(cases)):
            if text[i][j]:
                ax.text(j, i, text[i][j], ha="center", va="center", fontsize=7,
                        color="white" if np.isnan(grid[i, j]) else "black", fontweight="bold")
    ax.set_xticks(range(len(cases)))
    ax.set_xticklabels(cases, rotation=60, ha="right", fontsize=7)
    ax.set_yticks(range(len(solvers)))
    ax.set_yticklabels(solvers, fontsize=8)
    fig.colorbar(im, ax=ax, label=f"log10 {cols['error']} reached [1]")
    ax.set_title(textwrap.fill("stability (error e on the original QP): ! = 'converged' not confirmed by the measure, "
                               "rel = solved_relaxation, N = NaN/Inf seen, ~ = non-monotone, it/t/st/div/inf/inv = "
                               "max_iterations/time_limit/stalled/diverged/infeasible/invalid; grey = no finite error",
                               int(12 * width), break_long_words=False), fontsize=7)
    fig.tight_layout()
    return figutil.save_figure(fig, out_dir, stem)


def stiff_histories(stress_dir: str, df: pd.DataFrame) -> dict:
    """{case: {solver label: DataFrame(time_s, error)}} for the stiff families' runs whose record
    kept its history (runs/<case>__<solver>.json; `contactbench stress` keeps them for the
    families whose name starts with "stiff")."""
    if "family" not in df.columns or "case" not in df.columns:
        return {}
    out: dict = {}
    stiff = df[df["family"].astype(str).str.startswith("stiff")]
    for case, label in zip(stiff["case"], stiff["solver"]):
        path = os.path.join(stress_dir, "runs", f"{case}__{label}.json")
        if not os.path.isfile(path):
            continue
        with open(path) as f:
            run = json.load(f)
        hist = run.get("history") or {}
        rows, cols = hist.get("rows") or [], current_column_names(hist.get("columns") or [], path)
        if not rows or "time_s" not in cols or "accuracy" not in cols:
            continue
        h = pd.DataFrame(rows, columns=cols)
        # Histories with solve_time_s are stamped from the start of setup (older ones: solve only).
        setup = 0.0 if "solve_time_s" in cols else float((run.get("time") or {}).get("setup_s") or 0.0)
        curve = pd.DataFrame({"time_s": pd.to_numeric(h["time_s"], errors="coerce") + setup,
                              "error": pd.to_numeric(h["accuracy"], errors="coerce")}).dropna()
        if len(curve):
            out.setdefault(str(case), {})[str(label)] = curve
    return out


def _case_key(case: str) -> tuple:
    """slab-stiff-1e4 < slab-stiff-1e12: by family prefix, then by the trailing modulus."""
    head, _, tail = case.rpartition("-")
    try:
        return (head, float(tail))
    except ValueError:
        return (case, 0.0)


def plot_stiff_family(histories: dict, out_dir: str, tol: Optional[float] = None,
                      stem: str = "stiff_family") -> List[str]:
    """Error e against time (setup included) per stiff case, one line per solver."""
    if not histories:
        return []
    cases = sorted(histories, key=_case_key)
    nrow, ncol = figutil.grid(len(cases))  # a page column wide, two panels a row
    fig, axes = plt.subplots(nrow, ncol, figsize=(7.0 if ncol > 1 else 3.5, 2.5 * nrow), squeeze=False)
    labels = sorted({lab for h in histories.values() for lab in h})
    # the solvers' fixed colours and markers (a label "cg:precond=ichol" is a variant of cg)
    styles = figutil.assign_styles(labels, {lab: lab.split(":")[0] for lab in labels})
    colours = {lab: styles[lab]["color"] for lab in labels}
    for k, case in enumerate(cases):
        ax = axes[k // ncol][k % ncol]
        for lab, curve in sorted(histories[case].items()):
            y = curve["error"].clip(lower=1e-17)
            ax.step(curve["time_s"].clip(lower=1e-6), y, where="post", label=lab, color=colours[lab],
                    linestyle="-" if "ichol" in lab else "--", linewidth=1.1, marker=styles[lab]["marker"],
                    markevery=[len(y) - 1], markersize=4, clip_on=False)
        if tol:
            ax.axhline(tol, color="black", linewidth=0.6, linestyle=":")
            ax.annotate(f"tol = {tol:g}", (1.0, tol), xycoords=("axes fraction", "data"), ha="right", va="bottom",
                        fontsize=7)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_title(case, fontsize=8)
        ax.set_xlabel("time [s] (setup included)", fontsize=8)
        ax.set_ylabel("e on the original QP [1]", fontsize=8)
    for k in range(len(cases), nrow * ncol):
        axes[k // ncol][k % ncol].axis("off")
    handles = [plt.Line2D([], [], color=colours[lab], linestyle="-" if "ichol" in lab else "--",
                          marker=styles[lab]["marker"]) for lab in labels]
    fig.tight_layout()
    fig.legend(handles, labels, loc="upper center", bbox_to_anchor=(0.5, 0.0), ncol=min(3, len(labels)),
               fontsize=7, frameon=False)
    return figutil.save_figure_outside(fig, out_dir, stem)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("stress", help="stress output folder (with stability.csv) or a CSV file")
    parser.add_argument("--out", help="figure folder (default: <folder>/figures)")
    args = parser.parse_args(argv)
    try:
        df = read_table(args.stress)
        base = args.stress if os.path.isdir(args.stress) else os.path.dirname(os.path.abspath(args.stress))
        for p in plot_stability(df, args.out or os.path.join(base, "figures")):
            print(p)
        tol = float(df["tol"].iloc[0]) if "tol" in df.columns and len(df) else None
        for p in plot_stiff_family(stiff_histories(base, df), args.out or os.path.join(base, "figures"), tol):
            print(p)
    except (FileNotFoundError, ValueError) as err:
        print(f"stability.py: {err}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
