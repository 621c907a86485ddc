#!/usr/bin/python3
"""Suite-wide comparisons of a results folder (DESIGN.md "Metrics", "Across a suite"; the rules are
in docs/work.md "Profiles").

- tiers: the accuracy error e on the original QP (docs/accuracy.md) at 1e-2, 1e-4, 1e-6, 1e-8 of
  the scene size, keeping only the tiers no tighter than the runs' tol (a run that stopped at its
  tol is not asked for more); the dropped tiers are named in the report;
- time to a tier, read off the histories (the final point when a run has no history), counted
  from the start of setup (solve-only with --solve-only, labelled so);
- one problem set per tier: every solver is judged on every problem of the suite it applies to;
  `not_applicable` runs ("n/a": a problem class the solver does not take, e.g. mprgp-box on
  general rows, pgs over max_rows) leave that solver's denominator and are counted beside; a
  `solved_relaxation` run (tol met only on a problem the solver changed) is judged on e of the
  original QP like any run, so it reaches a tier only if it brought e there;
- shifted geometric mean of the times, sgm = exp(mean(log(t + s))) - s, normalised to the best
  solver of the tier (ratio 1 = best), with the shift scaled to the data: s = 10% of the median of
  the times-to-tier reached over the report (printed; --shift sets it in seconds); a run that never
  reaches a tier counts at the penalty time (the suite's time_limit_s, else the largest time seen);
- Dolan-More performance profiles: rho_s(tau) = share of problems with t_ps / min_s t_ps <= tau;
- More-Wild data profiles: share of problems solved to a tier within a budget of work units
  (A-product equivalents, docs/work.md: factorisations, triangular solves and dense sweeps
  included; A-products for results written before the unit existed);
- "status honesty": of the runs whose solver said "converged", how many the measure confirms on the
  original QP (converged), on the solver's own problem only (solved_relaxation), or not at all
  (unconfirmed).

usage: profiles.py RESULTS_DIR [--shift S] [--solve-only] [--out FIGDIR]
Writes RESULTS_DIR/profiles.md and FIGDIR/profiles_{performance,data}.{png,pdf}.
"""
from __future__ import annotations

import argparse
import math
import os
import sys
from typing import Dict, Iterable, List, Optional, Tuple


import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402
from matplotlib.ticker import NullFormatter  # noqa: E402

from plots import figutil  # noqa: E402
from plots.figutil import TIERS, fmt, plt  # noqa: E402
from plots.loader import (NOT_APPLICABLE_STATUS, RELAXATION_STATUS, Results, history_time,  # noqa: E402
                          load_results)

#: the data-scaled shift: this fraction of the median time-to-tier reached
SHIFT_FRACTION = 0.1
#: the column a run's n/a count goes in
NA_COLUMN = "n/a"
#: the column of the number of problems a solver is judged on (every problem but its n/a ones)
JUDGED_COLUMN = "judged"


def shifted_geomean(values: Iterable[float], shift: float) -> float:
    """exp(mean(log(v + shift))) - shift; NaN for an empty input."""
    v = np.asarray(list(values), dtype=float)
    if v.size == 0:
        return float("nan")
    if np.any(v + shift <= 0):
        raise ValueError(f"shifted_geomean: values + shift must be > 0 (shift {shift}, min {v.min()})")
    return float(np.exp(np.mean(np.log(v + shift))) - shift)


def data_shift(times: Iterable[float], fraction: float = SHIFT_FRACTION) -> float:
    """The shift scaled to the data: `fraction` of the median of the positive finite times (the
    times-to-tier reached); 1e-6 s when there are none."""
    t = np.asarray([v for v in times if v is not None], dtype=float)
    t = t[np.isfinite(t) & (t > 0)]
    return float(fraction * np.median(t)) if t.size else 1e-6


def judged_tiers(runs: pd.DataFrame, tiers=TIERS) -> Tuple[list, list, float]:
    """(kept, dropped, tol): the tiers no tighter than the largest accuracy tol of the runs that ran
    (a tier below a run's tol asks for more than the run was asked for)."""
    tol = float("nan")
    if not runs.empty:
        col = "accuracy_tol" if "accuracy_tol" in runs else "tol" if "tol" in runs else None
        if col:
            sel = runs[runs["status"] != NOT_APPLICABLE_STATUS] if "status" in runs else runs
            vals = pd.to_numeric(sel[col], errors="coerce")
            vals = vals[np.isfinite(vals) & (vals > 0)]
            tol = float(vals.max()) if len(vals) else float("nan")
    if math.isnan(tol):
        return list(tiers), [], tol
    kept = [t for t in tiers if t >= tol * (1 - 1e-12)]
    return kept, [t for t in tiers if t not in kept], tol


def tier_table(results: Results, tiers=TIERS, include_setup: bool = True) -> pd.DataFrame:
    """One row per (snapshot, label, tier): reached, time_s (from the start of setup unless
    include_setup is False), a_products and work (A-product equivalents) when first reached;
    relaxation = the run is solved_relaxation (judged on e of the original QP, like any run),
    na = not_applicable (not judged)."""
    rows = []
    for _, run in results.runs.iterrows():
        snap, label = run["snapshot"], run["label"]
        status = run.get("status", "")
        relaxation = status == RELAXATION_STATUS
        na = status == NOT_APPLICABLE_STATUS
        h = results.history(snap, label)
        final_ok = bool(np.isfinite(run.get("accuracy", np.nan))) and not bool(run.get("nonfinite", False))
        if not h.empty and "time_s" in h:
            h = h.assign(time_s=history_time(h, run, include_setup))
        final_time = float(run.get("time_s", np.nan)) if include_setup else float(run.get("solve_s", np.nan))
        for tier in tiers:
            t = a = w = float("nan")
            if not h.empty and "accuracy" in h:
                t = figutil.first_reach(h, "accuracy", tier, "time_s")
                a = figutil.first_reach(h, "accuracy", tier, "a_products")
                w = figutil.first_reach(h, "accuracy", tier, "work")
            if math.isnan(t) and final_ok and run.get("accuracy", np.inf) <= tier:
                # no history, or the history's stride skipped the point: the final point counts
                t = final_time
                a = float(run.get("a_products", np.nan))
                w = float(run.get("work", np.nan))
            if na:  # the solver does not take this problem class: not judged on it
                t = a = w = float("nan")
            # a relaxation is judged like every run, on e of the ORIGINAL QP (the history's and the
            # final point's accuracy): it reaches a tier only if it brought e there
            rows.append({"snapshot": snap, "label": label, "tier": tier, "reached": not math.isnan(t),
                         "time_s": t, "a_products": a, "work": w, "relaxation": relaxation, "na": na})
    return pd.DataFrame(rows, columns=["snapshot", "label", "tier", "reached", "time_s", "a_products", "work",
                                       "relaxation", "na"])


def penalty_time(results: Results) -> float:
    """The time a failed run counts for: the suite's time limit, else the largest time seen."""
    limit = results.suite.get("time_limit_s") if results.suite else None
    if limit and float(limit) > 0:
        return float(limit)
    times = pd.to_numeric(results.runs.get("time_s", pd.Series(dtype=float)), errors="coerce")
    return float(times.max()) if times.notna().any() else 1.0


def performance_ratios(cost: pd.DataFrame) -> pd.DataFrame:
    """cost: index = problems, columns = solvers, NaN = failed. Ratios to the best; inf = failed.
    A problem no solver solved gets inf everywhere."""
    best = cost.min(axis=1, skipna=True)
    ratios = cost.div(best, axis=0)
    return ratios.replace([np.nan], np.inf)


def _denominators(columns, count: int, excluded: pd.DataFrame = None) -> Dict[str, int]:
    """Problems each solver is judged on: all of them minus its excluded (not_applicable) runs."""
    if excluded is None:
        return {s: max(1, count) for s in columns}
    return {s: max(1, count - int(excluded[s].fillna(False).astype(bool).sum()) if s in excluded else count)
            for s in columns}


def performance_profile(ratios: pd.DataFrame, taus: np.ndarray, excluded: pd.DataFrame = None) -> pd.DataFrame:
    """rho_s(tau) for each tau (rows) and solver (columns); `excluded` (problems x solvers, True for
    not_applicable runs) leaves those runs out of the solver's denominator."""
    n = _denominators(ratios.columns, len(ratios), excluded)
    return pd.DataFrame({s: [(ratios[s] <= tau).sum() / n[s] for tau in taus] for s in ratios.columns},
                        index=taus)


def data_profile(work: pd.DataFrame, budgets: np.ndarray, excluded: pd.DataFrame = None) -> pd.DataFrame:
    """work: index = problems, columns = solvers, NaN = not solved. Share solved within each budget
    (excluded runs, marked in `excluded`, are left out of the denominator)."""
    n = _denominators(work.columns, len(work), excluded)
    return pd.DataFrame({s: [(work[s] <= b).sum() / n[s] for b in budgets] for s in work.columns}, index=budgets)


def status_honesty(runs: pd.DataFrame) -> pd.DataFrame:
    """Per label: runs; runs whose solver said converged; of those, the runs the measure confirms
    on the original QP (status converged), on the solver's own problem only (solved_relaxation),
    and the share confirmed on the original QP (older files, without solver_status: a converged
    status that status_confirmed confirms)."""
    rows = []
    for label, g in runs.groupby("label", sort=False):
        said = g["solver_status"] if "solver_status" in g else g["status"]
        claimed = g[said == "converged"]
        confirmed = int(((claimed["status"] == "converged") & claimed["status_confirmed"].map(bool)).sum())
        relaxation = int((claimed["status"] == RELAXATION_STATUS).sum())
        rows.append({"label": label, "runs": len(g), "converged": len(claimed), "confirmed": confirmed,
                     "relaxation": relaxation,
                     "share": confirmed / len(claimed) if len(claimed) else float("nan")})
    return pd.DataFrame(rows, columns=["label", "runs", "converged", "confirmed", "relaxation", "share"])


def compute(results: Results, shift: Optional[float] = None, tiers=TIERS,
            include_setup: bool = True) -> Dict[str, object]:
    """All numbers of profiles.md, as DataFrames. shift None: scaled to the data (data_shift of
    the times-to-tier reached); tiers tighter than the runs' tol are dropped."""
    kept, dropped, tol = judged_tiers(results.runs, tiers)
    tt = tier_table(results, kept, include_setup)
    labels = results.labels()
    penalty = penalty_time(results)
    judged = tt[~tt["na"].astype(bool)]  # every problem the solver applies to; relaxations included
    shift_rule = "given"
    if shift is None:
        shift = data_shift(judged.loc[judged["reached"], "time_s"])
        shift_rule = f"{SHIFT_FRACTION:g} x the median time-to-tier reached"
    success, sgm, median = {}, {}, {}
    for tier in kept:
        sel = judged[judged["tier"] == tier]
        success[tier] = sel.groupby("label")["reached"].mean().reindex(labels)
        times = sel.assign(t=sel["time_s"].where(sel["reached"], penalty))
        sgm[tier] = times.groupby("label")["t"].agg(lambda v: shifted_geomean(v, shift)).reindex(labels)
        median[tier] = sel[sel["reached"]].groupby("label")["time_s"].median().reindex(labels)
    success_table = pd.DataFrame(success, index=labels)
    first = tt[tt["tier"] == kept[0]] if len(tt) and kept else tt
    success_table[JUDGED_COLUMN] = (first.groupby("label")["na"].apply(lambda v: int((~v.astype(bool)).sum()))
                                    .reindex(labels).fillna(0) if len(first) else pd.Series(0, index=labels))
    for col, key in ((RELAXATION_STATUS, "relaxation"), (NA_COLUMN, "na")):
        success_table[col] = (first.groupby("label")[key].sum().reindex(labels).fillna(0)
                              if len(first) else pd.Series(0, index=labels))
    sgm_table = pd.DataFrame(sgm, index=labels)
    ratio_table = sgm_table / sgm_table.min(axis=0, skipna=True) if not sgm_table.empty else sgm_table
    return {"tiers": tt, "tier_values": kept, "dropped_tiers": dropped, "tol": tol, "labels": labels,
            "penalty_s": penalty, "shift_s": shift, "shift_rule": shift_rule, "include_setup": include_setup,
            "success": success_table, "sgm": sgm_table, "sgm_ratio": ratio_table,
            "median": pd.DataFrame(median, index=labels),
            "work_column": "work" if tt["work"].notna().any() else "a_products",
            "honesty": status_honesty(results.runs) if not results.runs.empty else pd.DataFrame()}


def cost_matrix(tt: pd.DataFrame, tier: float, column: str = "time_s") -> pd.DataFrame:
    sel = tt[tt["tier"] == tier]
    return sel.pivot_table(index="snapshot", columns="label", values=column, aggfunc="first", dropna=False)


def excluded_matrix(tt: pd.DataFrame, tier: float) -> pd.DataFrame:
    """problems x solvers, True where the run is not_applicable (the solver is not judged on that
    problem; a solved_relaxation run is judged, on e of the original QP)."""
    sel = tt[tt["tier"] == tier].assign(excluded=lambda d: d["na"].astype(bool).astype(float))
    return sel.pivot_table(index="snapshot", columns="label", values="excluded", aggfunc="first",
                           dropna=False) > 0


#: the former name (solved_relaxation only); not_applicable runs are excluded the same way
relaxation_matrix = excluded_matrix


def _draw_profiles(numbers: dict, labels: List[str], solvers: Dict[str, str], display: Dict[str, str],
                   column: str, xlabel: str, title: str, out_dir: str, stem: str) -> List[str]:
    tt, tiers = numbers["tiers"], sorted(numbers["tier_values"], reverse=True)
    # a grid a page column wide (two panels a row, figutil.grid)
    rows, cols = figutil.grid(max(1, len(tiers)))
    fig, axes = plt.subplots(rows, cols, figsize=(7.0 if cols > 1 else 3.5, 2.5 * rows), squeeze=False)
    for ax in axes.flat[len(tiers):]:
        ax.axis("off")
    styles = figutil.assign_styles(labels, solvers)
    for ax, tier in zip(axes.flat, tiers):
        cost = cost_matrix(tt, tier, column).reindex(columns=labels)
        excluded = excluded_matrix(tt, tier).reindex(columns=labels)
        if column == "time_s":
            ratios = performance_ratios(cost)
            finite = ratios.replace(np.inf, np.nan).stack()
            top = max(10.0, float(finite.max()) * 1.2) if not finite.empty else 10.0
            xs = np.logspace(0, math.log10(top), 200)
            prof = performance_profile(ratios, xs, excluded)
        else:
            vals = cost.stack()
            lo = max(0.1, float(vals[vals > 0].min()) / 1.5) if (vals > 0).any() else 1.0
            hi = max(lo * 10, float(vals.max()) * 1.5) if not vals.empty else 10.0
            xs = np.logspace(math.log10(lo), math.log10(hi), 200)
            prof = data_profile(cost, xs, excluded)
        judged = _denominators(labels, len(cost), excluded)
        no_work = figutil.work_left_out(labels, solvers) if column != "time_s" else {}
        for label in labels:
            if label in no_work:
                continue  # its work is not counted in full (figutil.WORK_NOT_COUNTED): said in profiles.md
            if len(cost) - (int(excluded[label].fillna(False).astype(bool).sum()) if label in excluded else 0) <= 0:
                continue  # every run of the label is n/a: nothing to draw
            style = styles[label]
            ax.step(xs, prof[label], where="post", color=style["color"], ls=style["linestyle"], lw=1.4,
                    marker=style["marker"], markevery=[len(xs) - 1], markersize=4, clip_on=False,
                    label=f"{display.get(label, label)} ({judged[label]} judged)")
        ax.set_xscale("log")
        ax.xaxis.set_minor_formatter(NullFormatter())  # short ranges would label every minor tick
        ax.set_ylim(-0.02, 1.02)
        ax.set_xlabel(xlabel)
        ax.set_title(f"{title}, error e <= {tier:g}", fontsize=8)
        ax.grid(True, alpha=0.3)
        ax.set_ylabel("share of problems" + (" solved" if column != "time_s" else "") + " [1]")
    fig.tight_layout()
    figutil.legend_outside(fig, axes.flat[:1], title="solver (problems judged; n/a left out)")
    return figutil.save_figure_outside(fig, out_dir, stem)


def plot_profiles(numbers: dict, out_dir: str, runs: Optional[pd.DataFrame] = None) -> List[str]:
    labels = numbers["labels"]
    solvers = figutil.label_solvers(runs) if runs is not None else {}
    display = {label: figutil.display_label(label, runs) for label in labels} if runs is not None else {}
    clock = "setup + solve" if numbers.get("include_setup", True) else "solve only"
    written = _draw_profiles(numbers, labels, solvers, display, "time_s", f"tau [1] (time / best time; {clock})",
                             "performance profile", out_dir, "profiles_performance")
    unit = "work units (A-product equivalents)" if numbers.get("work_column") == "work" else "A-products"
    written += _draw_profiles(numbers, labels, solvers, display, numbers.get("work_column", "work"),
                              f"budget [{unit}]", "data profile", out_dir, "profiles_data")
    return written


def _table(df: pd.DataFrame, index_name: str, fmt_cell=fmt) -> str:
    cols = [str(c) if not isinstance(c, float) else f"{c:.0e}" for c in df.columns]
    cells = {c: fmt_cell for c in df.columns}
    for c in df.columns:
        if c in (RELAXATION_STATUS, NA_COLUMN, JUDGED_COLUMN):  # a count, whatever the table's cell format
            cells[c] = lambda v: "—" if v is None or (isinstance(v, float) and math.isnan(v)) else str(int(v))
    lines = ["| " + index_name + " | " + " | ".join(cols) + " |", "|" + "---|" * (len(cols) + 1)]
    for idx, row in df.iterrows():
        lines.append(f"| {idx} | " + " | ".join(cells[c](v) for c, v in zip(df.columns, row.values)) + " |")
    return "\n".join(lines)


def _ratio_cells(numbers: dict) -> pd.DataFrame:
    """"ratio (sgm s)" cells of the normalised shifted geometric means."""
    ratio, sgm = numbers["sgm_ratio"], numbers["sgm"]
    out = ratio.copy().astype(object)
    for label in ratio.index:
        for tier in ratio.columns:
            r, t = ratio.loc[label, tier], sgm.loc[label, tier]
            out.loc[label, tier] = "—" if pd.isna(r) else f"{fmt(r)} ({fmt(t)} s)"
    return out


def write_markdown(results: Results, numbers: dict, path: str, figures: List[str]) -> str:
    shift, penalty = numbers["shift_s"], numbers["penalty_s"]
    pct = lambda v: "—" if v is None or (isinstance(v, float) and math.isnan(v)) else f"{100 * v:.0f}%"  # noqa: E731
    clock = ("from the start of setup (setup + solve)" if numbers.get("include_setup", True)
             else "solve only (setup excluded, --solve-only)")
    dropped = numbers.get("dropped_tiers") or []
    tiers_note = (f"Tiers tighter than the runs' tol ({fmt(numbers['tol'])}) are left out: "
                  + ", ".join(f"{t:.0e}" for t in dropped) + "." if dropped else
                  f"Every tier is at or above the runs' tol ({fmt(numbers.get('tol'))}).")
    parts = [f"# Profiles: {results.suite.get('name', os.path.basename(os.path.normpath(results.path)))}", "",
             f"{len(results.runs)} runs, {len(results.snapshots())} snapshots, {len(numbers['labels'])} solver labels. "
             "Tiers are on the accuracy error e measured on the original QP (docs/accuracy.md: residual "
             f"lengths as a fraction of the scene size); times are read off the histories, {clock}. "
             + tiers_note, "",
             "## Success rate per tier", "",
             f"Every solver is judged on the same problems: all {len(results.snapshots())} of the suite but those "
             "of a class it does not take (`not_applicable`, column n/a); column `judged` gives the count. A run "
             "with status `solved_relaxation` (tol met only on a problem the solver changed: decoupled rows, or J "
             "ignored) is judged like any other, on the accuracy error e of the original QP: it reaches a tier "
             "only if it brought e there (column `solved_relaxation` counts them).", "",
             _table(numbers["success"], "label", pct), "",
             f"## Time to tier: shifted geometric mean, normalised to the best solver "
             f"(shift = {shift:.3g} s = {numbers.get('shift_rule', 'given')}; failures count {penalty:g} s)", "",
             "Cell: sgm / best sgm of the tier (sgm in seconds).", "",
             _table(_ratio_cells(numbers), "label"), "",
             "## Time to tier: median over the runs that reached it [s]", "", _table(numbers["median"], "label"), "",
             "## Status honesty", "",
             "Of the runs whose solver said `converged`: confirmed on the original QP (status `converged`), "
             "met on the solver's own problem only (`solved_relaxation`), and the share confirmed.", ""]
    hon = numbers["honesty"]
    if hon.empty:
        parts.append("(no runs)")
    else:
        parts.append("| label | runs | said converged | confirmed | solved relaxation | share |")
        parts.append("|---|---|---|---|---|---|")
        for _, r in hon.iterrows():
            parts.append(f"| {r['label']} | {r['runs']} | {r['converged']} | {r['confirmed']} | {r['relaxation']} "
                         f"| {pct(r['share'])} |")
        runs = results.runs
        said = runs["solver_status"] if "solver_status" in runs else runs["status"]
        unconfirmed = runs[(said == "converged") & (runs["status"] != "converged")
                           & (runs["status"] != RELAXATION_STATUS)
                           | ((runs["status"] == "converged") & (~runs["status_confirmed"].map(bool)))]
        if not unconfirmed.empty:
            parts += ["", "Unconfirmed `converged` claims:", ""]
            for _, r in unconfirmed.iterrows():
                parts.append(f"- {r['snapshot']} / {r['label']}: error {fmt(r.get('accuracy'))} (tol {fmt(r.get('tol'))})")
    no_work = figutil.work_left_out(numbers["labels"], figutil.label_solvers(results.runs))
    if no_work:
        parts += ["", "Left out of the data profiles (work not counted in full): "
                  + "; ".join(f"`{k}`: {v}" for k, v in no_work.items()) + "."]
    parts += ["", "## Figures", ""]
    for f in figures:
        if f.endswith(".png"):
            parts.append(f"![{os.path.basename(f)}]({os.path.relpath(f, os.path.dirname(path))})")
    text = "\n".join(parts) + "\n"
    with open(path, "w", encoding="utf-8") as f:
        f.write(text)
    return text


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("results")
    parser.add_argument("--shift", type=float, default=None,
                        help=f"shift [s] of the geometric mean (default: {SHIFT_FRACTION:g} x the median time-to-tier)")
    parser.add_argument("--solve-only", action="store_true", help="time to tier without setup (labelled so)")
    parser.add_argument("--out", help="figure folder (default RESULTS/figures)")
    args = parser.parse_args(argv)
    try:
        results = load_results(args.results)
    except (FileNotFoundError, ValueError) as err:
        print(f"profiles.py: {err}", file=sys.stderr)
        return 2
    if results.runs.empty:
        print(f"profiles.py: {args.results}: no runs", file=sys.stderr)
        return 2
    numbers = compute(results, args.shift, include_setup=not args.solve_only)
    figures = plot_profiles(numbers, args.out or os.path.join(args.results, "figures"), results.runs)
    md = os.path.join(args.results, "profiles.md")
    write_markdown(results, numbers, md, figures)
    print(f"profiles.py: shift of the geometric mean = {numbers['shift_s']:.3g} s ({numbers['shift_rule']}); "
          f"wrote {md}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
