#!/usr/bin/python3
"""Fig. 10: error against time of MPRGP and ICA on one long-cube QP (suites/paper/fig10.json),
on each solver's native residual (MPRGP ||phi+beta||_2, ICA ||Ax-b-J'lambda||_2, absolute, as the
paper plots them) and on the accuracy error e (docs/accuracy.md); the time to reach 1e-2 on both, taken as
the time from which the error stays below 1e-2 (ICA's stationarity is 0 at its unconstrained start).

usage: fig10.py RESULTS_DIR [--data DIR] [--out DIR]
"""
from __future__ import annotations

import os
import sys


import numpy as np  # noqa: E402

from plots import figutil  # noqa: E402
from plots.claims import (DOES_NOT_HOLD, HOLDS, HOLDS_NATIVE_ONLY, NOT_MEASURED, Claim)  # noqa: E402
from plots.figutil import fmt, plt  # noqa: E402
from plots.loader import history_time, measured, unmeasured_notes  # noqa: E402
from plots.paper_context import FigureOutcome, NotProduced, PaperContext, run_standalone  # noqa: E402

SUITE = "fig10"
MPRGP = "mprgp"
#: Sec. 6.2: "we can not obtain physically plausible results until the residual ... is smaller than 10^-2"
LEVEL = 1e-2
#: Sec. 6.2: "more than one order of magnitude faster than ICA"
FACTOR = 10.0


def pick_snapshot(res):
    runs = res.runs.sort_values(["m", "snapshot"], ascending=[False, True])
    return runs.iloc[0]["snapshot"]


def speedup(res, snap, ica_label, column, with_setup=False):
    """(ica time / mprgp time to LEVEL on column, is_lower_bound, t_mprgp, t_ica). When ICA never
    reaches it, its whole run time gives a lower bound; when MPRGP never reaches it, NaN.
    with_setup adds each run's setup_s (MPRGP's power method, ICA's unconstrained start solve,
    which the paper left untimed) to its history time."""
    hm, hi = res.history(snap, MPRGP), res.history(snap, ica_label)
    run = lambda lab: res.runs[(res.runs["snapshot"] == snap) & (res.runs["label"] == lab)].iloc[0]  # noqa: E731
    setup = lambda lab: float(run(lab)["setup_s"]) if with_setup and np.isfinite(run(lab)["setup_s"]) else 0.0  # noqa: E731

    def timed(h, lab):  # the history on the chosen clock (with or without setup, any file age)
        h = h.copy()
        h["time_s"] = history_time(h, run(lab), include_setup=with_setup)
        return h
    tm = figutil.settle_time(timed(hm, MPRGP), column, LEVEL)
    ti = figutil.settle_time(timed(hi, ica_label), column, LEVEL)
    if not np.isfinite(tm) or tm <= 0:
        return float("nan"), False, tm, ti
    if np.isfinite(ti):
        return ti / tm, False, tm, ti
    total = float(run(ica_label)["time_s"]) + (setup(ica_label) if not np.isfinite(run(ica_label)["time_s"]) else 0.0)
    return total / tm, True, tm, ti


def produce(ctx: PaperContext) -> FigureOutcome:
    res = ctx.require_results(SUITE)
    snap = pick_snapshot(res)
    ran = set(measured(res.runs[res.runs["snapshot"] == snap])["label"])
    labels = [lab for lab in res.labels() if lab in ran and not res.history(snap, lab).empty]
    icas = [lab for lab in labels if lab.startswith("ica")]
    if MPRGP not in labels or not icas:
        raise NotProduced(f"suite '{SUITE}': histories of '{MPRGP}' and an 'ica*' label needed on {snap}")
    run0 = res.runs[res.runs["snapshot"] == snap].iloc[0]
    out = FigureOutcome("fig10", "Fig. 10: MPRGP vs ICA, error against time")
    out.notes += unmeasured_notes(res.runs[res.runs["snapshot"] == snap])
    fig, axes = plt.subplots(1, 2, figsize=(11, 3.8), squeeze=False)
    for ax, column, ylabel in ((axes[0, 0], "native_residual", "native residual (absolute)"),
                               (axes[0, 1], "kkt_rel", "accuracy error e (docs/accuracy.md)")):
        for lab in labels:
            h = res.history(snap, lab)
            style = figutil.solver_style(lab, figutil.label_solvers(res.runs).get(lab))
            ax.plot(h["time_s"], figutil.positive(h[column]), color=style["color"], ls=style["linestyle"], label=lab,
                    lw=1.3)
        ax.axhline(LEVEL, color="grey", lw=0.7)
        ax.set_xscale("symlog", linthresh=1e-3)
        ax.set_xlim(left=0)
        ax.set_yscale("log")
        ax.set_xlabel("time [s]")
        ax.set_ylabel(ylabel)
        ax.grid(True, which="both", alpha=0.3)
    fig.suptitle(f"{snap}: n = {fmt(run0['n'])}, m = {fmt(run0['m'])}", fontsize=9)
    fig.tight_layout()
    figutil.legend_outside(fig, axes.flat)
    out.files += figutil.save_figure_outside(fig, ctx.fig_dir, "fig10_mprgp_vs_ica")
    if not run0["m"] > 0:
        out.notes.append(f"warning: the selected QP {snap} has no contact rows (m = 0): the simulation "
                         "produced no contact in the frames simulated")

    ica = icas[0]
    r_nat, lb_nat, tm_nat, ti_nat = speedup(res, snap, ica, "native_residual")
    r_kkt, lb_kkt, tm_kkt, ti_kkt = speedup(res, snap, ica, "kkt_rel")
    r_fair, lb_fair, tm_fair, ti_fair = speedup(res, snap, ica, "kkt_rel", with_setup=True)
    show = lambda r, lb: ("> " if lb else "") + fmt(r)  # noqa: E731
    if not np.isfinite(r_fair) and not np.isfinite(r_nat):
        verdict = NOT_MEASURED
    elif np.isfinite(r_fair) and r_fair >= FACTOR:
        verdict = HOLDS
    elif np.isfinite(r_nat) and r_nat >= FACTOR:
        verdict = HOLDS_NATIVE_ONLY
    else:
        verdict = DOES_NOT_HOLD
    authors = ctx.authors_csv("fig11_mprgp_vs_ica.csv")
    a_text = "—"
    if authors is not None and not authors.empty:
        ratio = authors["ica_time_s"] / authors["mprgp_time_s"]
        a_text = (f"no long-cube data; on the two-dino QPs ICA/MPRGP time to 8e-5 native = "
                  f"{fmt(ratio.min())}-{fmt(ratio.max())}x")
    out.claims.append(Claim(
        key="fig10-ica-10x",
        claim="To residual 1e-2, MPRGP is more than 10x faster than ICA",
        source="Sec. 6.2 (\"more than one order of magnitude faster than ICA\"), Fig. 10",
        paper="> 10x at residual 1e-2",
        authors=a_text,
        ours=(f"{ica}/mprgp time to 1e-2: native {show(r_nat, lb_nat)}x (mprgp {fmt(tm_nat)} s, ica {fmt(ti_nat)} s); "
              f"accuracy error e {show(r_kkt, lb_kkt)}x (mprgp {fmt(tm_kkt)} s, ica {fmt(ti_kkt)} s); "
              f"accuracy error e with setup timed {show(r_fair, lb_fair)}x (mprgp {fmt(tm_fair)} s, ica {fmt(ti_fair)} s)"),
        verdict=verdict,
        rule=f"times are those from which the error stays <= {LEVEL:g}; holds when the ratio on the accuracy "
             f"error e, setup (power method, ICA's unconstrained start) timed, is >= {FACTOR:g}; 'only on native "
             "residuals' when only the native ratio with the paper's timing is ('> x': ICA never reached 1e-2, "
             "its run time is a lower bound)"))
    rows = ["| label | status | time to 1e-2 native [s] | time to e <= 1e-2 [s] | final accuracy error e | time [s] | setup [s] |",
            "|---|---|---|---|---|---|---|"]
    for lab in labels:
        h = res.history(snap, lab)
        r = res.runs[(res.runs["snapshot"] == snap) & (res.runs["label"] == lab)].iloc[0]
        rows.append(f"| {lab} | {r['status']} | {fmt(figutil.settle_time(h, 'native_residual', LEVEL))} | "
                    f"{fmt(figutil.settle_time(h, 'kkt_rel', LEVEL))} | {fmt(r['kkt_rel'])} | {fmt(r['time_s'])} | "
                    f"{fmt(r['setup_s'])} |")
    out.tables.append("\n".join(rows))
    return out


if __name__ == "__main__":
    sys.exit(run_standalone(produce, sys.argv[1:], SUITE, __doc__.splitlines()[0]))
