#!/usr/bin/python3
"""Suite-wide comparisons of a results folder (DESIGN.md "Metrics", "Across a suite").

- success rate per accuracy tier (accuracy error e on the original QP, docs/accuracy.md: 1e-2, 1e-4,
  1e-6, 1e-8 of the scene size) and time to reach each tier, read off the histories (the final point
  when a run has no history). A `solved_relaxation` run (tol met only on a problem the solver changed)
  is neither a success nor a failure: it is left out of the success rates, the geometric means and
  the profiles' denominators, and counted in its own column;
- shifted geometric mean of those times, sgm = exp(mean(log(t + s))) - s, with the shift s stated
  (10 s by default, as qpbenchmark); a run that never reaches a tier counts at the penalty time
  (the suite's time_limit_s, else the largest time seen), as qpbenchmark counts failures;
- Dolan-More performance profiles: rho_s(tau) = share of problems with t_ps / min_s t_ps <= tau;
- More-Wild data profiles: share of problems solved to a tier within a budget of A-products;
- "status honesty": of the runs whose solver said "converged", how many the measure confirms on the
  original QP (converged), on the solver's own problem only (solved_relaxation), or not at all
  (unconfirmed).

usage: profiles.py RESULTS_DIR [--shift 10] [--out FIGDIR]
Writes RESULTS_DIR/profiles.md and FIGDIR/profiles_{performance,data}.{png,pdf}.
"""
from __future__ import annotations

import argparse
import math
import os
import sys
from typing import Dict, Iterable, List


import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

from plots import figutil  # noqa: E402
from plots.figutil import TIERS, fmt, plt  # noqa: E402
from plots.loader import RELAXATION_STATUS, Results, load_results  # noqa: E402

DEFAULT_SHIFT_S = 10.0


def shifted_geomean(values: Iterable[float], shift: float = DEFAULT_SHIFT_S) -> float:
    """exp(mean(log(v + shift))) - shift; NaN for an empty input."""
    v = np.asarray(list(values), dtype=float)
    if v.size == 0:
        return float("nan")
    if np.any(v + shift <= 0):
        raise ValueError(f"shifted_geomean: values + shift must be > 0 (shift {shift}, min {v.min()})")
    return float(np.exp(np.mean(np.log(v + shift))) - shift)


def tier_table(results: Results, tiers=TIERS) -> pd.DataFrame:
    """One row per (snapshot, label, tier): reached, time_s and a_products when first reached;
    relaxation = the run is solved_relaxation (neither success nor failure)."""
    rows = []
    for _, run in results.runs.iterrows():
        snap, label = run["snapshot"], run["label"]
        relaxation = run.get("status", "") == RELAXATION_STATUS
        h = results.history(snap, label)
        final_ok = bool(np.isfinite(run.get("kkt_rel", np.nan))) and not bool(run.get("nonfinite", False))
        for tier in tiers:
            t = a = float("nan")
            if not h.empty and "kkt_rel" in h:
                t = figutil.first_reach(h, "kkt_rel", tier, "time_s")
                a = figutil.first_reach(h, "kkt_rel", tier, "a_products")
            if math.isnan(t) and final_ok and run.get("kkt_rel", np.inf) <= tier:
                # no history, or the history's stride skipped the point: the final point counts
                t = float(run.get("time_s", np.nan))
                a = float(run.get("a_products", np.nan))
            if relaxation:
                t = a = float("nan")
            rows.append({"snapshot": snap, "label": label, "tier": tier, "reached": not math.isnan(t),
                         "time_s": t, "a_products": a, "relaxation": relaxation})
    return pd.DataFrame(rows, columns=["snapshot", "label", "tier", "reached", "time_s", "a_products",
                                       "relaxation"])


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
    """Problems each solver is judged on: all of them minus its solved_relaxation runs."""
    if excluded is None:
        return {s: max(1, count) for s in columns}
    return {s: max(1, count - int(excluded[s].fillna(False).astype(bool).sum()) if s in excluded else count)
            for s in columns}


def performance_profile(ratios: pd.DataFrame, taus: np.ndarray, excluded: pd.DataFrame = None) -> pd.DataFrame:
    """rho_s(tau) for each tau (rows) and solver (columns); `excluded` (problems x solvers, True for
    solved_relaxation runs) leaves those runs out of the solver's denominator."""
    n = _denominators(ratios.columns, len(ratios), excluded)
    return pd.DataFrame({s: [(ratios[s] <= tau).sum() / n[s] for tau in taus] for s in ratios.columns},
                        index=taus)


def data_profile(work: pd.DataFrame, budgets: np.ndarray, excluded: pd.DataFrame = None) -> pd.DataFrame:
    """work: index = problems, columns = solvers, NaN = not solved. Share solved within each budget
    (solved_relaxation runs, marked in `excluded`, are left out of the denominator)."""
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


def compute(results: Results, shift: float = DEFAULT_SHIFT_S, tiers=TIERS) -> Dict[str, object]:
    """All numbers of profiles.md, as DataFrames."""
    tt = tier_table(results, tiers)
    labels = results.labels()
    penalty = penalty_time(results)
    success, sgm, median = {}, {}, {}
    judged = tt[~tt["relaxation"].astype(bool)]  # solved_relaxation: neither success nor failure
    for tier in tiers:
        sel = judged[judged["tier"] == tier]
        success[tier] = sel.groupby("label")["reached"].mean().reindex(labels)
        times = sel.assign(t=sel["time_s"].where(sel["reached"], penalty))
        sgm[tier] = times.groupby("label")["t"].apply(lambda s: shifted_geomean(s, shift)).reindex(labels)
        median[tier] = sel[sel["reached"]].groupby("label")["time_s"].median().reindex(labels)
    success_table = pd.DataFrame(success)
    first = tt[tt["tier"] == tiers[0]] if len(tt) else tt
    success_table[RELAXATION_STATUS] = (first.groupby("label")["relaxation"].sum().reindex(labels)
                                        if len(first) else pd.Series(0, index=labels))
    return {"tiers": tt, "labels": labels, "penalty_s": penalty, "shift_s": shift,
            "success": success_table, "sgm": pd.DataFrame(sgm), "median": pd.DataFrame(median),
            "honesty": status_honesty(results.runs) if not results.runs.empty else pd.DataFrame()}


def cost_matrix(tt: pd.DataFrame, tier: float, column: str = "time_s") -> pd.DataFrame:
    sel = tt[tt["tier"] == tier]
    return sel.pivot_table(index="snapshot", columns="label", values=column, aggfunc="first", dropna=False)


def relaxation_matrix(tt: pd.DataFrame, tier: float) -> pd.DataFrame:
    """problems x solvers, True where the run is solved_relaxation."""
    sel = tt[tt["tier"] == tier].assign(relaxation=lambda d: d["relaxation"].astype(float))
    return sel.pivot_table(index="snapshot", columns="label", values="relaxation", aggfunc="first",
                           dropna=False) > 0


def plot_profiles(numbers: dict, out_dir: str) -> List[str]:
    tt, labels, tiers = numbers["tiers"], numbers["labels"], sorted(set(numbers["tiers"]["tier"]), reverse=True)
    colours = {label: f"C{i % 10}" for i, label in enumerate(labels)}
    written = []
    # Dolan-More: time to each tier
    fig, axes = plt.subplots(1, len(tiers), figsize=(4 * len(tiers), 3.3), squeeze=False)
    for ax, tier in zip(axes.flat, tiers):
        cost = cost_matrix(tt, tier).reindex(columns=labels)
        ratios = performance_ratios(cost)
        finite = ratios.replace(np.inf, np.nan).stack()
        top = max(2.0, float(finite.max()) * 1.2) if not finite.empty else 2.0
        taus = np.logspace(0, math.log10(top), 200)
        prof = performance_profile(ratios, taus, relaxation_matrix(tt, tier).reindex(columns=labels))
        for label in labels:
            ax.step(taus, prof[label], where="post", color=colours[label], label=label)
        ax.set_xscale("log")
        ax.set_ylim(-0.02, 1.02)
        ax.set_xlabel("tau (time / best time)")
        ax.set_title(f"performance profile, error e <= {tier:g}", fontsize=9)
        ax.grid(True, alpha=0.3)
    axes.flat[0].set_ylabel("share of problems")
    axes.flat[0].legend(fontsize=7)
    fig.tight_layout()
    written += figutil.save_figure(fig, out_dir, "profiles_performance")
    # More-Wild: A-products budget
    fig, axes = plt.subplots(1, len(tiers), figsize=(4 * len(tiers), 3.3), squeeze=False)
    for ax, tier in zip(axes.flat, tiers):
        work = cost_matrix(tt, tier, "a_products").reindex(columns=labels)
        vals = work.stack()
        hi = max(10.0, float(vals.max()) * 1.5) if not vals.empty else 10.0
        budgets = np.logspace(0, math.log10(hi), 200)
        prof = data_profile(work, budgets, relaxation_matrix(tt, tier).reindex(columns=labels))
        for label in labels:
            ax.step(budgets, prof[label], where="post", color=colours[label], label=label)
        ax.set_xscale("log")
        ax.set_ylim(-0.02, 1.02)
        ax.set_xlabel("budget [A-products]")
        ax.set_title(f"data profile, error e <= {tier:g}", fontsize=9)
        ax.grid(True, alpha=0.3)
    axes.flat[0].set_ylabel("share of problems solved")
    axes.flat[0].legend(fontsize=7)
    fig.tight_layout()
    written += figutil.save_figure(fig, out_dir, "profiles_data")
    return written


def _table(df: pd.DataFrame, index_name: str, fmt_cell=fmt) -> str:
    cols = [str(c) if not isinstance(c, float) else f"{c:.0e}" for c in df.columns]
    cells = {c: fmt_cell for c in df.columns}
    for c in df.columns:
        if c == RELAXATION_STATUS:  # a count, whatever the table's cell format
            cells[c] = lambda v: "—" if v is None or (isinstance(v, float) and math.isnan(v)) else str(int(v))
    lines = ["| " + index_name + " | " + " | ".join(cols) + " |", "|" + "---|" * (len(cols) + 1)]
    for idx, row in df.iterrows():
        lines.append(f"| {idx} | " + " | ".join(cells[c](v) for c, v in zip(df.columns, row.values)) + " |")
    return "\n".join(lines)


def write_markdown(results: Results, numbers: dict, path: str, figures: List[str]) -> str:
    shift, penalty = numbers["shift_s"], numbers["penalty_s"]
    pct = lambda v: "—" if v is None or (isinstance(v, float) and math.isnan(v)) else f"{100 * v:.0f}%"  # noqa: E731
    parts = [f"# Profiles: {results.suite.get('name', os.path.basename(os.path.normpath(results.path)))}", "",
             f"{len(results.runs)} runs, {len(results.snapshots())} snapshots, {len(numbers['labels'])} solver labels. "
             "Tiers are on the accuracy error e measured on the original QP (docs/accuracy.md: residual "
             "lengths as a fraction of the scene size); times are solver times read off the histories.", "",
             "## Success rate per tier", "",
             "Runs with status `solved_relaxation` (tol met only on a problem the solver changed: decoupled "
             "rows, or J ignored) are neither successes nor failures: they are left out of the rates, the "
             "means and the profiles, and counted in their own column.", "",
             _table(numbers["success"], "label", pct), "",
             f"## Time to tier: shifted geometric mean [s] (shift = {shift:g} s; failures count {penalty:g} s)", "",
             _table(numbers["sgm"], "label"), "",
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
                parts.append(f"- {r['snapshot']} / {r['label']}: error {fmt(r.get('kkt_rel'))} (tol {fmt(r.get('tol'))})")
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
    parser.add_argument("--shift", type=float, default=DEFAULT_SHIFT_S, help="shift [s] of the geometric mean")
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
    numbers = compute(results, args.shift)
    figures = plot_profiles(numbers, args.out or os.path.join(args.results, "figures"))
    md = os.path.join(args.results, "profiles.md")
    write_markdown(results, numbers, md, figures)
    print(f"profiles.py: shift of the geometric mean = {args.shift:g} s; wrote {md}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
