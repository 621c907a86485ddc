#!/usr/bin/python3
"""Fig. 9: MPRGP's native residual ||phi + beta|| against iterations, with and without Jacobi
preconditioning, on the Fig. 8 QP (labels mprgp-jacobi and mprgp-none of suites/paper/fig8.json).

usage: fig9.py RESULTS_DIR [--data DIR] [--out DIR]
"""
from __future__ import annotations

import sys


import numpy as np  # noqa: E402

from plots import figutil  # noqa: E402
from plots.claims import Claim, verdict_threshold  # noqa: E402
from plots.figutil import fmt, plt  # noqa: E402
from plots.loader import measured  # noqa: E402
from plots.paper_context import FigureOutcome, NotProduced, PaperContext, run_standalone  # noqa: E402
from plots.fig8 import MPRGP, MPRGP_NONE, pick_snapshot  # noqa: E402

SUITE = "fig8"
#: "significantly improve": the unpreconditioned run needs at least this many times the iterations
SIGNIFICANT = 1.5


def produce(ctx: PaperContext) -> FigureOutcome:
    res = ctx.require_results(SUITE)
    snap = pick_snapshot(res)
    ran = set(measured(res.runs[res.runs["snapshot"] == snap])["label"])
    hj, hn = res.history(snap, MPRGP), res.history(snap, MPRGP_NONE)
    if hj.empty or hn.empty or not {MPRGP, MPRGP_NONE} <= ran:
        raise NotProduced(f"suite '{SUITE}': histories of '{MPRGP}' and '{MPRGP_NONE}' needed on {snap}")
    out = FigureOutcome("fig9", "Fig. 9: ||phi + beta|| with and without preconditioning")
    fig, axes = plt.subplots(1, 2, figsize=(7.0, 2.8), squeeze=False)
    for ax, x, xlabel in ((axes[0, 0], "iteration", "iterations (count)"), (axes[0, 1], "time_s", "time [s] (solve)")):
        ax.plot(hj[x], figutil.positive(hj["native_residual"]), "-", color=figutil.solver_colour("mprgp"),
                label="mprgp, Jacobi")
        ax.plot(hn[x], figutil.positive(hn["native_residual"]), "--", color=figutil.solver_colour("mprgp"),
                label="mprgp, no precond")
        ax.set_yscale("log")
        ax.set_xlabel(xlabel)
        ax.set_ylabel("||phi + beta||_2 [units of b]")  # the QP's gradient: b's unit
        ax.grid(True, which="both", alpha=0.3)
    run0 = res.runs[res.runs["snapshot"] == snap].iloc[0]
    mrun = res.runs[(res.runs["snapshot"] == snap) & (res.runs["label"] == MPRGP)].iloc[0]
    fig.suptitle(figutil.panel_title(snap, run0.get("n"), run0.get("m"), width=80), fontsize=9)
    fig.tight_layout()
    figutil.legend_outside(fig, axes.flat)
    out.files += figutil.save_figure_outside(fig, ctx.fig_dir, "fig9_preconditioning")

    # compare at the smallest residual both runs reached
    final_j = float(np.nanmin(figutil.positive(hj["native_residual"])))
    final_n = float(np.nanmin(figutil.positive(hn["native_residual"])))
    level = max(final_j, final_n)
    it_j = figutil.first_reach(hj, "native_residual", level, "iteration")
    it_n = figutil.first_reach(hn, "native_residual", level, "iteration")
    ratio = it_n / it_j if it_j and np.isfinite(it_j) else float("nan")
    statuses = {lab: res.runs[(res.runs["snapshot"] == snap) & (res.runs["label"] == lab)].iloc[0]["status"]
                for lab in (MPRGP, MPRGP_NONE)}
    out.claims.append(Claim(
        key="fig9-preconditioning",
        claim="Jacobi preconditioning significantly improves MPRGP's convergence",
        source="Sec. 6.1 (\"this simple preconditioning scheme can significantly improve the convergence\"), Fig. 9",
        paper="significant improvement (no number)",
        authors="— (no Fig. 9 data in the authors' files)",
        ours=(f"iterations to ||phi+beta|| = {level:.2e}: Jacobi {fmt(it_j)} ({statuses[MPRGP]}), none "
              f"{fmt(it_n)} ({statuses[MPRGP_NONE]}); ratio {fmt(ratio)}"),
        verdict=verdict_threshold(ratio, SIGNIFICANT),
        judged_on=(f"one QP, {snap} (n = {fmt(run0['n'])}, m = {fmt(run0['m'])}): both runs are mprgp on the same "
                   "rows (" + (f"its {mrun.get('solved_problem')} QP" if isinstance(mrun.get("solved_problem"), str)
                               else "the original QP") + "), judged on that problem's native residual ||phi+beta||"),
        threshold=SIGNIFICANT, estimate=ratio if np.isfinite(ratio) else None,
        rule=f"holds when the unpreconditioned run needs >= {SIGNIFICANT}x the iterations to the smallest "
             "residual both reached"))
    return out


if __name__ == "__main__":
    sys.exit(run_standalone(produce, sys.argv[1:], SUITE, __doc__.splitlines()[0]))
