"""The price of the paper's two friction baselines along a chain (issue 45): runs `contactbench
chains` on frictional scenes (the exact frictional step against mprgp+bmf03, mprgp+ica-friction when
registered, and no friction) and writes the table of docs/friction.md "The price along a chain".

usage: friction_chains.py [SCENE.json ...] --out DIR [--frames N] [--cb PATH]
       (default scenes: scenes/friction_slide.json scenes/friction_incline.json)

Writes DIR/<scene>/ (the `chains` folders, run with --fresh) and DIR/friction_chains.md."""
from __future__ import annotations

import argparse
import csv
import os
import subprocess
import sys
from typing import Dict, List

DEFAULT_SCENES = ("scenes/friction_slide.json", "scenes/friction_incline.json")


def read_rows(path: str) -> List[Dict[str, str]]:
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def pct(value: float) -> str:
    return f"{100 * value:.3g}"


def table(folders: Dict[str, str]) -> str:
    """One row per scene and chain: how far the chain moved from the exact one, per frame."""
    lines = ["| scene | frames | chain | frames by status | largest e | drift at the end (% of L) | "
             "largest drift (% of L) | drift per frame (% of L) | travel (% of L) |",
             "|---|---|---|---|---|---|---|---|---|"]
    for scene, folder in folders.items():
        rows = read_rows(os.path.join(folder, "chains.csv"))
        chains: Dict[str, List[Dict[str, str]]] = {}
        for r in rows:
            chains.setdefault(r["chain"], []).append(r)
        for chain, rs in chains.items():
            frames = len(rs)
            drift = [float(r["drift_rel"]) for r in rs]
            statuses: Dict[str, int] = {}
            for r in rs:  # the frame's last step's verdict
                statuses[r["status"]] = statuses.get(r["status"], 0) + 1
            by_status = ", ".join(f"{s} {n}" for s, n in sorted(statuses.items()))
            lines.append(f"| {scene} | {frames} | {chain} ({rs[0]['solver']}) | {by_status} | "
                         f"{max(float(r['accuracy']) for r in rs):.2g} | {pct(drift[-1])} | {pct(max(drift))} | "
                         f"{pct(drift[-1] / frames)} | {pct(float(rs[-1]['travel_rel']))} |")
    return "\n".join(lines) + "\n"


def main(argv: List[str]) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scenes", nargs="*", default=list(DEFAULT_SCENES))
    parser.add_argument("--out", required=True)
    parser.add_argument("--frames", type=int)
    parser.add_argument("--cb", default=os.environ.get("CB_CONTACTBENCH", "build/bin/contactbench"))
    args = parser.parse_args(argv)
    folders: Dict[str, str] = {}
    for scene in args.scenes:
        name = os.path.splitext(os.path.basename(scene))[0]
        folder = os.path.join(args.out, name)
        command = [args.cb, "chains", scene, "--out", folder, "--fresh"]
        if args.frames is not None:
            command += ["--frames", str(args.frames)]
        os.makedirs(args.out, exist_ok=True)
        with open(os.path.join(args.out, name + ".log"), "w") as log:
            rc = subprocess.run(command, stdout=log, stderr=subprocess.STDOUT).returncode
        if rc != 0:
            print(f"friction_chains.py: {' '.join(command)} failed (exit {rc}; {args.out}/{name}.log)",
                  file=sys.stderr)
            return rc
        folders[name] = folder
    text = table(folders)
    with open(os.path.join(args.out, "friction_chains.md"), "w") as f:
        f.write(text)
    sys.stdout.write(text)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
