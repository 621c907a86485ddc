#!/usr/bin/python3
"""Fig. 11: time (and A-products) of MPRGP and ICA against the number of DOFs, on the frame-11 QPs
of the two-dinosaur scenes at several resolutions (suites/paper/fig11.json), with the power
method's share (setup_s, counters.power_products) shown apart, and the authors' points
(figures/fig11_mprgp_vs_ica.csv) beside ours.

Labels: mprgp-published / ica-published (native stopping at the authors' absolute 8e-5, MPRGP's
cold-start power method as the authors ran it), mprgp-fair / ica-fair (stopping on the accuracy
error e of docs/accuracy.md).

usage: fig11.py RESULTS_DIR [--data DIR] [--out DIR]
"""
from __future__ import annotations

import sys


import numpy as np  # noqa: E402

from plots import figutil  # noqa: E402
from plots.claims import BELOW, INCONCLUSIVE, NOT_MEASURED, Claim, combine_published_fair, combined_reason, \
    judge_rounds, withdraw_quick  # noqa: E402
from plots.figutil import fmt, plt  # noqa: E402
from plots.loader import history_time, measured, status_notes, unmeasured_notes  # noqa: E402
from plots.paper_context import FigureOutcome, NotProduced, PaperContext, median_over_rounds, run_standalone  # noqa: E402

SUITE = "fig11"
PAIRS = {"published": ("mprgp-published", "ica-published"), "fair": ("mprgp-fair", "ica-fair")}
#: the fair reading times each run to the level from which its accuracy error e on the original QP
#: stays below this (Sec. 6.2's "physically plausible" residual, as in Fig. 10), setup + solve
FAIR_LEVEL = 1e-2
#: the advantage grows when ICA/MPRGP at the largest DOF count / the same at the smallest is above 1
GROWTH = 1.0
#: quick mode: resolutions whose largest / smallest DOF count is below this are too close for a growth
#: that a full run (the authors' 7818 to 81000 DOF) could not reverse
QUICK_SPAN = 2.0
#: quick mode: a fair run whose final e is within this factor of FAIR_LEVEL (either side) crossed or
#: missed the level by a margin another problem could turn around
QUICK_E_MARGIN = 2.0
#: the x axis of every panel
DOF_LABEL = "degrees of freedom n (count)"


def by_dof(runs, label):
    sel = measured(runs[runs["label"] == label]).copy()
    return sel.sort_values("n")


def fair_time(res, run) -> float:
    """Setup + solve time from which the run's e stays <= FAIR_LEVEL (NaN when it never does)."""
    h = res.history(run["snapshot"], run["label"])
    if h.empty:
        return float(run["time_s"]) if run.get("accuracy", np.inf) <= FAIR_LEVEL else float("nan")
    return figutil.settle_time(h.assign(time_s=history_time(h, run, include_setup=True)), "accuracy", FAIR_LEVEL)


def ratios(res, mprgp, ica, mode="published"):
    """ICA time / MPRGP time per DOF count (ascending). published: each run's whole time (setup +
    solve) to its native stop; fair: the time to e <= FAIR_LEVEL on the original QP (fair_time)."""
    runs = res.runs
    m, i = by_dof(runs, mprgp), by_dof(runs, ica)
    if m.empty or i.empty:
        return None
    if mode == "fair":
        m = m.assign(time_s=[fair_time(res, r) for _, r in m.iterrows()])
        i = i.assign(time_s=[fair_time(res, r) for _, r in i.iterrows()])
    merged = m.merge(i, on="snapshot", suffixes=("_m", "_i")).sort_values("n_m")
    merged["ratio"] = merged["time_s_i"] / merged["time_s_m"]
    return merged


def round_values(rounds, mode):
    """Per round: (ratio at the smallest DOF count, ratio at the largest, growth = the second / the first)."""
    small, large, growth = [], [], []
    for res in rounds:
        r = ratios(res, *PAIRS[mode], mode=mode)
        if r is None or r.empty:
            small.append(np.nan)
            large.append(np.nan)
            growth.append(np.nan)
            continue
        small.append(float(r["ratio"].iloc[0]))
        large.append(float(r["ratio"].iloc[-1]) if len(r) > 1 else np.nan)
        growth.append(float(r["ratio"].iloc[-1] / r["ratio"].iloc[0]) if len(r) > 1 else np.nan)
    return small, large, growth


def quick_reasons(runs) -> dict:
    """Quick mode: why a full run could reverse each fig11 claim ({"grows": [...], "low": [...]}):
    resolutions less than QUICK_SPAN apart (the growth), a fair run whose final e lies within
    QUICK_E_MARGIN of FAIR_LEVEL (both claims: its time to the level hangs on that margin)."""
    out = {"grows": [], "low": []}
    dofs = sorted(set(by_dof(runs, PAIRS["fair"][0])["n"].dropna().astype(int)))
    if len(dofs) > 1 and dofs[-1] / dofs[0] < QUICK_SPAN:
        out["grows"].append(f"quick mode: the resolutions judged are {dofs[-1] / dofs[0]:.2f}x apart ({dofs[0]} and "
                            f"{dofs[-1]} DOF), under {QUICK_SPAN:g}x")
    smallest = dofs[0] if dofs else None
    for lab in PAIRS["fair"]:
        for _, r in by_dof(runs, lab).iterrows():
            e = float(r["accuracy"]) if np.isfinite(r["accuracy"]) else float("nan")
            if np.isfinite(e) and e > 0 and max(e / FAIR_LEVEL, FAIR_LEVEL / e) < QUICK_E_MARGIN:
                text = (f"quick mode: {lab} at {fmt(r['n'])} DOF ends at e {e:.3g}, within {QUICK_E_MARGIN:g}x of the "
                        f"level {FAIR_LEVEL:g} its fair time is measured to")
                out["grows"].append(text)
                if int(r["n"]) == smallest:
                    out["low"].append(text)
    return out


def _annotate_rows(ax, m):
    """The decoupled row count at each mprgp point, at 7 pt (figure_checks.MIN_FONT_PT), centred on
    it and in turn above and below, so that the counts of two close resolutions do not overlap."""
    for k, (_, r) in enumerate(m.sort_values("n").iterrows()):
        above = k % 2 == 0
        ax.annotate(fmt(r["rows_after"] if np.isfinite(r["rows_after"]) else r["m"]), (r["n"], r["time_s"]),
                    fontsize=7, xytext=(0, 5 if above else -5), textcoords="offset points", ha="center",
                    va="bottom" if above else "top")


def _draw(ax, df, label, y, filled, marks):
    """One series in its solver's style (published filled markers, fair open ones), with the
    not-converged mark on its runs whose status is not `converged`."""
    style = figutil.solver_style(label, "mprgp" if label.startswith("mprgp") else "ica")
    ax.plot(df["n"], figutil.positive(df[y]), color=style["color"], marker=style["marker"],
            ls="-" if filled else "--", mfc=None if filled else "none", label=label)
    if marks:
        bad = df[df["status"] != "converged"]
        if not bad.empty:
            ax.plot(bad["n"], figutil.positive(bad[y]), **figutil.FAILED_MARK)


def produce(ctx: PaperContext) -> FigureOutcome:
    res = ctx.require_results(SUITE)
    runs = res.runs
    if not any(lab in set(runs["label"]) for pair in PAIRS.values() for lab in pair):
        raise NotProduced(f"suite '{SUITE}' has none of the labels {sorted(sum(PAIRS.values(), ()))}")
    rounds = ctx.round_results(SUITE) or [res]
    shown = median_over_rounds(rounds)
    authors = ctx.authors_csv("fig11_mprgp_vs_ica.csv")
    out = FigureOutcome("fig11", "Fig. 11: scaling of MPRGP and ICA with the number of DOFs")
    out.notes += unmeasured_notes(runs)
    out.notes += status_notes(runs)
    # a page column wide: two panels a row, the legend below (figure_checks: 7 in, 7 pt, units)
    fig, axes = plt.subplots(2, 2, figsize=(7.0, 5.6), squeeze=False)
    for ax, (mode, (ml, il)) in zip(axes.flat[:2], PAIRS.items()):
        m, i = by_dof(shown, ml), by_dof(shown, il)
        filled = mode == "published"  # fair series: dashed, open markers, in every panel
        if not m.empty:
            _draw(ax, m, ml, "time_s", filled, True)
            ax.plot(m["n"], figutil.positive(m["setup_s"]), ":", color=figutil.solver_colour("mprgp"), alpha=0.6,
                    label=f"{ml}: setup (power method)")
            _annotate_rows(ax, m)
        if not i.empty:
            _draw(ax, i, il, "time_s", filled, True)
        if authors is not None and mode == "published":
            ax.plot(authors["dofs"], authors["mprgp_time_s"], "^:", mfc="none", color=figutil.solver_colour("mprgp"),
                    alpha=0.7, label="authors: mprgp (2009 machine)")
            ax.plot(authors["dofs"], authors["ica_time_s"], "v:", mfc="none", color=figutil.solver_colour("ica"),
                    alpha=0.7, label="authors: ica")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel(DOF_LABEL)
        ax.set_ylabel("time, setup + solve [s]")
        ax.set_title(f"{mode}: time, median of {len(rounds)} rounds\n(numbers: decoupled rows)")
        ax.grid(True, which="both", alpha=0.3)
    ax = axes.flat[2]
    for mode, (ml, il) in PAIRS.items():
        m, i = by_dof(runs, ml), by_dof(runs, il)
        if not m.empty:
            _draw(ax, m, ml, "a_products", mode == "published", False)
            if "counters.power_products" in m:
                ax.plot(m["n"], figutil.positive(m["counters.power_products"]), ":" if mode == "published" else "-.",
                        color=figutil.solver_colour("mprgp"), alpha=0.5, label=f"{ml}: power method")
        if not i.empty:
            _draw(ax, i, il, "a_products", mode == "published", False)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel(DOF_LABEL)
    ax.set_ylabel("A-products (count)")
    ax.set_title("ours: A-products (power method apart)")
    ax.grid(True, which="both", alpha=0.3)
    ax = axes.flat[3]
    for mode, (ml, il) in PAIRS.items():
        for lab in (ml, il):
            d = by_dof(runs, lab)
            if not d.empty:
                _draw(ax, d, lab, "iterations", mode == "published", False)
    if authors is not None:
        ax.plot(authors["dofs"], authors["power_iterations"], "^:", mfc="none", color=figutil.solver_colour("mprgp"),
                alpha=0.7, label="authors: power iterations")
        ax.plot(authors["dofs"], authors["mprgp_iterations"], "v:", mfc="none", color=figutil.solver_colour("mprgp"),
                alpha=0.7, label="authors: mprgp iterations")
        ax.plot(authors["dofs"], authors["ica_iterations"], "v:", mfc="none", color=figutil.solver_colour("ica"),
                alpha=0.7, label="authors: ica iterations")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel(DOF_LABEL)
    ax.set_ylabel("iterations (count)")
    ax.set_title("iterations (ours and the authors')")
    ax.grid(True, which="both", alpha=0.3)
    fig.tight_layout()
    figutil.legend_outside(fig, axes.flat, notes=[figutil.failed_mark()])
    out.files += figutil.save_figure_outside(fig, ctx.fig_dir, "fig11_scaling")

    small, grows, texts = {}, {}, []
    never = [(r["n"], f"{r['label']} at {fmt(r['n'])} DOF (final e {fmt(r['accuracy'])})")
             for lab in PAIRS["fair"] for _, r in by_dof(runs, lab).iterrows() if not np.isfinite(fair_time(res, r))]
    smallest = by_dof(runs, PAIRS["fair"][0])["n"].min() if not by_dof(runs, PAIRS["fair"][0]).empty else np.nan
    for mode in PAIRS:
        s_vals, l_vals, g_vals = round_values(rounds, mode)
        large = judge_rounds(l_vals, 1.0, BELOW)  # for its median and interval only
        small[mode] = judge_rounds(s_vals, 1.0, BELOW)
        grows[mode] = judge_rounds(g_vals, GROWTH)
        if mode == "fair":
            for j, cases in ((small[mode], [t for n, t in never if n == smallest]), (grows[mode], [t for _, t in never])):
                if cases and j.verdict in (NOT_MEASURED, INCONCLUSIVE):
                    j.reason += f" (e never stayed <= {FAIR_LEVEL:g} on the original QP: {', '.join(cases)})"
        r = ratios(res, *PAIRS[mode], mode=mode)
        if r is not None and len(r) > 1:
            texts.append(f"{mode}: ICA/MPRGP at {fmt(r['n_m'].iloc[0])} DOF {small[mode].text()}x, at "
                         f"{fmt(r['n_m'].iloc[-1])} DOF {large.text()}x, growth {grows[mode].text()}x")
        elif r is not None and len(r) == 1:
            grows[mode].verdict, grows[mode].reason = NOT_MEASURED, "one resolution only"
    a_grow = a_small = "—"
    if authors is not None and not authors.empty:
        a = authors.sort_values("dofs")
        ar = (a["ica_time_s"] / a["mprgp_time_s"]).to_numpy()
        a_grow = f"ICA/MPRGP {fmt(ar[0])}x at {fmt(a['dofs'].iloc[0])} DOF -> {fmt(ar[-1])}x at {fmt(a['dofs'].iloc[-1])} DOF"
        a_small = f"ICA/MPRGP {fmt(ar[0])}x at {fmt(a['dofs'].iloc[0])} DOF (ICA slower there too)" if ar[0] > 1 \
            else f"ICA/MPRGP {fmt(ar[0])}x at {fmt(a['dofs'].iloc[0])} DOF"
    statuses = "; ".join(f"{lab}: " + ", ".join(f"{k} {v}" for k, v in by_dof(runs, lab)["status"].value_counts().items())
                         for pair in PAIRS.values() for lab in pair if not by_dof(runs, lab).empty)
    dofs = sorted(set(by_dof(runs, PAIRS["fair"][0])["n"].dropna().astype(int)))
    judged = (f"the frame-11 QPs of {len(dofs)} resolutions ({', '.join(str(d) for d in dofs)} DOF), "
              f"{len(rounds)} interleaved rounds; as published each run's whole time (setup + solve) to its own "
              f"stop on the problem it solved (native residual); fair: the time (setup + solve) from which the "
              f"accuracy error e on the original QP stays <= {FAIR_LEVEL:g}. Statuses: {statuses}")
    growth = Claim(
        key="fig11-advantage-grows",
        claim="MPRGP's advantage over ICA grows with the resolution",
        source="Sec. 6.2 (\"the performance advantage over ICA will be more significant on models with higher resolution\"), Fig. 11",
        paper="advantage grows with DOFs", authors=a_grow,
        ours="; ".join(texts) if texts else "—",
        verdict=combine_published_fair(grows["published"].verdict, grows["fair"].verdict),
        judged_on=judged,
        rule=f"growth = (ICA/MPRGP time at the largest DOF count) / (the same at the smallest), per round; holds when "
             f"the fair growth's interval is above {GROWTH:g}, does not hold when below; 'only as published' when only "
             "the published growth holds",
        reason=combined_reason(grows["published"], grows["fair"]))
    out.claims.append(growth.decided_by(grows["fair"] if grows["fair"].verdict != NOT_MEASURED else grows["published"],
                                        GROWTH))
    low = Claim(
        key="fig11-ica-low-res",
        claim="On low resolutions ICA is the better choice",
        source="Sec. 6.2 (\"on lower resolutions, ICA should be used\")",
        paper="ICA preferable at low resolution", authors=a_small,
        ours=(f"ICA/MPRGP time at the smallest resolution, median [interval] of {len(rounds)} rounds: published "
              f"{small['published'].text()}x, fair {small['fair'].text()}x"),
        verdict=combine_published_fair(small["published"].verdict, small["fair"].verdict),
        judged_on=judged,
        rule="holds when the interval of ICA/MPRGP time at the smallest DOF count is below 1 (fair reading; "
             "'only as published' when only with the authors' settings)",
        reason=combined_reason(small["published"], small["fair"]))
    out.claims.append(low.decided_by(small["fair"] if small["fair"].verdict != NOT_MEASURED else small["published"],
                                     1.0, BELOW))
    if ctx.quick:  # verdicts a full run could reverse, with the reason
        why = quick_reasons(runs)
        if why["grows"]:
            withdraw_quick(growth, "; ".join(why["grows"]))
        if why["low"]:
            withdraw_quick(low, "; ".join(why["low"]))
    rows = [f"Times: setup + solve, median of {len(rounds)} rounds; fair time to e <= {FAIR_LEVEL:g} from round 1's history.",
            "", "| label | DOFs | rows (decoupled) | status | iterations | A-products | power products | setup [s] | "
            "time, setup + solve [s] | time to e <= 1e-2, setup + solve [s] | accuracy error e |",
            "|---|---|---|---|---|---|---|---|---|---|---|"]
    for lab in [l for pair in PAIRS.values() for l in pair]:
        for _, r in by_dof(shown, lab).iterrows():
            rows.append(f"| {lab} | {fmt(r['n'])} | {fmt(r['rows_after'])} | {r['status']} | {fmt(r['iterations'])} | "
                        f"{fmt(r['a_products'])} | {fmt(r.get('counters.power_products'))} | {fmt(r['setup_s'])} | "
                        f"{fmt(r['time_s'])} | {fmt(fair_time(res, r))} | {fmt(r['accuracy'])} |")
    out.tables.append("\n".join(rows))
    return out


if __name__ == "__main__":
    sys.exit(run_standalone(produce, sys.argv[1:], SUITE, __doc__.splitlines()[0]))
