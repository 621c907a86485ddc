#!/usr/bin/python3
"""Runs the frictional suite (suites/friction.json; docs/friction.md "The frictional suite") end to end:

1. frames: simulates the frictional scenes a few frames (scenes/friction_incline.json,
   scenes/friction_slide.json, scenes/two_dinos_1303_friction.json) into OUT/sim/<scene> and
   converts the real global FCLIB files of tests/data/fclib into OUT/fclib/<file>.qpsnap
   (`contactbench convert`; the local files, W without A, cannot go through `run`: they stay with
   `contactbench friction-solve`). Kept when already there (--force redoes them).
2. runs: the suite at each tolerance (--tols, default 1e-4 and 1e-8) in --rounds interleaved rounds
   (default 5, the fewest whose [min, max] is a 90% interval of the median: plots/intervals.py),
   round k in OUT/runs/tol<tol>/round<k>, the solvers' order reversed in even rounds, so that no
   solver always runs first on a problem (docs/work.md "Claims"). `contactbench run` reuses a
   finished run; --force reruns.
3. report: OUT/friction_suite (Markdown, REPORT_NAME: the table of every run, the per-label summary and the claim rows)
   and the profiles FIGDIR/friction_profiles.png (plots/friction_profiles.py), from the runs' final
   points: status, errors and iterations of round 1 (the same in every round for these
   deterministic solvers: checked, a difference is reported), time the median over the rounds.

usage: friction_suite.py [--cb BIN] [--out DIR] [--rounds R] [--tols T,T] [--figures DIR]
                         [--force] [--report-only]
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
sys.path.insert(0, ROOT)

import pandas as pd  # noqa: E402

from plots import friction_profiles as fp  # noqa: E402
from plots.figutil import fmt  # noqa: E402
from plots.intervals import min_rounds  # noqa: E402
from plots.profiles import data_shift  # noqa: E402

SUITE = os.path.join(ROOT, "suites", "friction.json")
#: the prefix of the suite's data paths (relative to suites/), replaced by OUT
SUITE_DATA = "../results/friction"
#: the scenes simulated and how many frames (the suite picks frames from them)
SCENES = [("friction_incline", 10), ("friction_slide", 10), ("two_dinos_1303_friction", 12)]
#: the real global FCLIB files (frictional: mu = 0.3) that `convert` makes snapshots of
FCLIB_GLOBAL = ["CubeH8", "LMGC_GFC3D-i00001-1-00000", "LMGC_GFC3D-i00501-4-00000",
                "LMGC_GlobalFrictionContactProblem00046"]
#: the scenes whose frames are the "flexible frames" of the claim (FEM bodies of the simulator)
FLEXIBLE = [name for name, _ in SCENES]
#: the report written into OUT (a results file, not a document of the repository)
REPORT_NAME = "friction_suite" + ".md"


def call(cmd) -> None:
    print("+ " + " ".join(cmd), flush=True)
    rc = subprocess.call(cmd)
    if rc != 0:
        raise SystemExit(f"friction_suite.py: `{' '.join(cmd)}` exited {rc}")


def make_frames(cb: str, out: str, force: bool) -> None:
    for name, frames in SCENES:
        folder = os.path.join(out, "sim", name)
        if force or not os.path.isfile(os.path.join(folder, "simulation.json")):
            call([cb, "simulate", os.path.join(ROOT, "scenes", f"{name}.json"), "--frames", str(frames),
                  "--out", folder])
    os.makedirs(os.path.join(out, "fclib"), exist_ok=True)
    for stem in FCLIB_GLOBAL:
        target = os.path.join(out, "fclib", f"{stem}.qpsnap")
        if force or not os.path.isfile(target):
            call([cb, "convert", os.path.join(ROOT, "tests", "data", "fclib", f"{stem}.hdf5"), target])


def instantiate(out: str, tol: float, round_index: int) -> str:
    """The suite at `tol` with its data paths under OUT (absolute) and, in even rounds, its solvers
    in reverse order; written to OUT/suites/ and returned."""
    with open(SUITE, encoding="utf-8") as f:
        suite = json.load(f)
    data = os.path.abspath(out)

    def moved(path: str) -> str:
        if path.startswith(SUITE_DATA):
            return data + path[len(SUITE_DATA):]
        return os.path.normpath(os.path.join(os.path.dirname(SUITE), path))

    snaps = []
    for entry in suite["snapshots"]:
        if isinstance(entry, str):
            snaps.append(moved(entry))
        else:
            entry = dict(entry, sim=moved(entry["sim"]))
            if "scene" in entry:
                entry["scene"] = moved(entry["scene"])
            snaps.append(entry)
    suite["snapshots"] = snaps
    suite["tol"] = tol
    if round_index % 2 == 0:
        suite["solvers"] = list(reversed(suite["solvers"]))
    path = os.path.join(out, "suites", f"friction.tol{tol:g}.round{round_index}.json")
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path + ".tmp", "w", encoding="utf-8") as f:
        json.dump(suite, f, indent=1)
    os.replace(path + ".tmp", path)
    return path


def round_folder(out: str, tol: float, k: int) -> str:
    return os.path.join(out, "runs", f"tol{tol:g}", f"round{k}")


def run_rounds(cb: str, out: str, tols, rounds: int, force: bool) -> None:
    for k in range(1, rounds + 1):  # rounds outermost: a load change moves every tolerance alike
        for tol in tols:
            cmd = [cb, "run", instantiate(out, tol, k), "--out", round_folder(out, tol, k)]
            call(cmd + (["--force"] if force else []))


def combined(out: str, tol: float, rounds: int):
    """(runs, round tables, notes): round 1's records with time_s the median over the rounds."""
    tables = [fp.read_records(round_folder(out, tol, k)) for k in range(1, rounds + 1)
              if os.path.isdir(os.path.join(round_folder(out, tol, k), "runs"))]
    if not tables:
        raise SystemExit(f"friction_suite.py: no runs at tol {tol:g} under {out}/runs (run without --report-only)")
    key = ["snapshot", "label"]
    first = tables[0].set_index(key)
    times = pd.concat([t.set_index(key)["time_s"].rename(i) for i, t in enumerate(tables)], axis=1)
    notes = []
    for i, t in enumerate(tables[1:], start=2):
        other = t.set_index(key).reindex(first.index)
        differ = other.index[(other["status"] != first["status"]).to_numpy()]
        if len(differ):
            notes.append(f"tol {tol:g}, round {i}: status differs from round 1 on "
                         + ", ".join(f"{s}/{lab}" for s, lab in differ))
    runs = first.assign(time_s=times.median(axis=1), time_min=times.min(axis=1),
                        time_max=times.max(axis=1)).reset_index()
    return runs, tables, notes


def summary_table(by_tol) -> str:
    """Per tol and label: runs judged, solved by FCLIB error, by e, and the statuses."""
    lines = ["| tol | solver | judged | FCLIB error <= tol | e <= tol | statuses |", "|---|---|---|---|---|---|"]
    for tol in sorted(by_tol, reverse=True):
        runs = by_tol[tol]
        for label, g in runs.groupby("label", sort=False):
            judged = g[g["status"] != fp.NOT_APPLICABLE]
            statuses = ", ".join(f"{s} {n}" for s, n in judged["status"].value_counts().items())
            na = len(g) - len(judged)
            lines.append(f"| {tol:g} | {label} | {len(judged)}" + (f" ({na} n/a)" if na else "") +
                         f" | {int(fp.reached(g, tol, 'fclib').sum())} | {int(fp.reached(g, tol, 'e').sum())} | {statuses} |")
    return "\n".join(lines)


def problem_group(snapshot: str) -> str:
    """The scene a frame comes from, or "FCLIB global" for a converted file."""
    for name in FLEXIBLE:
        if snapshot.startswith(name + "_f"):
            return name
    return "FCLIB global"


def group_table(by_tol) -> str:
    """Per tol and label, one cell per problem group: the median time over its problems [s] and how
    many of them met the tol by e and by FCLIB's error."""
    groups = FLEXIBLE + ["FCLIB global"]
    lines = ["| tol | solver | " + " | ".join(groups) + " |", "|---|---|" + "---|" * len(groups)]
    for tol in sorted(by_tol, reverse=True):
        runs = by_tol[tol].assign(group=lambda d: d["snapshot"].map(problem_group))
        for label, g in runs.groupby("label", sort=False):
            cells = []
            for group in groups:
                sel = g[g["group"] == group]
                if sel.empty:
                    cells.append("—")
                    continue
                n = len(sel)
                cells.append(f"{fmt(sel['time_s'].median())} (e {int(fp.reached(sel, tol, 'e').sum())}/{n}, "
                             f"FCLIB {int(fp.reached(sel, tol, 'fclib').sum())}/{n})")
            lines.append(f"| {tol:g} | {label} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def claim_lines(claim) -> str:
    return (f"| {claim.claim} ({fp.MEASURES[claim.key.rsplit('-', 1)[1]]}) | {claim.verdict} | {claim.ours} | "
            f"{claim.reason or '—'} |")


def report(out: str, tols, rounds: int, figures: str) -> str:
    by_tol, rounds_by_tol, notes = {}, {}, []
    for tol in tols:
        runs, tables, n = combined(out, tol, rounds)
        by_tol[tol], rounds_by_tol[tol] = runs, tables
        notes += n
    frictionless = sorted({lab for runs in by_tol.values() for lab in fp.frictionless_labels(runs)})
    panels = {tol: runs[~runs["label"].isin(frictionless)] for tol, runs in by_tol.items()}
    figs = fp.draw(panels, ["fclib", "e"], figures, "friction_profiles", frictionless)
    with open(SUITE, encoding="utf-8") as f:
        penalty = float(json.load(f).get("time_limit_s", 60))
    claim_rows = []
    for tol in tols:
        flexible = sorted({s for s in by_tol[tol]["snapshot"] if any(s.startswith(n + "_f") for n in FLEXIBLE)})
        reached_times = [t for m in ("fclib", "e") for t in by_tol[tol].loc[fp.reached(by_tol[tol], tol, m), "time_s"]]
        shift = data_shift(reached_times)
        text = f"{len(flexible)} simulator frames ({', '.join(FLEXIBLE)})"
        for measure in ("fclib", "e"):
            claim_rows.append(fp.claim_row(rounds_by_tol[tol], tol, measure, flexible, penalty, shift, text))
    parts = ["# The frictional suite", "",
             f"{len(rounds_by_tol[tols[0]])} round(s) per tolerance; time = median over the rounds (setup + solve).",
             "Frictionless labels (solved_relaxation on every run), left out of the profiles: "
             + (", ".join(frictionless) or "none") + ".", "",
             "## Per solver", "", summary_table(by_tol), "",
             "## Per problem group: median time [s] (runs that met tol by e, by FCLIB's error)", "",
             group_table(by_tol), "",
             "## Claims", "", "| claim | verdict | ours (median [interval]) | reason |", "|---|---|---|---|",
             *[claim_lines(c) for c in claim_rows], "",
             "## Every run", "", fp.run_table(by_tol), ""]
    if notes:
        parts += ["## Notes", ""] + [f"- {n}" for n in notes] + [""]
    parts += ["## Figures", ""] + [f"- {f}" for f in figs]
    path = os.path.join(out, REPORT_NAME)
    with open(path + ".tmp", "w", encoding="utf-8") as f:
        f.write("\n".join(parts) + "\n")
    os.replace(path + ".tmp", path)
    with open(os.path.join(out, "friction_claims.json"), "w", encoding="utf-8") as f:
        json.dump([c.to_dict() for c in claim_rows], f, indent=1)
    return path


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cb", default=os.path.join(ROOT, "build", "bin", "contactbench"))
    ap.add_argument("--out", default=os.path.join(ROOT, "results", "friction"))
    ap.add_argument("--rounds", type=int, default=min_rounds())
    ap.add_argument("--tols", default="1e-4,1e-8")
    ap.add_argument("--figures", help="figure folder (default OUT/figures)")
    ap.add_argument("--force", action="store_true", help="re-simulate, re-convert and re-run everything")
    ap.add_argument("--report-only", action="store_true", help="only step 3, from the runs already there")
    args = ap.parse_args(argv)
    tols = [float(t) for t in args.tols.split(",")]
    if not args.report_only:
        make_frames(args.cb, args.out, args.force)
        run_rounds(args.cb, args.out, tols, args.rounds, args.force)
    path = report(args.out, tols, args.rounds, args.figures or os.path.join(args.out, "figures"))
    print(f"friction_suite.py: wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
