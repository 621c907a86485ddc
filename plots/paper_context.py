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
from plots.intervals import min_rounds
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
    #: suite -> {snapshot path: {"sha256", "source"}} the suite was run (or found cached) on (reproduce.py)
    judged: Dict[str, Dict[str, dict]] = field(default_factory=dict)
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


def round_folders(out: str, name: str) -> List[str]:
    """The repeat rounds reproduce.py wrote for suite `name` under OUT: OUT/rounds/<name>/<k> for
    k = 2, 3, ... (numeric order), those holding a summary.csv; [] when it ran once."""
    base = os.path.join(out, "rounds", name)
    if not os.path.isdir(base):
        return []
    ks = sorted((d for d in os.listdir(base) if d.isdigit()), key=int)
    return [os.path.join(base, d) for d in ks if os.path.isfile(os.path.join(base, d, "summary.csv"))]


def standalone_rounds(results: str, explicit: List[str]) -> List[str]:
    """Every round of a suite for a figure script run on its own, round 1 (RESULTS) first: the
    --round folders when given, else the rounds reproduce.py laid out beside RESULTS (RESULTS =
    OUT/runs/<suite>, rounds in OUT/rounds/<suite>/<k>), so that the script judges its timed claims
    on the same rounds as the report."""
    if explicit:
        return [results] + list(explicit)
    parent = os.path.dirname(os.path.abspath(results))
    if os.path.basename(parent) != "runs":
        return [results]
    return [results] + round_folders(os.path.dirname(parent), os.path.basename(os.path.abspath(results)))


def standalone_context(argv, suite: str, description: str) -> PaperContext:
    """Command line of a figure script run on its own: RESULTS_DIR [--round DIR ...] [--data DIR]
    [--out DIR]."""
    parser = argparse.ArgumentParser(description=description)
    parser.add_argument("results", help=f"results folder of the '{suite}' suite")
    parser.add_argument("--round", action="append", default=[], metavar="DIR", dest="rounds",
                        help="a repeat round's results folder, repeatable (default: OUT/rounds/<suite>/<k> "
                             "when RESULTS is OUT/runs/<suite>, as `make reproduce` writes them)")
    parser.add_argument("--data", default=default_data_dir(),
                        help="the authors' data (default $CB_CACHE/paper-data, written by `make paper-data`)")
    parser.add_argument("--out", default=None, help="output folder (figures/ goes inside; default: RESULTS)")
    parser.add_argument("--sim", action="append", default=[], metavar="KEY=DIR",
                        help="simulation folders (table1: scene=DIR), repeatable")
    args = parser.parse_args(argv)
    ctx = PaperContext(out=args.out or args.results, data=args.data, results={suite: args.results})
    rounds = standalone_rounds(args.results, args.rounds)
    if len(rounds) > 1:
        ctx.rounds[suite] = rounds
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
    used = ctx.rounds.get(suite)
    print(f"{suite}: {len(used)} rounds: {', '.join(used)}" if used else
          f"{suite}: one round ({ctx.results[suite]}; a timed claim needs {min_rounds()}: --round DIR)")
    for f in outcome.files:
        print(f)
    for c in outcome.claims:
        print(f"[{c.verdict}] {c.claim}: paper {c.paper}; authors {c.authors}; ours {c.ours}")
    for t in outcome.tables:
        print(t)
    return 0
