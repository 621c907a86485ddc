#!/usr/bin/python3
"""The frictional suite's numbers (issue 48 item 6, issue 45 item 3; docs/friction.md "The frictional
suite"): performance profiles on time to a tolerance in Acary, Bremond, Huber's form (2018), the
table of every run, and the claim row on MPRGP-based against Siconos' frictional solvers.

Acary et al. run each solver once per tolerance and count a run as solved when its error is at or
below the tolerance; so does this module, on the final point of the suite's runs at each tolerance
(one results folder per tolerance and round). A run is judged by a measure, not by its status:
- "fclib": FCLIB's relative natural-map error, the field's measure, as the harness computes it
  (the record's `fclib_error`, docs/peers.md "Frictional problems");
- "e": our frictional accuracy error e (the record's `accuracy.max`, docs/accuracy.md).
Each solver stops on its own criterion at the suite's tol, so a run may reach one measure and not
the other: both are reported. A run that does not reach the tolerance counts as failed (ratio
infinite). `not_applicable` runs leave the solver's denominator. Labels whose every run is
`solved_relaxation` (frictionless solvers: they solve the problem with mu = 0) are frictionless:
left out of the profiles and named beside them.

A library of plots/friction_suite.py (which runs the suite and writes the report).
"""
from __future__ import annotations

import glob
import json
import math
import os
from typing import Dict, Iterable, List, Optional, Sequence

import numpy as np
import pandas as pd

from plots import claims, figutil
from plots.profiles import performance_profile, performance_ratios

#: the measures a run is judged by: column of the record table, and the text of the figures
MEASURES = {"fclib": "FCLIB relative error", "e": "frictional error e"}
NOT_APPLICABLE = "not_applicable"
RELAXATION = "solved_relaxation"
#: solver-name prefixes of the families the claim compares
MPRGP_PREFIX = "mprgp"
SICONOS_PREFIX = "siconos-"


def read_records(folder: str) -> pd.DataFrame:
    """One row per run record of a results folder (runs/*.json): snapshot, label, solver, status,
    solver_status, iterations, time_s (setup + solve, the median of the repeats), samples (every
    repeat's total time), e (accuracy.max), fclib (fclib_error), tol."""
    rows = []
    for path in sorted(glob.glob(os.path.join(folder, "runs", "*.json"))):
        with open(path, encoding="utf-8") as f:
            rec = json.load(f)
        acc = rec.get("accuracy")
        e = acc.get("max") if isinstance(acc, dict) else acc
        t = rec.get("time") or {}
        rows.append({"snapshot": (rec.get("snapshot") or {}).get("id", ""), "label": rec.get("label", ""),
                     "solver": rec.get("solver", ""), "status": rec.get("status", ""),
                     "solver_status": rec.get("solver_status", ""), "iterations": rec.get("iterations"),
                     "time_s": _num(t.get("total_s")), "samples": t.get("samples_total_s") or [_num(t.get("total_s"))],
                     "e": _num(e), "fclib": _num(rec.get("fclib_error")), "tol": _num(rec.get("tol")),
                     "message": rec.get("message", "")})
    return pd.DataFrame(rows, columns=["snapshot", "label", "solver", "status", "solver_status", "iterations",
                                       "time_s", "samples", "e", "fclib", "tol", "message"])


def _num(v) -> float:
    try:
        return float(v)
    except (TypeError, ValueError):
        return float("nan")


def reached(runs: pd.DataFrame, tol: float, measure: str) -> pd.Series:
    """Whether each run's final point is at or below tol by the measure (NaN, a missing error or an
    n/a run: not reached)."""
    err = pd.to_numeric(runs[measure], errors="coerce")
    return (err <= tol) & np.isfinite(err) & (runs["status"] != NOT_APPLICABLE)


def frictionless_labels(runs: pd.DataFrame) -> List[str]:
    """Labels every judged run of which solved the frictionless relaxation (solved_relaxation)."""
    out = []
    for label, g in runs.groupby("label", sort=False):
        judged = g[g["status"] != NOT_APPLICABLE]
        if len(judged) and (judged["status"] == RELAXATION).all():
            out.append(str(label))
    return out


def cost_tables(runs: pd.DataFrame, tol: float, measure: str, time_column: str = "time_s"):
    """(cost, excluded): problems x labels; cost = the run's time where it reached tol, NaN where it
    failed; excluded = True for not_applicable runs (left out of the label's denominator)."""
    ok = reached(runs, tol, measure)
    d = runs.assign(cost=runs[time_column].where(ok), na=(runs["status"] == NOT_APPLICABLE).astype(float))
    cost = d.pivot_table(index="snapshot", columns="label", values="cost", aggfunc="first", dropna=False)
    na = d.pivot_table(index="snapshot", columns="label", values="na", aggfunc="first", dropna=False) > 0
    labels = list(dict.fromkeys(runs["label"]))
    problems = list(dict.fromkeys(runs["snapshot"]))
    return cost.reindex(index=problems, columns=labels), na.reindex(index=problems, columns=labels).fillna(False)


def profile(runs: pd.DataFrame, tol: float, measure: str, taus: Sequence[float]) -> pd.DataFrame:
    """Dolan-More rho_s(tau): the share of the problems (n/a left out) a label solved to tol within
    tau times the best time on that problem; a failed run never counts."""
    cost, na = cost_tables(runs, tol, measure)
    return performance_profile(performance_ratios(cost), np.asarray(taus, dtype=float), na)


def draw(panels: Dict[float, pd.DataFrame], measures: Iterable[str], out_dir: str, stem: str,
         left_out: Iterable[str] = ()) -> List[str]:
    """One panel per (measure, tol): rows the measures, columns the tolerances. `panels` maps a tol
    to the runs at that tol (frictionless labels already removed)."""
    measures = list(measures)
    tols = sorted(panels, reverse=True)
    fig, axes = figutil.plt.subplots(len(measures), len(tols), figsize=(7.0, 2.4 * len(measures)), squeeze=False)
    labels = list(dict.fromkeys(lab for runs in panels.values() for lab in runs["label"]))
    solvers = {lab: s for runs in panels.values() for lab, s in zip(runs["label"], runs["solver"])}
    styles = figutil.assign_styles(labels, solvers)
    for r, measure in enumerate(measures):
        for c, tol in enumerate(tols):
            ax, runs = axes[r][c], panels[tol]
            cost, na = cost_tables(runs, tol, measure)
            ratios = performance_ratios(cost)
            finite = ratios.replace(np.inf, np.nan).stack()
            top = max(10.0, float(finite.max()) * 1.5) if not finite.empty else 10.0
            xs = np.logspace(0, math.log10(top), 300)
            prof = performance_profile(ratios, xs, na)
            for label in labels:
                if label not in prof:
                    continue
                s = styles[label]
                judged = int(len(cost) - na[label].sum()) if label in na else len(cost)
                ax.step(xs, prof[label], where="post", color=s["color"], ls=s["linestyle"], lw=1.3,
                        marker=s["marker"], markevery=[len(xs) - 1], markersize=4, clip_on=False,
                        label=f"{label} ({judged} problems judged)")
            ax.set_xscale("log")
            ax.set_ylim(-0.02, 1.02)
            ax.set_xlabel("tau [1] (time / best time on the problem; setup + solve)")
            ax.set_ylabel("share of problems [1]")
            ax.set_title(f"{MEASURES[measure]} <= {tol:g}", fontsize=8)
            ax.grid(True, alpha=0.3)
    fig.tight_layout()
    title = "solver" + (f" (frictionless, left out: {', '.join(left_out)})" if left_out else "")
    figutil.legend_outside(fig, axes.flat, title=title)
    return figutil.save_figure_outside(fig, out_dir, stem)


def sgm_time(times: Iterable[float], shift: float) -> float:
    """Shifted geometric mean exp(mean(log(t + shift))) - shift of finite times."""
    v = np.asarray(list(times), dtype=float)
    return float(np.exp(np.mean(np.log(v + shift))) - shift) if v.size else float("nan")


def family_time(runs: pd.DataFrame, tol: float, measure: str, problems: Sequence[str], prefix: str,
                penalty: float, shift: float):
    """(best label, its shifted geometric mean time over `problems`, whether it failed any): the
    label of the family (solver name starting with `prefix`) with the least shifted geometric mean
    of the time to tol by the measure, a failed or n/a run counted at `penalty` seconds."""
    best = (None, float("nan"), False)
    fam = runs[runs["solver"].astype(str).str.startswith(prefix) & runs["snapshot"].isin(problems)]
    ok = reached(fam, tol, measure)
    for label, g in fam.assign(ok=ok).groupby("label", sort=True):
        t = [row.time_s if row.ok else penalty for row in g.itertuples()]
        t += [penalty] * (len(problems) - len(g))  # a problem the label did not run counts as failed
        value, failed = sgm_time(t, shift), not bool(g["ok"].all()) or len(g) < len(problems)
        if best[0] is None or value < best[1]:
            best = (str(label), value, failed)
    return best


def claim_row(rounds: List[pd.DataFrame], tol: float, measure: str, problems: Sequence[str], penalty: float,
              shift: float, problems_text: str) -> claims.Claim:
    """"An MPRGP-based frictional solver is faster than the best Siconos solver at tol on the
    problems": per round, q = (best MPRGP-based label's sgm time) / (best Siconos label's sgm time),
    judged below 1 by the report's rules (plots/claims.py judge_rounds: the median over the rounds
    and its order-statistic interval). A round whose MPRGP side failed a problem gives only a lower
    bound of q (decides only `does not hold`); one whose Siconos side failed gives an upper bound
    (decides only `holds`). Frictionless labels (frictionless_labels) are no candidates."""
    values, lower, upper, picks = [], [], [], []
    for runs in rounds:
        runs = runs[~runs["label"].isin(frictionless_labels(runs))]  # mprgp-coupled is no frictional solver  # mprgp-coupled is no frictional solver
        m_label, m_t, m_fail = family_time(runs, tol, measure, problems, MPRGP_PREFIX, penalty, shift)
        s_label, s_t, s_fail = family_time(runs, tol, measure, problems, SICONOS_PREFIX, penalty, shift)
        values.append(m_t / s_t if m_label and s_label else None)
        lower.append(m_fail and not s_fail)
        upper.append(s_fail and not m_fail)
        picks.append((m_label, s_label, m_fail and s_fail))
    j = claims.judge_rounds(values, 1.0, claims.BELOW, lower_bounds=lower)
    if any(upper) and j.verdict == claims.DOES_NOT_HOLD:
        j.verdict = claims.INCONCLUSIVE
        j.reason = "some rounds give only an upper bound (the Siconos side never reached the level) above 1"
    if any(both for _, _, both in picks) and j.verdict in claims.DECIDED:
        j.verdict = claims.INCONCLUSIVE
        j.reason = "both sides failed a problem in some round: the ratio of two penalties decides nothing"
    pairs = sorted({f"{m} / {s}" for m, s, _ in picks if m and s})
    c = claims.Claim(
        key=f"friction-mprgp-vs-siconos-{tol:g}-{measure}",
        claim=f"an MPRGP-based frictional solver is faster than the best Siconos solver at {tol:g} on the flexible frames",
        source="issue 45 Done-when", paper="— (the paper is frictionless)",
        ours=(f"time ratio {j.text()} ({j.samples} rounds; " + ", ".join(pairs) + ")") if j.estimate is not None else "—",
        verdict=j.verdict, rule=(f"per round: shifted geometric mean (shift {shift:g} s) of the time to {MEASURES[measure]} "
                                 f"<= {tol:g}, failures at {penalty:g} s, best MPRGP-based label over best Siconos "
                                 "label; holds when the median's interval is wholly below 1"),
        judged_on=problems_text)
    return c.decided_by(j, 1.0, claims.BELOW)


def fmt(v) -> str:
    return figutil.fmt(v)


def run_table(by_tol: Dict[float, pd.DataFrame], group: Optional[Dict[str, str]] = None) -> str:
    """Markdown: one row per (tol, problem, label): status, iterations, time, e, FCLIB error, and
    which of the two measures met the tol."""
    lines = ["| tol | problem | solver | status | iterations | time (s) | e | FCLIB error | met tol by |",
             "|---|---|---|---|---|---|---|---|---|"]
    for tol in sorted(by_tol, reverse=True):
        runs = by_tol[tol]
        for row in runs.itertuples():
            met = [name for name, col in (("e", "e"), ("FCLIB", "fclib"))
                   if np.isfinite(getattr(row, col)) and getattr(row, col) <= tol and row.status != NOT_APPLICABLE]
            lines.append(f"| {tol:g} | {row.snapshot} | {row.label} | {row.status} | {row.iterations} | "
                         f"{fmt(row.time_s)} | {fmt(row.e)} | {fmt(row.fclib)} | {', '.join(met) or 'neither'} |")
    return "\n".join(lines)
