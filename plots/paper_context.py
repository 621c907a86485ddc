"""What the paper-figure scripts share: where the results and simulations are, the authors' data,
and the outcome each script hands to the report.

A figure whose inputs are missing raises NotProduced(reason); the report then says
"not produced: <reason>", never a made-up figure.
"""
from __future__ import annotations

import argparse
import os
from dataclasses import dataclass, field
from typing import Dict, List, Optional

import pandas as pd

from plots.claims import Claim
from plots.loader import Results, load_results, load_simulation


class NotProduced(Exception):
    """A figure could not be produced; the message is the reason shown in the report."""


@dataclass
class FigureOutcome:
    name: str                               #: "fig6", "table1", ...
    title: str
    files: List[str] = field(default_factory=list)   #: figures written (png + pdf)
    claims: List[Claim] = field(default_factory=list)
    tables: List[str] = field(default_factory=list)  #: markdown blocks for the report
    notes: List[str] = field(default_factory=list)
    missing: Optional[str] = None           #: reason when not produced


def median_over_rounds(rounds: List[Results]) -> pd.DataFrame:
    """Round 1's runs with time_s, setup_s and solve_s replaced by their medians over the rounds
    (per snapshot and label), for figures and tables that show one time per run."""
    if not rounds:
        return pd.DataFrame()
    first = rounds[0].runs.copy()
    if len(rounds) == 1:
        return first
    cols = [c for c in ("time_s", "setup_s", "solve_s") if c in first]
    every = pd.concat([r.runs[["snapshot", "label"] + cols] for r in rounds], ignore_index=True)
    med = every.groupby(["snapshot", "label"], sort=False)[cols].median()
    keyed = first.set_index(["snapshot", "label"])
    keyed.loc[med.index.intersection(keyed.index), cols] = med.loc[med.index.intersection(keyed.index), cols]
    return keyed.reset_index()


def default_data_dir() -> str:
    """Where `make paper-data` puts the authors' data: $CB_CACHE/paper-data (CB_CACHE defaults to
    ~/.cache/contactbench). Callers treat a missing folder as "no authors' data"."""
    cache = os.environ.get("CB_CACHE") or os.path.join(os.path.expanduser("~"), ".cache", "contactbench")
    return os.path.join(cache, "paper-data")


@dataclass
class PaperContext:
    out: str                                #: results/paper
    data: Optional[str] = None              #: the authors' data, $CB_CACHE/paper-data (may be absent)
    quick: bool = False
    results: Dict[str, str] = field(default_factory=dict)   #: suite name -> results folder
    sims: Dict[str, str] = field(default_factory=dict)      #: scene key -> simulation folder
    reasons: Dict[str, str] = field(default_factory=dict)   #: suite/scene -> why it is missing
    notes: Dict[str, List[str]] = field(default_factory=dict)  #: suite -> notes (e.g. substitutions)
    #: timed suite -> its rounds' results folders, round 1 (= results[suite]) first (reproduce.py)
    rounds: Dict[str, List[str]] = field(default_factory=dict)
    _round_cache: Dict[str, list] = field(default_factory=dict, repr=False)

    @property
    def fig_dir(self) -> str:
        return os.path.join(self.out, "figures")

    def require_results(self, suite: str) -> Results:
        folder = self.results.get(suite) or os.path.join(self.out, "runs", suite)
        if suite in self.reasons:
            raise NotProduced(self.reasons[suite])
        try:
            res = load_results(folder)
        except FileNotFoundError:
            raise NotProduced(f"no results for suite '{suite}' in {folder}")
        if res.runs.empty:
            raise NotProduced(f"suite '{suite}' produced no runs ({folder})")
        return res

    def round_results(self, suite: str) -> List[Results]:
        """Every round of a timed suite, round 1 first; [round 1] alone when it ran once (the
        claims then have one timing and say so). Folders that do not load are left out."""
        if suite not in self._round_cache:
            loaded = []
            for folder in self.rounds.get(suite) or [self.results.get(suite) or os.path.join(self.out, "runs", suite)]:
                try:
                    res = load_results(folder)
                except (FileNotFoundError, ValueError):
                    continue
                if not res.runs.empty:
                    loaded.append(res)
            self._round_cache[suite] = loaded
        return self._round_cache[suite]

    def simulation(self, key: str) -> Optional[dict]:
        folder = self.sims.get(key)
        if not folder or not os.path.isdir(folder):
            return None
        return load_simulation(folder)

    def authors_csv(self, name: str) -> Optional[pd.DataFrame]:
        """The authors' data file figures/<name>, or None when --data is absent."""
        if not self.data:
            return None
        path = os.path.join(self.data, "figures", name)
        return pd.read_csv(path) if os.path.isfile(path) else None


def standalone_context(argv, suite: str, description: str) -> PaperContext:
    """Command line of a figure script run on its own: RESULTS_DIR [--data DIR] [--out DIR]."""
    parser = argparse.ArgumentParser(description=description)
    parser.add_argument("results", help=f"results folder of the '{suite}' suite")
    parser.add_argument("--data", default=default_data_dir(),
                        help="the authors' data (default $CB_CACHE/paper-data, written by `make paper-data`)")
    parser.add_argument("--out", default=None, help="output folder (figures/ goes inside; default: RESULTS)")
    parser.add_argument("--sim", action="append", default=[], metavar="KEY=DIR",
                        help="simulation folders (table1: scene=DIR), repeatable")
    args = parser.parse_args(argv)
    ctx = PaperContext(out=args.out or args.results, data=args.data, results={suite: args.results})
    for item in args.sim:
        key, _, folder = item.partition("=")
        ctx.sims[key] = folder
    return ctx


def run_standalone(produce, argv, suite: str, description: str) -> int:
    ctx = standalone_context(argv, suite, description)
    try:
        outcome = produce(ctx)
    except NotProduced as err:
        print(f"not produced: {err}")
        return 1
    for f in outcome.files:
        print(f)
    for c in outcome.claims:
        print(f"[{c.verdict}] {c.claim}: paper {c.paper}; authors {c.authors}; ours {c.ours}")
    for t in outcome.tables:
        print(t)
    return 0
