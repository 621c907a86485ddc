#!/usr/bin/python3
"""Fig. 10: error against time of MPRGP and ICA on one long-cube QP (suites/paper/fig10.json),
on each solver's native residual (MPRGP ||phi+beta||_2, ICA ||Ax-b-J'lambda||_2, absolute, as the
paper plots them) and on the common relative KKT error; the time to reach 1e-2 on both.

usage: fig10.py RESULTS_DIR [--data DIR] [--out DIR]
"""
from __future__ import annotations

import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import numpy as np  # noqa: E402

import figutil  # noqa: E402
from claims import (DOES_NOT_HOLD, HOLDS, HOLDS_NATIVE_ONLY, NOT_MEASURED, Claim)  # noqa: E402
from figutil import fmt, plt  # noqa: E402
from paper_context import FigureOutcome, NotProduced, PaperContext, run_standalone  # noqa: E402

SUITE = "fig10"
MPRGP = "mprgp"
#: Sec. 6.2: "we can not obtain physically plausible results until the residual ... is smaller than 10^-2"
LEVEL = 1e-2
#: Sec. 6.2: "more than one order of magnitude faster than ICA"
FACTOR = 10.0


def pick_snapshot(res):
    runs = res.runs.sort_values(["m", "snapshot"], ascending=[False, True])
    return runs.iloc[0]["snapshot"]


def speedup(res, snap, ica_label, column):
    """(ica time / mprgp time to LEVEL on column, is_lower_bound). When ICA never reaches it, its
    whole run time gives a lower bound; when MPRGP never reaches it, NaN."""
    hm, hi = res.history(snap, MPRGP), res.history(snap, ica_label)
    tm = figutil.first_reach(hm, column, LEVEL)
    ti = figutil.first_reach(hi, column, LEVEL)
    if not np.isfinite(tm) or tm <= 0:
        return float("nan"), False, tm, ti
    if np.isfinite(ti):
        return ti / tm, False, tm, ti
    total = float(res.runs[(res.runs["snapshot"] == snap) & (res.runs["label"] == ica_label)]["time_s"].iloc[0])
    return total / tm, True, tm, ti


def produce(ctx: PaperContext) -> FigureOutcome:
    res = ctx.require_results(SUITE)
    snap = pick_snapshot(res)
    labels = [lab for lab in res.labels() if not res.history(snap, lab).empty]
    icas = [lab for lab in labels if lab.startswith("ica")]
    if MPRGP not in labels or not icas:
        raise NotProduced(f"suite '{SUITE}': histories of '{MPRGP}' and an 'ica*' label needed on {snap}")
    run0 = res.runs[res.runs["snapshot"] == snap].iloc[0]
    out = FigureOutcome("fig10", "Fig. 10: MPRGP vs ICA, error against time")
    fig, axes = plt.subplots(1, 2, figsize=(11, 3.8), squeeze=False)
    for ax, column, ylabel in ((axes[0, 0], "native_residual", "native residual (absolute)"),
                               (axes[0, 1], "kkt_rel", "common relative KKT error")):
        for i, lab in enumerate(labels):
            h = res.history(snap, lab)
            ax.plot(h["time_s"], figutil.positive(h[column]), "-", color=f"C{i}", label=lab, lw=1.3)
        ax.axhline(LEVEL, color="grey", lw=0.7)
        ax.set_xscale("symlog", linthresh=1e-3)
        ax.set_yscale("log")
        ax.set_xlabel("time [s]")
        ax.set_ylabel(ylabel)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7)
    fig.suptitle(f"{snap}: n = {fmt(run0['n'])}, m = {fmt(run0['m'])}", fontsize=9)
    fig.tight_layout()
    out.files += figutil.save_figure(fig, ctx.fig_dir, "fig10_mprgp_vs_ica")
    if not run0["m"] > 0:
        out.notes.append(f"warning: the selected QP {snap} has no contact rows (m = 0): the simulation "
                         "produced no contact in the frames simulated")

    ica = icas[0]
    r_nat, lb_nat, tm_nat, ti_nat = speedup(res, snap, ica, "native_residual")
    r_kkt, lb_kkt, tm_kkt, ti_kkt = speedup(res, snap, ica, "kkt_rel")
    show = lambda r, lb: ("> " if lb else "") + fmt(r)  # noqa: E731
    if not np.isfinite(r_kkt) and not np.isfinite(r_nat):
        verdict = NOT_MEASURED
    elif np.isfinite(r_kkt) and r_kkt >= FACTOR:
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
              f"common KKT {show(r_kkt, lb_kkt)}x (mprgp {fmt(tm_kkt)} s, ica {fmt(ti_kkt)} s)"),
        verdict=verdict,
        rule=f"holds when the ratio on the common KKT error >= {FACTOR:g}; 'only on native residuals' when "
             "only the native ratio is ('> x': ICA never reached 1e-2, its run time is a lower bound)"))
    rows = ["| label | status | time to 1e-2 native [s] | time to 1e-2 KKT [s] | final KKT rel | time [s] | setup [s] |",
            "|---|---|---|---|---|---|---|"]
    for lab in labels:
        h = res.history(snap, lab)
        r = res.runs[(res.runs["snapshot"] == snap) & (res.runs["label"] == lab)].iloc[0]
        rows.append(f"| {lab} | {r['status']} | {fmt(figutil.first_reach(h, 'native_residual', LEVEL))} | "
                    f"{fmt(figutil.first_reach(h, 'kkt_rel', LEVEL))} | {fmt(r['kkt_rel'])} | {fmt(r['time_s'])} | "
                    f"{fmt(r['setup_s'])} |")
    out.tables.append("\n".join(rows))
    return out


if __name__ == "__main__":
    sys.exit(run_standalone(produce, sys.argv[1:], SUITE, __doc__.splitlines()[0]))
