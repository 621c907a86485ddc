#!/usr/bin/env python3
"""Stiff figure (issue 17): error against time for cg and mprgp with the jacobi and ichol
preconditioners (and cg ichol with deflation=rigid, mprgp ichol's coarse space) on the stiff-slab
scene at Young's moduli 1e4..1e12 Pa.

    python3 plots/stiff.py run  --bin build/bin/contactbench --out results/stiff [--youngs 1e4,1e8,...]
    python3 plots/stiff.py plot --out results/stiff          (redraw from results/stiff/runs/*.json)
    --scene scenes/stiff_slab_graded.json                    (the irregular mesh, cond(A) = 1.1e9 at 1e10)
    --scene scenes/stiff_dino.json --frames 2                (the dinosaur reproducer, 292 rows at frame 1)

`run` simulates one step of scenes/stiff_slab.json per modulus (the stress cases slab-stiff-*),
solves the snapshot with each configuration (tol 1e-8, history on) and writes
runs/<E>__<config>.json, stiff.csv (one line per run) and stiff.png/pdf.
Error: mprgp's accuracy error e (docs/accuracy.md, the harness's common measure); cg ignores J, so its error is
its own: the unconstrained residual |b - Ax|_inf relative to its start, from x = 0 (start=zero).
"""
from __future__ import annotations

import argparse
import glob
import json
import math
import os
import subprocess
import sys
import tempfile
from typing import Dict, List

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import pandas as pd  # noqa: E402

import figutil  # noqa: E402
from figutil import plt  # noqa: E402
from record_schema import current_column_names  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
SCENE = os.path.join(HERE, "..", "scenes", "stiff_slab.json")

#: label -> (solver, settings)
CONFIGS: Dict[str, tuple] = {
    "cg-jacobi": ("cg", {"precond": "jacobi", "start": "zero"}),
    "cg-ichol": ("cg", {"precond": "ichol", "start": "zero"}),
    # The fair baseline of mprgp-ichol (whose default deflation is rigid): PCG with the same coarse space.
    "cg-ichol-rigid": ("cg", {"precond": "ichol", "start": "zero", "deflation": "rigid"}),
    "mprgp-jacobi": ("mprgp", {"precond": "jacobi"}),
    "mprgp-ichol": ("mprgp", {"precond": "ichol"}),
}
STYLE = {"cg-jacobi": (figutil.solver_colour("cg"), "--"), "cg-ichol": (figutil.solver_colour("cg"), "-"),
         "cg-ichol-rigid": (figutil.solver_colour("cg"), ":"),
         "mprgp-jacobi": (figutil.solver_colour("mprgp"), "--"), "mprgp-ichol": (figutil.solver_colour("mprgp"), "-")}


def error_curve(run: dict) -> pd.DataFrame:
    """time_s, iteration and error of one run's history (see the module doc for the error)."""
    hist = run.get("history") or {}
    cols = current_column_names(hist.get("columns") or [], "run of " + str(run.get("label", run.get("solver"))))
    rows = hist.get("rows") or []
    df = pd.DataFrame(rows, columns=cols) if rows else pd.DataFrame(columns=["iteration", "time_s", "error"])
    if df.empty:
        return df
    # Time from the start of setup: ichol's factorization of A is setup for cg but happens in
    # the solve for mprgp (its face is known only then); both count.
    # Histories with solve_time_s are already stamped from the start of setup (older ones: solve only).
    setup = 0.0 if "solve_time_s" in cols else float(run.get("time", {}).get("setup_s") or 0.0)
    df["time_s"] = pd.to_numeric(df["time_s"], errors="coerce") + setup
    if run.get("solver") == "cg":
        stat = pd.to_numeric(df["stationarity"], errors="coerce")
        start = float(stat.iloc[0]) if len(stat) and stat.iloc[0] > 0 else float("nan")
        df["error"] = stat / start
    else:
        df["error"] = pd.to_numeric(df["accuracy"], errors="coerce")
    return df


def summary_row(youngs: float, label: str, run: dict, tol: float) -> dict:
    df = error_curve(run)
    reach = df[df["error"] <= tol] if not df.empty else df
    counters = run.get("counters", {})
    info = run.get("info", {})
    return {
        "youngs": youngs,
        "config": label,
        "status": run.get("status"),
        "iterations": run.get("iterations"),
        "first_iteration_at_tol": float(reach["iteration"].iloc[0]) if len(reach) else math.nan,
        "first_time_at_tol_s": float(reach["time_s"].iloc[0]) if len(reach) else math.nan,
        "setup_s": run.get("time", {}).get("setup_s"),
        "solve_s": run.get("time", {}).get("solve_s"),
        "expansions": counters.get("expansion_steps"),
        "proportionings": counters.get("proportioning_steps"),
        "factorizations": counters.get("precond_factorizations"),
        "factor_nonzeros": (info.get("ichol") or {}).get("factor_nonzeros"),
        "a_nonzeros": (info.get("ichol") or {}).get("a_nonzeros"),
        "deflation_modes": (info.get("deflation") or {}).get("modes"),
    }


def plot(runs: Dict[float, Dict[str, dict]], out_dir: str, tol: float) -> List[str]:
    moduli = sorted(runs)
    fig, axes = plt.subplots(1, len(moduli), figsize=(3.2 * len(moduli), 3.2), sharey=True, squeeze=False)
    for ax, youngs in zip(axes[0], moduli):
        for label, run in sorted(runs[youngs].items()):
            df = error_curve(run)
            if df.empty:
                continue
            color, ls = STYLE.get(label, ("k", "-"))
            ax.plot(figutil.positive(df["time_s"]), figutil.positive(df["error"]), color=color, ls=ls, label=label)
        figutil.draw_tol(ax, tol)
        ax.set_xscale("log")
        ax.set_yscale("log")
        snap = next(iter(runs[youngs].values()), {}).get("snapshot") or {}
        ax.set_title(figutil.panel_title(f"E = {youngs:.0e} Pa", snap.get("n"), snap.get("m")), fontsize=9)
        ax.set_xlabel("time incl. setup (s)")
    axes[0][0].set_ylabel("relative error")
    fig.tight_layout()
    figutil.legend_outside(fig, axes.flat)
    return figutil.save_figure_outside(fig, out_dir, "stiff")


def load_runs(out_dir: str) -> Dict[float, Dict[str, dict]]:
    runs: Dict[float, Dict[str, dict]] = {}
    for path in sorted(glob.glob(os.path.join(out_dir, "runs", "*__*.json"))):
        stem = os.path.basename(path)[:-5]
        youngs, label = stem.split("__", 1)
        with open(path) as f:
            runs.setdefault(float(youngs), {})[label] = json.load(f)
    return runs


def write_outputs(runs: Dict[float, Dict[str, dict]], out_dir: str, tol: float) -> None:
    rows = [summary_row(e, label, run, tol) for e in sorted(runs) for label, run in sorted(runs[e].items())]
    table = pd.DataFrame(rows)
    tmp = os.path.join(out_dir, "stiff.csv.tmp")
    table.to_csv(tmp, index=False)
    os.replace(tmp, os.path.join(out_dir, "stiff.csv"))
    print(table.to_string(index=False))
    for path in plot(runs, out_dir, tol):
        print("wrote", path)


def run_all(binary: str, out_dir: str, moduli: List[float], tol: float, max_iterations: int, time_limit: float,
            scene_path_in: str = SCENE, frames: int = 1) -> None:
    os.makedirs(os.path.join(out_dir, "runs"), exist_ok=True)
    with open(scene_path_in) as f:
        scene = json.load(f)
    # Relative mesh paths are resolved against the scene's folder: make them absolute.
    for body in scene.get("bodies", []):
        mesh = body.get("mesh")
        if isinstance(mesh, str) and not os.path.isabs(mesh) and ":" not in mesh:
            body["mesh"] = os.path.join(os.path.dirname(os.path.abspath(scene_path_in)), mesh)
    for youngs in moduli:
        with tempfile.TemporaryDirectory() as tmp:
            scene["bodies"][0]["material"]["youngs"] = youngs
            scene_path = os.path.join(tmp, "stiff_slab.json")
            with open(scene_path, "w") as f:
                json.dump(scene, f)
            subprocess.run([binary, "simulate", scene_path, "--frames", str(frames), "--out", tmp], check=True,
                           stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
            snaps = sorted(glob.glob(os.path.join(tmp, "snapshots", "*.qpsnap")))
            if not snaps:
                raise SystemExit(f"plots/stiff.py: no snapshot for E = {youngs:g}")
            for label, (solver, settings) in CONFIGS.items():
                out = os.path.join(out_dir, "runs", f"{youngs:.0e}__{label}.json")
                cmd = [binary, "solve", snaps[-1], "--solver", solver, "--history", "--json", out,
                       "--time-limit", str(time_limit), "--set", f"tol={tol}", "--set", f"max_iterations={max_iterations}"]
                for k, v in settings.items():
                    cmd += ["--set", f"{k}={v}"]
                subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
                print(f"E = {youngs:.0e} {label}: done", file=sys.stderr)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("mode", choices=["run", "plot"])
    ap.add_argument("--out", default="results/stiff")
    ap.add_argument("--bin", default="build/bin/contactbench")
    ap.add_argument("--youngs", default="1e4,1e6,1e8,1e10,1e12")
    ap.add_argument("--scene", default=SCENE, help="a one-body scene (default scenes/stiff_slab.json)")
    ap.add_argument("--tol", type=float, default=1e-8)
    ap.add_argument("--max-iterations", type=int, default=20000)
    ap.add_argument("--time-limit", type=float, default=60.0)
    ap.add_argument("--frames", type=int, default=1,
                    help="simulate this many frames and solve the last snapshot (scenes/stiff_dino.json: 2)")
    args = ap.parse_args(argv)
    if args.mode == "run":
        try:
            moduli = [float(v) for v in args.youngs.split(",")]
        except ValueError:
            print(f"plots/stiff.py: --youngs: expected comma-separated numbers, got '{args.youngs}'", file=sys.stderr)
            return 2
        run_all(args.bin, args.out, moduli, args.tol, args.max_iterations, args.time_limit, args.scene, args.frames)
    runs = load_runs(args.out)
    if not runs:
        print(f"plots/stiff.py: {args.out}/runs: no run JSON (<E>__<config>.json)", file=sys.stderr)
        return 2
    write_outputs(runs, args.out, args.tol)
    return 0


if __name__ == "__main__":
    sys.exit(main())
