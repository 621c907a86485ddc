#!/usr/bin/python3
"""The reproduction report (results/paper/report.md): a table of the paper's claims beside the
authors' data and ours, with verdicts computed by the figure scripts, then each figure (or the
reason it was not produced), its tables and notes, and how the run was made.

usage: report.py OUT_DIR [--data DIR]   (re-renders from OUT_DIR/runs/* without re-running anything)
"""
from __future__ import annotations

import argparse
import json
import os
import sys
from typing import Dict, List, Optional


from plots.claims import ABOVE, INCONCLUSIVE, INCONCLUSIVE_QUICK, NOT_MEASURED, QUICK_MARGIN, Claim, \
    quick_margin_guard  # noqa: E402
from plots.loader import STATUS_MEANINGS  # noqa: E402
from plots.paper_context import FigureOutcome, NotProduced, PaperContext, round_folders  # noqa: E402

#: the claims every report has a row for, in order, with the figure that measures each
EXPECTED_CLAIMS = [
    ("fig6-decoupling", "fig6", "Decoupling the constraints makes each frame's QP much cheaper"),
    ("fig8-similar-to-cg", "fig8", "MPRGP converges about as fast as CG on the same A with J ignored"),
    ("fig9-preconditioning", "fig9", "Jacobi preconditioning significantly improves MPRGP's convergence"),
    ("fig10-ica-10x", "fig10", "To residual 1e-2, MPRGP is more than 10x faster than ICA"),
    ("fig11-advantage-grows", "fig11", "MPRGP's advantage over ICA grows with the resolution"),
    ("fig11-ica-low-res", "fig11", "On low resolutions ICA is the better choice"),
    ("table1-cg-dominates", "table1", "CG steps dominate MPRGP's iterations (monotone MPRGP)"),
    ("table1-power-warm", "table1", "The warm-started power method converges within 40 iterations"),
    ("sec6-decoupling-no-visual-artifacts", "decoupling_claims",
     "Collision decoupling shows no visual artifacts in the eight-dinosaur scene"),
    ("sec7-decoupling-no-noticeable-artifacts", "decoupling_claims",
     "Collision decoupling ignores some constraints without noticeable artifacts"),
    ("sec5-depth-sorted-selection", "decoupling_claims", "A depth-sorted selection of the kept rows reduces the price"),
]


def figure_modules():
    from plots import fig6
    from plots import fig8
    from plots import fig9
    from plots import fig10
    from plots import fig11
    from plots import table1
    from plots import decoupling_claims
    return [fig6, fig8, fig9, fig10, fig11, table1, decoupling_claims]


def produce_all(ctx: PaperContext, log=print) -> List[FigureOutcome]:
    """Runs every figure script; a failure becomes an outcome with `missing` set."""
    outcomes = []
    for module in figure_modules():
        name = module.__name__.rsplit(".", 1)[-1]  # "fig6": the name EXPECTED_CLAIMS gives its rows
        try:
            outcome = module.produce(ctx)
            if ctx.quick:  # a verdict on a thin margin is one a full run could reverse
                for claim in outcome.claims:
                    quick_margin_guard(claim)
            log(f"[report] {name}: {len(outcome.files)} files, {len(outcome.claims)} claims")
        except NotProduced as err:
            outcome = FigureOutcome(name, name, missing=str(err))
            log(f"[report] {name}: not produced: {err}")
        except Exception as err:  # a bug in one figure must not hide the others
            outcome = FigureOutcome(name, name, missing=f"error in {name}.py: {type(err).__name__}: {err}")
            log(f"[report] {name}: ERROR {type(err).__name__}: {err}")
        outcomes.append(outcome)
    return outcomes


def collect_claims(outcomes: List[FigureOutcome]) -> List[Claim]:
    """One claim per EXPECTED_CLAIMS row (a 'not measured' row when its figure was not produced)."""
    found: Dict[str, Claim] = {c.key: c for o in outcomes for c in o.claims}
    reasons = {o.name: o.missing for o in outcomes if o.missing}
    rows = []
    for key, fig, text in EXPECTED_CLAIMS:
        if key in found:
            rows.append(found.pop(key))
        else:
            reason = reasons.get(fig, "no measurement")
            rows.append(Claim(key=key, claim=text, source=fig, paper="see paper", ours="—", verdict=NOT_MEASURED,
                              notes=[f"not produced: {reason}"], judged_on="nothing (not produced)", reason=reason))
    rows.extend(found.values())  # claims a figure added beyond the expected list
    return rows


#: the report's one explanation of the verdicts (plots/claims.py)
VERDICT_LEGEND = (
    "Verdicts: **holds** / **does not hold** are decided: a timed ratio only when its whole interval (the "
    "median of repeated, interleaved rounds with its distribution-free interval, docs/work.md \"Claims\") lies "
    "on one side of the threshold; counts (iterations, CG steps) are deterministic. **holds only as "
    "published** / **holds only on native residuals**: the fair reading (the same preconditioner and tolerance "
    "for both, the accuracy error e on the original QP, setup timed) does not hold or was not measured, while "
    "the authors' setting or measure does. **inconclusive**: measured, but the interval straddles the threshold "
    "(reason given). **not measured**: nothing exercised the claim (reason given). **inconclusive (quick)**: quick "
    f"mode only, a verdict a full run could reverse (a margin within {QUICK_MARGIN:g}x of the threshold, resolutions "
    "too close, a "
    "final error crossing its level by a hair; the reason names it and what the quick run found). The column "
    "\"judged on\" "
    "names the problem each verdict is judged on.")


def status_legend() -> str:
    """The statuses every figure, table and claim row uses, each explained once."""
    return ("Run statuses (one vocabulary in every figure, table and row; figures mark every status but "
            "`converged` with a black x): " + "; ".join(f"`{k}`: {v}" for k, v in STATUS_MEANINGS.items()) + ".")


def _cell(text: str) -> str:
    return str(text).replace("|", "\\|").replace("\n", " ")


def render(ctx: PaperContext, outcomes: List[FigureOutcome], meta: Optional[dict] = None) -> str:
    meta = meta or {}
    claims = collect_claims(outcomes)
    lines = ["# Reproduction of Li et al. 2015, \"Deformable Objects Collision Handling with Fast Convergence\"", ""]
    mode = "quick (coarse meshes, few frames)" if ctx.quick else "full"
    cpu = f" wall, {meta['cpu_s']:.0f} s CPU (this script and contactbench)" if "cpu_s" in meta else ""
    lines.append(f"Mode: {mode}. " + (f"Run time of this reproduction: {meta['elapsed_s']:.0f} s{cpu}. " if "elapsed_s" in meta else "")
                 + (f"Authors' data: `{ctx.data}`." if ctx.data else "Authors' data: not given (--data)."))
    if meta.get("provenance"):
        p = meta["provenance"]
        lines.append("")
        lines.append("Machine and build: " + ", ".join(f"{k} {p[k]}" for k in
                                                      ("cpu", "cores", "compiler", "build_type", "git_commit", "git_dirty", "blas")
                                                      if k in p) + ".")
    if meta.get("full_run_s") is not None:
        cpu = meta.get("full_run_cpu_s")
        lines.append(f"The last full run took {meta['full_run_s']:.0f} s" + (f" ({cpu:.0f} s CPU)." if cpu else "."))
    lines += ["", "Every number below is computed from this run's results and the authors' CSV files; the "
              "paper's numbers are quoted from paper.txt with their section. Verdicts are computed by rules "
              "stated per row.", "", "## Claims", "",
              "| claim | judged on | paper | authors' data | ours | verdict |", "|---|---|---|---|---|---|"]
    for c in claims:
        why = f" ({_cell(c.reason)})" if c.reason and c.verdict in (INCONCLUSIVE, NOT_MEASURED, INCONCLUSIVE_QUICK) \
            else ""
        lines.append(f"| {_cell(c.claim)} ({_cell(c.source)}) | {_cell(c.judged_on or '—')} | {_cell(c.paper)} | "
                     f"{_cell(c.authors)} | {_cell(c.ours)} | **{_cell(c.verdict)}**{why} |")
    lines += ["", VERDICT_LEGEND, "", status_legend(), "", "Verdict rules:", ""]
    for c in claims:
        rule = c.rule or "; ".join(c.notes) or "—"
        if c.interval is not None and c.threshold is not None:
            rule += (f" Deciding quantity: {c.estimate:.3g}, {100 * (c.coverage or 0):.1f}% interval "
                     f"[{c.interval[0]:.3g}, {c.interval[1]:.3g}] from {c.samples} interleaved rounds, "
                     f"threshold {c.threshold:g} ({'holds above' if c.direction == ABOVE else 'holds below'}).")
        lines.append(f"- {c.key}: {rule}")
    lines += ["", "## Figures", ""]
    for o in outcomes:
        lines.append(f"### {o.title}")
        lines.append("")
        if o.missing:
            lines.append(f"not produced: {o.missing}")
            lines.append("")
            continue
        for f in o.files:
            if f.endswith(".png"):
                lines.append(f"![{o.name}]({os.path.relpath(f, ctx.out)})")
        pdfs = [os.path.relpath(f, ctx.out) for f in o.files if f.endswith(".pdf")]
        if pdfs:
            lines.append("")
            lines.append("PDF: " + ", ".join(f"[{p}]({p})" for p in pdfs))
        for t in o.tables:
            lines += ["", t]
        for n in o.notes:
            lines += ["", n]
        lines.append("")
    if meta.get("strips"):
        lines += ["## Scenes simulated", ""]
        for key, path in meta["strips"].items():
            lines.append(f"- {key}: ![{key}]({os.path.relpath(path, ctx.out)})")
        lines.append("")
    if meta.get("judged"):
        lines += ["## Snapshots judged", "",
                  "Every suite's snapshots as its runs were made or reused (a cached run is reused only for the same "
                  "content, source, suite and build):", "", "| suite | snapshot | sha256 (16 hex) | source |",
                  "|---|---|---|---|"]
        for suite, snaps in sorted(meta["judged"].items()):
            for path, key in snaps.items():
                lines.append(f"| {_cell(suite)} | {_cell(os.path.basename(path))} | {key.get('sha256') or '—'} | "
                             f"{_cell(key.get('source', '—'))} |")
        lines.append("")
    if meta.get("steps"):
        lines += ["## What ran", ""]
        for s in meta["steps"]:
            lines.append(f"- {s}")
        lines.append("")
    if meta.get("profiles"):
        lines += ["## Suite profiles", ""]
        for name, path in meta["profiles"].items():
            lines.append(f"- {name}: [{os.path.relpath(path, ctx.out)}]({os.path.relpath(path, ctx.out)})")
        lines.append("")
    return "\n".join(lines) + "\n"


def write_report(ctx: PaperContext, outcomes: List[FigureOutcome], meta: Optional[dict] = None) -> str:
    os.makedirs(ctx.out, exist_ok=True)
    path = os.path.join(ctx.out, "report.md")
    with open(path, "w", encoding="utf-8") as f:
        f.write(render(ctx, outcomes, meta))
    with open(os.path.join(ctx.out, "claims.json"), "w", encoding="utf-8") as f:
        json.dump([c.to_dict() for c in collect_claims(outcomes)], f, indent=1)
    return path


def context_from_out(out: str, data: Optional[str], quick: bool = False) -> PaperContext:
    """A context over an existing results/paper folder (runs/<suite>/, sim/<scene>/)."""
    ctx = PaperContext(out=out, data=data, quick=quick)
    runs = os.path.join(out, "runs")
    if os.path.isdir(runs):
        for name in sorted(os.listdir(runs)):
            ctx.results[name] = os.path.join(runs, name)
    for name in list(ctx.results):
        extra = round_folders(out, name)
        if extra:
            ctx.rounds[name] = [ctx.results[name]] + extra
    sims = os.path.join(out, "sim")
    if os.path.isdir(sims):
        for name in sorted(os.listdir(sims)):
            ctx.sims[name] = os.path.join(sims, name)
    return ctx


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out", help="the reproduction folder (results/paper)")
    parser.add_argument("--data", default=None)
    args = parser.parse_args(argv)
    ctx = context_from_out(args.out, args.data)
    meta = {}
    mpath = os.path.join(args.out, "reproduce.json")
    if os.path.isfile(mpath):
        with open(mpath, encoding="utf-8") as f:
            meta = json.load(f)
        ctx.quick = bool(meta.get("quick", False))
        ctx.reasons.update(meta.get("reasons", {}))
    print(write_report(ctx, produce_all(ctx), meta))
    return 0


if __name__ == "__main__":
    sys.exit(main())
