#!/usr/bin/python3
"""Reproduce the paper's figures and write results/paper/report.md, from our own simulator.

usage: reproduce.py --contactbench build/bin/contactbench [--data DIR (default $CB_CACHE/paper-data)]
                    [--out results/paper] [--scenes scenes] [--quick] [--force]

Steps (each printed as it runs):
1. simulate the scenes (contactbench simulate SCENE --frames N --out OUT/sim/<scene> --data DATA),
   skipped when OUT/sim/<scene> already holds a finished simulation (simulation.json) of the same
   scene file content, data source and simulator version, with >= N frames and unchanged mesh files;
2. pick the snapshots each figure needs and instantiate suites/paper/*.json into OUT/suites/;
3. contactbench run OUT/suites/<name>.json --out OUT/runs/<name>, skipped when that folder already
   holds the results of the identical suite from the same contactbench binary on snapshots of the
   same content (sha256 of each file) and data source (a simulation redone at the same paths, e.g.
   with the authors' meshes after `make demo`'s stand-ins, runs again; after a rebuild the
   harness resumes and redoes the runs whose identity changed; it caches reference solutions by
   snapshot content and reference method, so a rebuild does not redo them); a timed suite
   (TIMED_SUITES: fig6 5 rounds, fig10 and fig11 8) runs in rounds, round k > 1 into
   OUT/rounds/<name>/<k> with the solvers' order reversed in even rounds, each cached the same way
   (the claims' intervals come from the rounds: docs/work.md "Claims");
4. profiles.md per suite, the figures (fig6, fig8, fig9, fig10, fig11, table1) and the report.
A figure whose inputs are missing is reported as "not produced: <reason>".
--quick: the coarsest two-dinosaur meshes stand in for the eight dinosaurs (Figs. 6, 8 and, when
the quick long cube has no contact, Table 1's chain), few frames, short time limits; it aims at
< 5 minutes in all.
"""
from __future__ import annotations

import argparse
import glob
import hashlib
import json
import os
import re
import shutil
import subprocess
import sys
import threading
import time
from typing import Dict, List, Optional


import pandas as pd  # noqa: E402

from plots import profiles  # noqa: E402
from plots import report  # noqa: E402
from plots.intervals import min_rounds  # noqa: E402
from plots.loader import NOT_APPLICABLE_STATUS, UNMEASURED_STATUSES, load_results, snapshot_table  # noqa: E402
from plots.paper_context import PaperContext, default_data_dir  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
MARKER = ".reproduce.json"

#: frames simulated per scene (full, quick); None = not simulated in that mode. A full run takes
#: the scene file's own "frames" when smaller (two-dinosaur scenes always stop after frame 11).
FRAMES = {
    "two_dinos": (12, 12),        # Fig. 11 uses frame 11
    "eight_dinos": (200, None),   # Figs. 5, 6, 8, 9 (the authors' Fig. 6 has 200 frames)
    "longcube": (100, 12),        # Figs. 10, 12
    "dragon_stair": (100, None),  # Table 1 (Fig. 3)
    "bunny_glass": (150, None),   # Table 1 (Fig. 4)
}
#: scene file stems accepted for each key (the first found is used)
ALIASES = {
    "eight_dinos": ("eight_dinos", "dino_eight", "eight_dinosaurs"),
    "longcube": ("longcube", "long_cube"),
    "dragon_stair": ("dragon_stair",),
    "bunny_glass": ("bunny_glass",),
}
#: quick mode: how many two-dinosaur resolutions (the coarsest)
QUICK_RESOLUTIONS = 2
#: the most snapshots a chain suite runs (fig6 over the frames with contact; table1 per scene)
CHAIN_MAX = {"full": 60, "quick": 6}
TABLE1_MAX = {"full": 20, "quick": 4}
#: per-run time limit in quick mode [s]
QUICK_TIME_LIMIT_S = 10
QUICK_BUDGET_S = 280
#: timed suites and their interleaved rounds (docs/work.md "Claims"); the rounds alternate the order
#: of the solvers, so no label always runs first on a snapshot. 5 is the fewest whose [min, max] is
#: a >= 90% interval of the median; the cheap suites whose ratios lie near their thresholds (fig10,
#: fig11) run 8, whose interval [2nd, 7th] (93%) leaves out one slow or fast round on each side, so
#: that one round caught by a load spike does not widen it
TIMED_SUITES = {"fig6": min_rounds(), "fig10": 8, "fig11": 8}


def process_cpu() -> float:
    """User + system CPU seconds of this process and of its children that have been waited for."""
    t = os.times()
    return t.user + t.system + t.children_user + t.children_system


class Runner:
    """Shells out to contactbench, logs every command, keeps a time budget."""

    def __init__(self, contactbench: str, budget_s: Optional[float], log_path: str):
        self.cb = contactbench
        self.start = time.monotonic()
        self.cpu_start = process_cpu()
        self.budget = budget_s
        self.steps: List[str] = []
        self.log_path = log_path

    def elapsed(self) -> float:
        return time.monotonic() - self.start

    def cpu(self) -> float:
        """CPU seconds (user + system) since the start, of this process and of the contactbench
        runs it waited for: on a loaded machine the wall time grows with the load, this much less."""
        return process_cpu() - self.cpu_start

    def remaining(self) -> Optional[float]:
        return None if self.budget is None else self.budget - self.elapsed()

    def say(self, text: str) -> None:
        print(f"[reproduce {self.elapsed():6.1f}s] {text}", flush=True)

    def call(self, args: List[str], what: str) -> (int, str):
        """Runs contactbench, echoing its output lines (indented) and logging them; returns
        (exit status, last stderr line). 124 = timed out or no time budget left."""
        rem = self.remaining()
        if rem is not None and rem < 5:
            self.steps.append(f"{what}: skipped (quick-mode time budget exhausted)")
            return 124, "quick-mode time budget exhausted"
        cmd = [self.cb] + args
        self.say(f"{what}: {' '.join(cmd)}")
        t0, cpu0 = time.monotonic(), self.cpu()
        timeout = rem if rem is not None else 6 * 3600
        errors: List[str] = []
        try:
            with open(self.log_path, "a", encoding="utf-8") as log:
                log.write(f"\n$ {' '.join(cmd)}\n")
                log.flush()
                with subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                                      bufsize=1) as proc:
                    timer = threading.Timer(timeout, proc.kill)
                    timer.start()
                    try:
                        for line in proc.stdout:
                            log.write(line)
                            print("    " + line.rstrip(), flush=True)
                            if line.strip():
                                errors.append(line.strip())
                                errors[:] = errors[-1:]
                        proc.wait()
                    finally:
                        timer.cancel()
        except OSError as err:
            self.steps.append(f"{what}: could not start: {err}")
            return 127, str(err)
        dt = time.monotonic() - t0
        rc = proc.returncode
        if rc is not None and rc < 0 and dt >= timeout - 1:
            self.steps.append(f"{what}: timed out after {dt:.0f} s")
            self.say(f"{what}: timed out after {dt:.0f} s")
            return 124, f"timed out after {dt:.0f} s"
        err = errors[-1] if errors else ""
        cpu = self.cpu() - cpu0
        self.steps.append(f"{what}: exit {rc} in {dt:.1f} s (CPU {cpu:.1f} s)" + (f" ({err})" if rc else ""))
        self.say(f"{what}: exit {rc} in {dt:.1f} s (CPU {cpu:.1f} s)")
        return rc, err


_SHA_CACHE: Dict[tuple, str] = {}


def file_sha(path: str) -> str:
    """sha256 (16 hex digits) of a file's content; memoised on (path, size, mtime) within the
    process, since a timed suite's rounds key on the same snapshots."""
    st = os.stat(path)
    memo = (os.path.abspath(path), st.st_size, st.st_mtime_ns)
    if memo not in _SHA_CACHE:
        _SHA_CACHE[memo] = _sha_of_content(path)
    return _SHA_CACHE[memo]


def _sha_of_content(path: str) -> str:
    digest = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()[:16]


def snapshot_source(path: str) -> str:
    """Where a simulated snapshot's meshes came from, read from its simulation's simulation.json
    (OUT/sim/<key>/snapshots/<file> -> OUT/sim/<key>/simulation.json): "authors' data DIR" or
    "stand-in meshes"; "unknown" for a snapshot outside a simulation folder."""
    record = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(path))), "simulation.json")
    try:
        with open(record, encoding="utf-8") as f:
            data = json.load(f).get("data") or ""
    except (OSError, ValueError, AttributeError):
        return "unknown"
    return f"authors' data {data}" if data else "stand-in meshes"


def snapshot_key(paths: List[str]) -> Dict[str, dict]:
    """The cache key of a suite's inputs beyond the suite file: per snapshot path, its content's
    sha256 and its source (a path holds other content after a simulation is redone)."""
    key = {}
    for p in paths:
        try:
            key[p] = {"sha256": file_sha(p), "source": snapshot_source(p)}
        except OSError as err:
            key[p] = {"sha256": None, "source": f"unreadable: {err.strerror}"}
    return key


def read_marker(folder: str) -> dict:
    path = os.path.join(folder, MARKER)
    if not os.path.isfile(path):
        return {}
    with open(path, encoding="utf-8") as f:
        return json.load(f)


def write_marker(folder: str, content: dict) -> None:
    with open(os.path.join(folder, MARKER), "w", encoding="utf-8") as f:
        json.dump(content, f, indent=1)


def scene_files(scenes_dir: str) -> Dict[str, str]:
    """scene key -> file; two-dinosaur resolutions as two_dinos_<vertices>."""
    found = {}
    for path in sorted(glob.glob(os.path.join(scenes_dir, "*.json"))):
        found[os.path.splitext(os.path.basename(path))[0]] = path
    for key, names in ALIASES.items():
        for name in names:
            if name in found and key not in found:
                found[key] = found[name]
    return found


def scene_frames(path: str, fallback: int) -> int:
    """The scene's own "frames" (the simulator's default), else `fallback`."""
    try:
        with open(path, encoding="utf-8") as f:
            value = json.load(f).get("frames")
        return int(value) if isinstance(value, int) and value > 0 else fallback
    except (OSError, ValueError, AttributeError):
        return fallback


def two_dino_keys(found: Dict[str, str]) -> List[str]:
    keys = [k for k in found if re.fullmatch(r"two_dinos_\d+", k)]
    return sorted(keys, key=lambda k: int(k.rsplit("_", 1)[1]))


def simulator_version(runner: Runner) -> Optional[str]:
    """`contactbench simulate --version` ("simulator N"), once per Runner; None when it fails."""
    if not hasattr(runner, "_simulator_version"):
        try:
            done = subprocess.run([runner.cb, "simulate", "--version"], capture_output=True, text=True, timeout=60)
            runner._simulator_version = done.stdout.strip() if done.returncode == 0 else None
        except OSError:
            runner._simulator_version = None
    return runner._simulator_version


def simulation_key(runner: Runner, scene: str, data: Optional[str]) -> dict:
    """Every input of a simulation but its frame count and mesh files (those are checked apart):
    the scene file's content, the data source and the simulator's version."""
    return {"scene_sha": file_sha(scene), "data": os.path.abspath(data) if data else None,
            "data_present": bool(data and os.path.isdir(data)), "simulator": simulator_version(runner)}


def simulation_meshes(folder: str) -> Optional[Dict[str, str]]:
    """Mesh file -> sha of a finished simulation (its simulation.json, written last), else None."""
    path = os.path.join(folder, "simulation.json")
    if not os.path.isfile(path):
        return None
    try:
        with open(path, encoding="utf-8") as f:
            meshes = json.load(f).get("meshes", [])
        return {m: file_sha(m) for m in meshes}
    except (OSError, ValueError, AttributeError):
        return None


def simulate(runner: Runner, ctx: PaperContext, key: str, scene: str, frames: int, data: Optional[str],
             force: bool) -> Optional[str]:
    """Simulates once (cached on the scene file, mesh files, data source, frames and simulator
    version); returns the folder, or None with ctx.reasons[key] set."""
    folder = os.path.join(ctx.out, "sim", key)
    inputs = simulation_key(runner, scene, data)
    marker = read_marker(folder)
    meshes = simulation_meshes(folder)
    if not force and marker.get("inputs") == inputs and marker.get("frames", 0) >= frames and \
            meshes is not None and marker.get("meshes") == meshes and \
            os.path.isdir(os.path.join(folder, "snapshots")):
        runner.say(f"simulate {key}: cached ({marker['frames']} frames in {folder})")
        runner.steps.append(f"simulate {key}: cached ({marker['frames']} frames)")
        ctx.sims[key] = folder
        return folder
    if marker:
        why = [k for k in inputs if marker.get("inputs", {}).get(k) != inputs[k]]
        if meshes is not None and marker.get("meshes") != meshes:
            why.append("mesh files")
        if why:
            runner.say(f"simulate {key}: not reused, changed: {', '.join(why)}")
    if os.path.isdir(folder):
        shutil.rmtree(folder)
    os.makedirs(folder, exist_ok=True)
    args = ["simulate", scene, "--frames", str(frames), "--out", folder]
    if data:
        args += ["--data", data]
    rc, err = runner.call(args, f"simulate {key}")
    snaps = snapshot_table(os.path.join(folder, "snapshots")) if os.path.isdir(os.path.join(folder, "snapshots")) \
        else pd.DataFrame()
    if rc != 0 or snaps.empty:
        ctx.reasons[key] = f"simulation of {os.path.basename(scene)} failed (exit {rc}{': ' + err if err else ''})" \
            if rc != 0 else f"simulation of {os.path.basename(scene)} wrote no snapshots"
        return None
    write_marker(folder, {"scene": scene, "inputs": inputs, "frames": frames,
                          "meshes": simulation_meshes(folder) or {}})
    ctx.sims[key] = folder
    return folder


def snapshots_of(ctx: PaperContext, key: str) -> pd.DataFrame:
    folder = ctx.sims.get(key)
    if not folder:
        return pd.DataFrame()
    return snapshot_table(os.path.join(folder, "snapshots"))


def instantiate(template: str, name: str, snapshots: List[str], out: str, quick: bool,
                round_index: int = 1) -> str:
    """The runnable suite OUT/suites/<name>.json (round 1) or <name>.round<k>.json: round k > 1 is
    the same suite, its solvers in reverse order when k is even."""
    with open(template, encoding="utf-8") as f:
        suite = json.load(f)
    suite["name"] = name
    if round_index % 2 == 0:
        suite["solvers"] = list(reversed(suite.get("solvers", [])))
    suite["snapshots"] = [os.path.abspath(p) for p in snapshots]
    if quick:
        suite["time_limit_s"] = min(float(suite.get("time_limit_s", QUICK_TIME_LIMIT_S)), QUICK_TIME_LIMIT_S)
        for s in suite.get("solvers", []):
            if "time_limit_s" in s.get("settings", {}):
                s["settings"]["time_limit_s"] = min(s["settings"]["time_limit_s"], QUICK_TIME_LIMIT_S)
    os.makedirs(os.path.join(out, "suites"), exist_ok=True)
    path = os.path.join(out, "suites", f"{name}.json" if round_index == 1 else f"{name}.round{round_index}.json")
    with open(path, "w", encoding="utf-8") as f:
        json.dump(suite, f, indent=1)
    return path


def round_folder(out: str, name: str, round_index: int) -> str:
    """Round 1 of a suite is OUT/runs/<name>; round k > 1 is OUT/rounds/<name>/<k>."""
    return os.path.join(out, "runs", name) if round_index == 1 else os.path.join(out, "rounds", name, str(round_index))


def run_suite(runner: Runner, ctx: PaperContext, name: str, template: str, snapshots: List[str],
              force: bool) -> None:
    """Runs a suite; a timed suite (TIMED_SUITES) in its rounds, one after the other."""
    if not snapshots:
        ctx.reasons.setdefault(name, f"no snapshots selected for suite '{name}'")
        return
    rounds = TIMED_SUITES.get(name, 1)
    for k in range(1, rounds + 1):
        run_round(runner, ctx, name, template, snapshots, force, k, rounds)
        if name in ctx.reasons:
            return
    if rounds > 1:
        ctx.rounds[name] = [round_folder(ctx.out, name, k) for k in range(1, rounds + 1)
                            if os.path.isfile(os.path.join(round_folder(ctx.out, name, k), "summary.csv"))]


def run_round(runner: Runner, ctx: PaperContext, name: str, template: str, snapshots: List[str], force: bool,
              round_index: int, rounds: int) -> None:
    suite_path = instantiate(template, name, snapshots, ctx.out, ctx.quick, round_index)
    with open(suite_path, encoding="utf-8") as f:
        suite = json.load(f)
    folder = round_folder(ctx.out, name, round_index)
    if round_index > 1:
        name_shown = f"{name} round {round_index}/{rounds}"
        rc, _ = _run_cached(runner, suite, suite_path, folder, name_shown, force)
        if rc != 0:
            ctx.notes.setdefault(name, []).append(f"round {round_index} of {rounds}: contactbench run exited {rc}")
        return
    marker = read_marker(folder)
    # The suite, the snapshots' content and source, and the build: contactbench itself redoes a
    # run whose snapshot, settings or build changed (run identity), and keys reference solutions
    # on content and method, not the binary.
    build = file_sha(runner.cb) if os.path.isfile(runner.cb) else None
    inputs = snapshot_key(suite.get("snapshots", []))
    ctx.judged[name] = inputs
    if not force and marker.get("suite") == suite and marker.get("build") == build and \
            marker.get("snapshots") == inputs and os.path.isfile(os.path.join(folder, "summary.csv")):
        runner.say(f"run {name}: cached ({folder})")
        runner.steps.append(f"run {name}: cached")
        ctx.results[name] = folder
        return
    if marker.get("suite") == suite and marker.get("snapshots") not in (None, inputs):
        runner.say(f"run {name}: not reused, changed: snapshot content or source")
    if os.path.isdir(folder) and (force or marker.get("suite") != suite):
        shutil.rmtree(folder)  # another suite: start over; same suite, new build: resume (identity decides)
    rc, err = runner.call(["run", suite_path, "--out", folder], f"run {name}")
    ctx.results[name] = folder
    has_runs = os.path.isdir(os.path.join(folder, "runs")) and any(
        n.endswith(".json") for n in os.listdir(os.path.join(folder, "runs")))
    refused = unmeasured_count(folder)
    if rc == 0 and has_runs and not refused:
        write_marker(folder, {"suite": suite, "build": build, "snapshots": inputs})
    elif has_runs and refused:
        # not cached: a solver that is missing today may be registered by the next build
        ctx.notes.setdefault(name, []).append(f"{refused} run(s) refused by contactbench (see the notes below); "
                                              "the suite is re-run next time")
    elif has_runs:
        ctx.notes.setdefault(name, []).append(f"contactbench run exited {rc} ({err}); partial results used")
    else:
        ctx.reasons[name] = f"contactbench run {name} failed (exit {rc}{': ' + err if err else ''})"


def _run_cached(runner: Runner, suite: dict, suite_path: str, folder: str, what: str, force: bool) -> (int, str):
    """A repeat round of a suite, cached like round 1 (same suite, snapshot content and binary)."""
    marker = read_marker(folder)
    build = file_sha(runner.cb) if os.path.isfile(runner.cb) else None
    inputs = snapshot_key(suite.get("snapshots", []))
    if not force and marker.get("suite") == suite and marker.get("build") == build and \
            marker.get("snapshots") == inputs and os.path.isfile(os.path.join(folder, "summary.csv")):
        runner.steps.append(f"run {what}: cached")
        return 0, ""
    if os.path.isdir(folder):
        shutil.rmtree(folder)  # a round is only ever the whole suite on one build: start over
    os.makedirs(os.path.dirname(folder), exist_ok=True)
    rc, err = runner.call(["run", suite_path, "--out", folder], f"run {what}")
    if rc == 0 and os.path.isfile(os.path.join(folder, "summary.csv")):
        write_marker(folder, {"suite": suite, "build": build, "snapshots": inputs})
    return rc, err


def unmeasured_count(folder: str) -> int:
    """Runs of a results folder that did not run (invalid_input / not_run; not_applicable runs are
    answered, not refused)."""
    try:
        res = load_results(folder, with_history=False)
    except (FileNotFoundError, ValueError):
        return 0
    return len(measured_complement(res.runs))


def measured_complement(runs: pd.DataFrame) -> pd.DataFrame:
    if runs.empty or "status" not in runs:
        return runs.iloc[0:0]
    # not_applicable is a property of the problem class, not of today's build: no reason to re-run
    return runs[runs["status"].isin(UNMEASURED_STATUSES) & (runs["status"] != NOT_APPLICABLE_STATUS)]


def pick_max_rows(snaps: pd.DataFrame, target: Optional[int] = None) -> List[str]:
    """The snapshot with the most rows (or the one nearest `target` rows among those with contact)."""
    if snaps.empty:
        return []
    with_rows = snaps[snaps["m"] > 0]
    if with_rows.empty:
        return [snaps.iloc[-1]["path"]]
    if target:
        idx = (with_rows["m"] - target).abs().idxmin()
        return [with_rows.loc[idx, "path"]]
    return [with_rows.sort_values("m", ascending=False).iloc[0]["path"]]


def pick_frame(snaps: pd.DataFrame, frame: int) -> List[str]:
    if snaps.empty:
        return []
    sel = snaps[snaps["frame"] == frame]
    if sel.empty:
        sel = snaps.iloc[[-1]]  # fewer frames than asked: the last one, said in the notes
    return [sel.iloc[0]["path"]]


def chain_with_contact(snaps: pd.DataFrame, limit: int) -> List[str]:
    """Consecutive snapshots from just before the first contact, at most `limit`."""
    if snaps.empty:
        return []
    contact = snaps.index[snaps["m"] > 0]
    start = max(0, int(contact[0]) - 2) if len(contact) else max(0, len(snaps) - limit)
    return list(snaps.iloc[start:start + limit]["path"])


def evenly(snaps: pd.DataFrame, limit: int) -> List[str]:
    if snaps.empty:
        return []
    if len(snaps) <= limit:
        return list(snaps["path"])
    step = len(snaps) / limit
    return [snaps.iloc[int(i * step)]["path"] for i in range(limit)]


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--contactbench", default=os.path.join(ROOT, "build", "bin", "contactbench"))
    parser.add_argument("--data", default=default_data_dir(),
                        help="the authors' data, as `make paper-data` writes it (default: $CB_CACHE/paper-data)")
    parser.add_argument("--out", default=os.path.join(ROOT, "results", "paper"))
    parser.add_argument("--scenes", default=os.path.join(ROOT, "scenes"))
    parser.add_argument("--suites", default=os.path.join(ROOT, "suites", "paper"))
    parser.add_argument("--quick", action="store_true", help="coarse meshes, few frames (< 5 minutes)")
    parser.add_argument("--force", action="store_true", help="re-simulate and re-run even when cached")
    parser.add_argument("--no-profiles", action="store_true", help="skip profiles.md per suite (faster)")
    args = parser.parse_args(argv)
    os.environ.setdefault("CB_REPORT", "0")  # one HTML page for the whole reproduction, at the end: none per suite

    out = os.path.abspath(args.out)
    os.makedirs(out, exist_ok=True)
    data = os.path.abspath(args.data) if args.data and os.path.isdir(args.data) else None
    ctx = PaperContext(out=out, data=data, quick=args.quick)
    runner = Runner(os.path.abspath(args.contactbench), QUICK_BUDGET_S if args.quick else None,
                    os.path.join(out, "reproduce.log"))
    mode = "quick" if args.quick else "full"
    runner.say(f"mode {mode}; out {out}; data {data or '(none)'}; contactbench {runner.cb}")
    if not data:
        runner.say(f"no authors' data at {args.data} (`make paper-data` fetches it): the scenes use the CGAL "
                   "stand-in meshes and the figures leave out the authors' curves")

    all_suites = ["fig6", "fig8", "fig10", "fig11"]
    found = scene_files(args.scenes)
    dinos = two_dino_keys(found)
    if args.quick:
        dinos = dinos[:QUICK_RESOLUTIONS]
    cb_ok = os.path.isfile(runner.cb) and os.access(runner.cb, os.X_OK)
    if not cb_ok:
        reason = f"contactbench binary not found at {runner.cb} (build it: make build)"
        runner.say(reason)
        for key in all_suites + ["table1-" + s for s in FRAMES]:
            ctx.reasons[key] = reason
    else:
        # 1. simulations
        plan = [(k, found[k], FRAMES["two_dinos"][1 if args.quick else 0]) for k in dinos]
        for key in ("longcube", "eight_dinos", "dragon_stair", "bunny_glass"):
            frames = FRAMES[key][1 if args.quick else 0]
            if frames is None:
                continue
            if not args.quick and key in found:
                frames = min(frames, scene_frames(found[key], frames))  # the scene's own, capped
            if key not in found:
                ctx.reasons[key] = "no scene file scenes/{" + ",".join(ALIASES[key]) + "}.json"
                runner.say(ctx.reasons[key])
                continue
            plan.append((key, found[key], frames))
        if not dinos:
            ctx.reasons["fig11"] = "no scenes/two_dinos_<vertices>.json"
        for key, scene, frames in plan:
            simulate(runner, ctx, key, scene, frames, data, args.force)

        # 2-3. suites
        tpl = lambda name: os.path.join(args.suites, f"{name}.json")  # noqa: E731
        eight = snapshots_of(ctx, "eight_dinos")
        small = snapshots_of(ctx, dinos[0]) if dinos else pd.DataFrame()
        if args.quick or eight.empty:
            sub = "quick mode" if args.quick else ctx.reasons.get("eight_dinos", "eight dinosaurs not simulated")
            if not small.empty:
                note = f"{sub}: the coarsest two-dinosaur scene ({dinos[0]}) stands in for the eight dinosaurs"
                for s in ("fig6", "fig8"):
                    ctx.notes.setdefault(s, []).append(note)
                run_suite(runner, ctx, "fig11", tpl("fig11"),
                          [p for k in dinos for p in pick_frame(snapshots_of(ctx, k), 11)], args.force)
                run_suite(runner, ctx, "fig8", tpl("fig8"), pick_frame(small, 11), args.force)
                run_suite(runner, ctx, "fig6", tpl("fig6"), chain_with_contact(small, CHAIN_MAX[mode]), args.force)
            else:
                for s in ("fig6", "fig8"):
                    ctx.reasons[s] = f"{sub}, and no two-dinosaur simulation to stand in"
        else:
            run_suite(runner, ctx, "fig8", tpl("fig8"), pick_max_rows(eight, target=691), args.force)
            run_suite(runner, ctx, "fig6", tpl("fig6"), chain_with_contact(eight, CHAIN_MAX[mode]), args.force)
        if dinos and "fig11" not in ctx.results and "fig11" not in ctx.reasons:
            run_suite(runner, ctx, "fig11", tpl("fig11"),
                      [p for k in dinos for p in pick_frame(snapshots_of(ctx, k), 11)], args.force)
        cube = snapshots_of(ctx, "longcube")
        cube_contact = not cube.empty and bool((cube["m"] > 0).any())
        if cube_contact and not args.quick:
            run_suite(runner, ctx, "fig10", tpl("fig10"), pick_max_rows(cube), args.force)
        elif not small.empty:
            why = "quick mode" if args.quick else ("the long cube had no contact in the frames simulated"
                                                   if not cube.empty else ctx.reasons.get("longcube", "no long cube"))
            ctx.notes.setdefault("fig10", []).append(
                f"{why}: frame 11 of {dinos[0]} stands in for the long-cube QP")
            run_suite(runner, ctx, "fig10", tpl("fig10"), pick_frame(small, 11), args.force)
        else:
            ctx.reasons["fig10"] = ctx.reasons.get("longcube", "long cube not simulated")
        for key in ("longcube", "eight_dinos", "dragon_stair", "bunny_glass"):
            snaps = snapshots_of(ctx, key)
            if snaps.empty:
                continue
            run_suite(runner, ctx, f"table1-{key}", tpl("table1"), evenly(snaps, TABLE1_MAX[mode]), args.force)
        if args.quick and eight.empty and not cube_contact and not small.empty and bool((small["m"] > 0).any()):
            # Table 1's claims are about frames with contact rows; the quick long cube has none
            ctx.notes.setdefault("table1", []).append(
                f"quick mode: the long cube has no contact row in the {len(cube)} frames simulated; the coarsest "
                f"two-dinosaur chain ({dinos[0]}, from 2 frames before its first contact) stands in for the eight "
                "dinosaurs' chain")
            run_suite(runner, ctx, "table1-eight_dinos", tpl("table1"), chain_with_contact(small, CHAIN_MAX[mode]),
                      args.force)

    # 4. profiles, figures, report
    profile_paths = {}
    provenance = {}
    for name, folder in sorted(ctx.results.items()):
        if name in ctx.reasons or args.no_profiles:
            continue
        try:
            res = load_results(folder)
        except (FileNotFoundError, ValueError):
            continue
        if res.runs.empty:
            continue
        provenance = provenance or res.provenance
        t0 = time.monotonic()
        runner.say(f"profiles {name}: {len(res.runs)} runs ...")
        numbers = profiles.compute(res)
        figs = profiles.plot_profiles(numbers, os.path.join(folder, "figures"), res.runs)
        md = os.path.join(folder, "profiles.md")
        profiles.write_markdown(res, numbers, md, figs)
        profile_paths[name] = md
        runner.say(f"profiles {name}: wrote {md} in {time.monotonic() - t0:.1f} s")
    runner.say("figures and claims: fig6, fig8, fig9, fig10, fig11, table1 ...")
    outcomes = report.produce_all(ctx, log=runner.say)
    for o in outcomes:
        for suite in (o.name, "fig8" if o.name == "fig9" else o.name):
            for note in ctx.notes.get(suite, []):
                if note not in o.notes:
                    o.notes.append(note)
    previous = {}
    meta_path = os.path.join(out, "reproduce.json")
    if os.path.isfile(meta_path):
        with open(meta_path, encoding="utf-8") as f:
            previous = json.load(f)
    elapsed = runner.elapsed()
    full_run_s = elapsed if not args.quick else previous.get("full_run_s")
    full_run_cpu_s = runner.cpu() if not args.quick else previous.get("full_run_cpu_s")
    strips = {}
    for key, folder in sorted(ctx.sims.items()):
        found_strips = sorted(glob.glob(os.path.join(folder, "*_strip.png")))
        if found_strips:
            strips[key] = found_strips[0]
    meta = {"quick": args.quick, "elapsed_s": elapsed, "cpu_s": runner.cpu(), "strips": strips, "full_run_s": full_run_s,
            "full_run_cpu_s": full_run_cpu_s, "steps": runner.steps,
            "reasons": ctx.reasons, "profiles": profile_paths, "provenance": provenance,
            "contactbench": runner.cb, "data": data, "judged": ctx.judged}
    if full_run_s is None:
        meta["steps"] = meta["steps"] + ["no full run recorded yet in this folder (make reproduce without QUICK)"]
    path = report.write_report(ctx, outcomes, meta)
    with open(meta_path, "w", encoding="utf-8") as f:
        json.dump(meta, f, indent=1)
    produced = [o.name for o in outcomes if not o.missing]
    missing = [f"{o.name} ({o.missing})" for o in outcomes if o.missing]
    runner.say(f"wrote {path}; produced: {', '.join(produced) or 'none'}")
    if missing:
        runner.say("not produced: " + "; ".join(missing))
    from plots import html_report  # issue 46: the reproduction's HTML page, claims and figures linked
    html_report.report_at_end(out, runner.say)
    return 0


if __name__ == "__main__":
    sys.exit(main())
