"""The report's rows for the price of collision decoupling (Sec. 5, 6, 7), judged by
plots/decoupling.py's rule on the chains `make decoupling` cached in results/decoupling (the sibling
of the report's folder). The chains take hours on 2 cores, so `make reproduce` reads them and never
runs them: without them the rows say "not measured" and how to measure them."""
import os

from plots.claims import Claim
from plots.paper_context import FigureOutcome, NotProduced, PaperContext


def chains_folder(ctx: PaperContext) -> str:
    return os.path.join(os.path.dirname(os.path.abspath(ctx.out)), "decoupling")


def produce(ctx: PaperContext) -> FigureOutcome:
    from plots import decoupling  # pandas and the chain readers, only when a report is made
    folder = chains_folder(ctx)
    summaries = decoupling.summaries_of(folder)
    if not summaries:
        raise NotProduced(f"no chains in {folder}/chains: run `make decoupling` first (hours on 2 cores)")
    out = FigureOutcome("decoupling_claims", "The price of collision decoupling (chains)")
    for r in decoupling.claim_rows(summaries):
        out.claims.append(Claim(key=r["key"], claim=r["claim"], source=r["source"], paper=r["paper"], ours=r["ours"],
                                verdict=r["verdict"], rule=r["rule"], judged_on=r["problem"], reason=r.get("reason", ""),
                                notes=list(r["numbers"])))
    out.notes.append(f"chains read from {folder} (docs/simulator.md \"The price of decoupling\")")
    return out
