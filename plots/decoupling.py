"""The price of decoupling along whole chains (issue 25): runs `contactbench chains` on scenes at
their time step and at half of it (cached), draws the chain figures, writes the table, and gives
the data of the claim rows for Sec. 5, 6 and 7 by the rule of docs/simulator.md "The price of
decoupling" (fixed before the paper scenes were run; its numbers are the constants below).

usage: decoupling.py SCENE.json [SCENE.json ...] --out DIR [--frames N] [--no-half-step]
                     [--cb PATH] [--data DIR] [--force]
       decoupling.py --report DIR        figures, table and claims of the chains already in DIR

Writes DIR/chains/<scene>/{h,h2}/ (the `chains` folders), DIR/figures/decoupling_<scene>_<h>.png
(penetration and divergence against frame), DIR/decoupling.md (the table and the claim rows) and
DIR/decoupling_claims.json (claim_rows(): what plots/claims.py can turn into Claim rows)."""
from __future__ import annotations

import argparse
import hashlib
import json
import math
import os
import shutil
import subprocess
import sys
from typing import Dict, List, Optional, Tuple

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

import figutil  # noqa: E402
from figutil import plt  # noqa: E402

#: sim/chains.hpp CHAINS_VERSION: a cached folder of another version is run again
CHAINS_VERSION = 5

# The rule for "noticeable" (docs/simulator.md). p: the deepest vertex inside a body or obstacle
# at a frame's end, relative to L (the smallest body's largest extent at rest).
NOTICEABLE = 0.01     #: a frame's penetration is noticeable above 1% of L (2-3 pixels in the video)
PRICE_FACTOR = 2.0    #: ... and it is decoupling's price when also > 2x the exact chains' maximum
NO_PRICE_FACTOR = 1.25  #: no price when <= 1% or <= 1.25x the exact chains' maximum
PRICE_TO_REDUCE = 0.005  #: Sec. 5: a scene has a price to reduce when the excess is > 0.5% of L

EXACT = "exact"
NOISE = "exact-tol1e-6"
CONTROL = "authors-exact"  #: the exact solver on the authors' kept rows (`chains --control`)
ORDERS = ("authors", "random", "depth")
STEPS = {"h": "the scene's step", "h2": "half the scene's step"}

REPORT_STEM = "decoupling"  #: the table and claims page: OUT/decoupling.md

HOLDS, DOES_NOT_HOLD, INCONCLUSIVE, NOT_MEASURED = "holds", "does not hold", "inconclusive", "not measured"
NOT_EXERCISED = "not exercised"  #: the decoupled chain kept every row: the run says nothing about decoupling


# ----------------------------------------------------------------------------- running (cached)

def file_sha(path: str) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def simulator_version(cb: str) -> Optional[str]:
    try:
        done = subprocess.run([cb, "simulate", "--version"], capture_output=True, text=True, timeout=60)
    except OSError:
        return None
    return done.stdout.strip() if done.returncode == 0 else None


def chains_key(cb: str, scene: str, frames: int, h: Optional[float], data: Optional[str]) -> dict:
    """Every input of a chains folder: the scene file's content, the frames, the step, the data
    folder and the versions of the simulator and of the chains' output."""
    return {"scene_sha": file_sha(scene), "frames": frames, "h": h,
            "data": os.path.abspath(data) if data else None, "simulator": simulator_version(cb),
            "chains_version": CHAINS_VERSION}


def read_json(path: str) -> dict:
    try:
        with open(path, encoding="utf-8") as f:
            return json.load(f)
    except (OSError, ValueError):
        return {}


def run_chains(cb: str, scene: str, folder: str, frames: int, h: Optional[float] = None,
               data: Optional[str] = None, force: bool = False, control: bool = False) -> Tuple[bool, str]:
    """Runs `contactbench chains` into folder unless a finished run of the same inputs is there
    (its key.json, written after chains.json); an interrupted run of the same inputs (key.pending.json,
    written before it started, and chains.state) is resumed by chains from its last whole frame.
    control adds the authors-exact chain. Returns (ok, what happened)."""
    key = chains_key(cb, scene, frames, h, data)
    if control:
        key["control"] = True
    if not force and read_json(os.path.join(folder, "key.json")) == key and \
            os.path.isfile(os.path.join(folder, "chains.json")):
        return True, f"cached ({folder})"
    pending = os.path.join(folder, "key.pending.json")
    resume = not force and read_json(pending) == key and os.path.isfile(os.path.join(folder, "chains.state"))
    if not resume:
        if os.path.isdir(folder):
            shutil.rmtree(folder)
        os.makedirs(folder)
        with open(pending + ".partial", "w", encoding="utf-8") as f:
            json.dump(key, f, indent=1)
        os.replace(pending + ".partial", pending)
    args = [cb, "chains", scene, "--frames", str(frames), "--out", folder]
    if h is not None:
        args += ["--h", repr(h)]
    if data:
        args += ["--data", data]
    if control:
        args.append("--control")
    with open(os.path.join(folder, "chains.log"), "a" if resume else "w", encoding="utf-8") as log:
        rc = subprocess.run(args, stdout=log, stderr=subprocess.STDOUT).returncode
    if rc != 0 or not os.path.isfile(os.path.join(folder, "chains.json")):
        return False, f"contactbench chains failed (exit {rc}; {folder}/chains.log)"
    tmp = os.path.join(folder, "key.json.partial")
    with open(tmp, "w", encoding="utf-8") as f:
        json.dump(key, f, indent=1)
    os.replace(tmp, os.path.join(folder, "key.json"))
    os.remove(pending)
    return True, f"{'resumed' if resume else 'ran'} ({folder})"


# ----------------------------------------------------------------------------- reading, numbers

def load(folder: str) -> Tuple[pd.DataFrame, dict]:
    """chains.csv as a frame (numbers parsed) and chains.json."""
    df = pd.read_csv(os.path.join(folder, "chains.csv"))
    return df, read_json(os.path.join(folder, "chains.json"))


def _max(series: pd.Series) -> float:
    values = pd.to_numeric(series, errors="coerce").to_numpy(dtype=float)
    values = values[np.isfinite(values)]
    return float(values.max()) if values.size else math.nan


def summarize(df: pd.DataFrame, record: dict) -> dict:
    """Per chain: max and mean penetration (relative to L; the mean over the frames where the
    exact chain has contact rows), max chain distance, rows dropped; and the noise floor."""
    exact = df[df["chain"] == EXACT]
    contact_frames = set(exact.loc[exact["rows"] > 0, "frame"])
    chains: Dict[str, dict] = {}
    for label, rows in df.groupby("chain", sort=False):
        in_contact = rows[rows["frame"].isin(contact_frames)]
        pen = pd.to_numeric(in_contact["penetration_rel"], errors="coerce")
        total = float(rows["rows"].sum())
        chains[label] = {
            "max_penetration_rel": _max(rows["penetration_rel"]),
            # chains of version < 4 have no count: nan
            "max_vertices_inside": _max(rows["vertices_inside"]) if "vertices_inside" in rows else math.nan,
            "mean_penetration_rel": float(pen.mean()) if len(pen) else math.nan,
            "max_violation_rel": _max(rows["violation_rel"]),
            "max_distance_rel": _max(rows["max_distance_rel"]),
            "max_rms_distance_rel": _max(rows["rms_distance_rel"]),
            "rows_dropped_fraction": float(rows["rows_dropped"].sum()) / total if total > 0 else 0.0,
            "frames": int(rows["frame"].max()) + 1 if len(rows) else 0,
            "blow_up": bool(rows["blow_up"].astype(int).any()),
            "steps_not_solved": int(rows["steps_not_solved"].sum()),
        }
    exact_max = max((chains[c]["max_penetration_rel"] for c in (EXACT, NOISE) if c in chains), default=math.nan)
    return {"scene": record.get("scene", "?"), "h": record.get("h"), "frames": record.get("frames"),
            "exact_solver": exact_solver(record),
            "body_size": record.get("body_size"), "contact_frames": len(contact_frames),
            "chains": chains, "exact_max_penetration_rel": exact_max,
            "noise_floor_rel": chains.get(NOISE, {}).get("max_distance_rel", math.nan),
            "render": record.get("render", {})}


def exact_solver(record: dict) -> str:
    """The solver of the exact chain (chains.json's chains), "?" when the record does not say."""
    for chain in record.get("chains", []):
        if isinstance(chain, dict) and chain.get("label") == EXACT:
            return str(chain.get("solver", "?"))
    return "?"


def price(summary: dict, order: str = "authors") -> str:
    """Does decoupling in this order have a noticeable price on this run? (the rule above)"""
    chain = summary["chains"].get(order)
    p_exact = summary["exact_max_penetration_rel"]
    if chain is None or not math.isfinite(chain["max_penetration_rel"]) or not math.isfinite(p_exact):
        return NOT_MEASURED
    if chain["rows_dropped_fraction"] == 0:
        return NOT_EXERCISED  # no row dropped: nothing of decoupling to judge
    p = chain["max_penetration_rel"]
    if p > NOTICEABLE and p > PRICE_FACTOR * p_exact:
        return "noticeable"
    if p <= NOTICEABLE or p <= NO_PRICE_FACTOR * p_exact:
        return "none"
    return INCONCLUSIVE


def excess(summary: dict, order: str) -> float:
    chain = summary["chains"].get(order)
    return chain["max_penetration_rel"] - summary["exact_max_penetration_rel"] if chain else math.nan


# ----------------------------------------------------------------------------- claims

def _pct(x: float) -> str:
    return "n/a" if x is None or not math.isfinite(x) else f"{100 * x:.2g}%"


def _numbers(s: dict) -> str:
    a = s["chains"].get("authors", {})
    return (f"{s['scene']} ({s['frames']} frames, h {s['h']} s): max penetration authors "
            f"{_pct(a.get('max_penetration_rel', math.nan))} vs exact {_pct(s['exact_max_penetration_rel'])} of L")


def claim_rows(summaries: Dict[str, Dict[str, dict]]) -> List[dict]:
    """The claim rows' data, judged on the runs at the scene's step (summaries[scene]["h"]): key,
    claim, source, paper, problem judged on, numbers, ours, verdict (holds | does not hold |
    inconclusive | not measured), the rule and, when not measured, the reason. plots/claims.py can build a Claim from each
    (key, claim, source, paper, ours, verdict, rule; notes = [problem] + numbers)."""
    at_h = {scene: runs["h"] for scene, runs in summaries.items() if "h" in runs}
    rule_price = (f"noticeable price: the authors' chain's max penetration > {_pct(NOTICEABLE)} of the body size L "
                  f"and > {PRICE_FACTOR:g}x the exact chains' max at the same step; none: <= {_pct(NOTICEABLE)} or "
                  f"<= {NO_PRICE_FACTOR:g}x; else inconclusive (docs/simulator.md \"The price of decoupling\")")
    rows = []

    eight = at_h.get("dino_eight")
    if eight:
        p = price(eight)
        verdict = {"noticeable": DOES_NOT_HOLD, "none": HOLDS, NOT_EXERCISED: NOT_MEASURED}.get(p, p)
        rows.append({"key": "sec6-decoupling-no-visual-artifacts", "source": "Sec. 6 (eight dinosaurs)",
                     "claim": "collision decoupling shows no visual artifacts in the eight-dinosaur scene",
                     "paper": "we have not observed any visual artifacts as shown in our video",
                     "problem": f"dino_eight, {eight['frames']} frames at h = {eight['h']} s, decoupled mprgp "
                                f"(authors' order) against {eight.get('exact_solver', '?')} on every row",
                     "numbers": [_numbers(eight)], "ours": _numbers(eight), "verdict": verdict, "rule": rule_price})
    else:
        rows.append({"key": "sec6-decoupling-no-visual-artifacts", "source": "Sec. 6 (eight dinosaurs)",
                     "claim": "collision decoupling shows no visual artifacts in the eight-dinosaur scene",
                     "paper": "we have not observed any visual artifacts as shown in our video",
                     "problem": "dino_eight", "numbers": [], "ours": "—", "verdict": NOT_MEASURED,
                     "rule": rule_price})

    prices = {scene: p for scene, p in ((scene, price(s)) for scene, s in at_h.items()) if p != NOT_EXERCISED}
    if not prices:
        verdict7 = NOT_MEASURED
    elif any(p == "noticeable" for p in prices.values()):
        verdict7 = DOES_NOT_HOLD
    elif all(p == "none" for p in prices.values()):
        verdict7 = HOLDS
    else:
        verdict7 = INCONCLUSIVE
    noticeable = sorted(s for s, p in prices.items() if p == "noticeable")
    rows.append({"key": "sec7-decoupling-no-noticeable-artifacts", "source": "Sec. 7",
                 "claim": "collision decoupling ignores some constraints without noticeable artifacts",
                 "paper": "the collision decoupling ignores some collision constraints without noticeable artifacts",
                 "problem": "every scene run at its own step whose decoupled chain dropped rows: "
                            + ", ".join(sorted(prices)),
                 "numbers": [_numbers(at_h[scene]) for scene in sorted(prices)],
                 "ours": (f"noticeable price on {len(noticeable)} of {len(prices)} scenes"
                          + (f" ({', '.join(noticeable)})" if noticeable else "")),
                 "verdict": verdict7, "rule": rule_price + "; does not hold when any scene has a noticeable price, "
                 "holds when none has; a scene where no row was dropped is not a case of the claim"})

    reduced = failed = 0
    with_price = []
    for scene, s in at_h.items():
        xa, xd = excess(s, "authors"), excess(s, "depth")
        if price(s) == NOT_EXERCISED or not (math.isfinite(xa) and math.isfinite(xd)) or xa <= PRICE_TO_REDUCE:
            continue
        with_price.append(f"{scene}: excess authors {_pct(xa)}, depth {_pct(xd)} of L")
        reduced += xd <= xa / 2
        failed += xd >= xa
    n = len(with_price)
    # no scene with a price to reduce is no case of the claim: not measured (plots/claims.py's vocabulary)
    verdict5 = NOT_MEASURED if n == 0 else HOLDS if reduced > n / 2 else DOES_NOT_HOLD if failed > n / 2 \
        else INCONCLUSIVE
    rows.append({"key": "sec5-depth-sorted-selection", "source": "Sec. 5",
                 "claim": "a depth-sorted selection of the rows to keep reduces the price of decoupling",
                 "paper": "suggested (depth-sorted collision decoupling) as a remedy for tunnelling near thin parts",
                 "problem": f"scenes whose authors'-order excess penetration is > {_pct(PRICE_TO_REDUCE)} of L: {n}",
                 "numbers": with_price,
                 "ours": f"depth halves the excess on {reduced} of {n}, does not reduce it on {failed}",
                 "verdict": verdict5,
                 "reason": (f"no scene's authors'-order excess penetration is > {_pct(PRICE_TO_REDUCE)} of L: no case "
                            "of the claim") if n == 0 else "",
                 "rule": "excess X = max penetration - the exact chains' max; depth reduces the price on a scene when "
                         "X_depth <= X_authors / 2; holds when it does on more than half of the scenes with "
                         f"X_authors > {_pct(PRICE_TO_REDUCE)}, does not hold when X_depth >= X_authors on more "
                         "than half, else inconclusive"})
    return rows


# ----------------------------------------------------------------------------- figures, table

CHAIN_STYLE = {EXACT: ("black", "-"), NOISE: ("grey", ":"), CONTROL: ("tab:purple", ":"), "authors": ("tab:red", "-"),
               "random": ("tab:orange", "--"), "depth": ("tab:blue", "-.")}


def plot_run(df: pd.DataFrame, summary: dict, folder: str, stem: str) -> List[str]:
    """Two panels: penetration against frame per chain (the 1% line of the rule), and the max
    distance to the exact chain against frame (the tol 1e-6 exact chain is the noise floor)."""
    fig, (ax_p, ax_d) = plt.subplots(1, 2, figsize=(11, 4))
    for label, rows in df.groupby("chain", sort=False):
        color, style = CHAIN_STYLE.get(label, (None, "-"))
        ax_p.plot(rows["frame"], 100 * rows["penetration_rel"], style, color=color, label=label)
        if label != EXACT:
            ax_d.plot(rows["frame"], figutil.positive(100 * rows["max_distance_rel"]), style, color=color, label=label)
    ax_p.axhline(100 * NOTICEABLE, color="red", lw=0.8, ls=":", label="noticeable (1% of L)")
    ax_p.set_xlabel("frame")
    ax_p.set_ylabel("penetration at the frame's end (% of L)")
    ax_d.set_yscale("log")
    ax_d.set_xlabel("frame")
    ax_d.set_ylabel("distance to the exact chain (% of L)")
    ax_d.set_title("exact-tol1e-6: the noise floor", fontsize=9)
    fig.suptitle(f"{summary['scene']}: h = {summary['h']} s, L = {summary['body_size']:.3g} m")
    handles, labels = ax_p.get_legend_handles_labels()
    h2, l2 = ax_d.get_legend_handles_labels()
    for h, lab in zip(h2, l2):
        if lab not in labels:
            handles.append(h)
            labels.append(lab)
    fig.legend(handles, labels, loc="lower center", ncol=4, fontsize=8)
    fig.tight_layout(rect=(0, 0.12, 1, 0.95))
    return figutil.save_figure(fig, folder, stem)


def _count(x: float) -> str:
    return "—" if x is None or not math.isfinite(x) else f"{x:.0f}"


def table(summaries: Dict[str, Dict[str, dict]]) -> str:
    """Markdown: per scene and step, max and mean penetration, max distance for every chain."""
    lines = ["| scene | step | frames | chain | max pen. (% L) | mean pen. (% L) | max dist. (% L) | "
             "rows dropped | max vertices inside | price |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for scene in sorted(summaries):
        for step in ("h", "h2"):
            s = summaries[scene].get(step)
            if not s:
                continue
            for label in (EXACT, NOISE) + ORDERS + (CONTROL,):
                c = s["chains"].get(label)
                if not c:
                    continue
                verdict = price(s, label) if label in ORDERS + (CONTROL,) else ("noise floor" if label == NOISE else "reference")
                lines.append(f"| {scene} | {s['h']} s | {c['frames']} | {label} | {100 * c['max_penetration_rel']:.3g} | "
                             f"{100 * c['mean_penetration_rel']:.3g} | {100 * c['max_distance_rel']:.3g} | "
                             f"{100 * c['rows_dropped_fraction']:.0f}% | {_count(c.get('max_vertices_inside'))} | {verdict} |")
    return "\n".join(lines) + "\n"


def compact_table(summaries: Dict[str, Dict[str, dict]]) -> str:
    """Markdown, one row per scene and step: max / mean penetration of every chain, the decoupled
    chains' max distance to the exact one, the noise floor (all % of L), the most vertices inside another
    body at a frame's end (exact / authors), the authors' order's price and the exact solver."""
    def cell(c: Optional[dict], dist: bool) -> str:
        if not c:
            return "—"
        text = f"{100 * c['max_penetration_rel']:.2g} / {100 * c['mean_penetration_rel']:.2g}"
        return text + (f" / {100 * c['max_distance_rel']:.2g}" if dist else "")

    lines = ["| scene | h (s) | frames | rows dropped (authors) | exact pen. max / mean | authors max / mean / dist. | "
             "random | depth | noise floor | vertices inside (exact / authors) | price (authors) | exact solver |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for scene in sorted(summaries):
        for step in ("h", "h2"):
            s = summaries[scene].get(step)
            if not s:
                continue
            ch = s["chains"]
            a = ch.get("authors", {})
            lines.append(f"| {scene} | {s['h']} | {s['frames']} | {100 * a.get('rows_dropped_fraction', math.nan):.0f}% | "
                         f"{cell(ch.get(EXACT), False)} | {cell(a, True)} | {cell(ch.get('random'), True)} | "
                         f"{cell(ch.get('depth'), True)} | {100 * s['noise_floor_rel']:.2g} | "
                         f"{_count(ch.get(EXACT, {}).get('max_vertices_inside'))} / "
                         f"{_count(a.get('max_vertices_inside'))} | {price(s)} | "
                         f"{s.get('exact_solver', '?')} |")
    return "\n".join(lines) + "\n"


def summaries_of(out: str, figures: bool = False) -> Dict[str, Dict[str, dict]]:
    """summaries[scene][h | h2] of every finished chains folder under OUT/chains (reads only;
    with figures, also draws OUT/figures/decoupling_<scene>_<step>.png)."""
    root = os.path.join(out, "chains")
    summaries: Dict[str, Dict[str, dict]] = {}
    for scene in sorted(os.listdir(root)) if os.path.isdir(root) else []:
        for step in STEPS:
            folder = os.path.join(root, scene, step)
            if not os.path.isfile(os.path.join(folder, "chains.json")):
                continue
            df, record = load(folder)
            s = summarize(df, record)
            s["folder"] = folder
            summaries.setdefault(scene, {})[step] = s
            if figures:
                plot_run(df, s, os.path.join(out, "figures"), f"decoupling_{scene}_{step}")
    return summaries


def report(out: str) -> List[dict]:
    """Figures, OUT/decoupling.md and OUT/decoupling_claims.json from every chains folder under out."""
    summaries = summaries_of(out, figures=True)
    claims = claim_rows(summaries)
    text = ["# The price of decoupling\n",
            "Chains of `contactbench chains` (docs/simulator.md \"The price of decoupling\"): penetration "
            "of the frame's end positions and the largest vertex distance to the exact chain, relative to "
            "the body size L. Price: the rule for \"noticeable\" applied to each decoupled chain.\n",
            compact_table(summaries),
            "\nCells: max / mean penetration (and max distance to the exact chain) in % of L; the mean is over "
            "the frames where the exact chain has contact rows.\n\n", table(summaries), "\n## Claims\n"]
    for c in claims:
        text.append(f"- **{c['source']}** {c['claim']}: **{c['verdict']}**. {c['ours']}. Judged on {c['problem']}. "
                    f"Rule: {c['rule']}.")
    renders = [os.path.join(s["folder"], s["render"][key]) for runs in summaries.values() for s in runs.values()
               for key in ("file", "penetration_file") if s["render"].get(key)]
    text.append("\nRenders (exact, exact-tol1e-6, authors, random, depth, left to right, at the frame where the "
                "authors' chain is farthest from the exact one, and where it penetrates deepest): "
                + ", ".join(renders) + "\n")
    page = os.path.join(out, REPORT_STEM + ".md")
    with open(page + ".partial", "w", encoding="utf-8") as f:
        f.write("\n".join(text))
    os.replace(page + ".partial", page)
    tmp = os.path.join(out, "decoupling_claims.json.partial")
    with open(tmp, "w", encoding="utf-8") as f:
        json.dump({"claims": claims, "summaries": summaries}, f, indent=1, default=str)
    os.replace(tmp, os.path.join(out, "decoupling_claims.json"))
    return claims


def main(argv: Optional[List[str]] = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scenes", nargs="*", help="scene files")
    parser.add_argument("--out", help="output folder")
    parser.add_argument("--report", metavar="DIR", help="only the figures, table and claims of DIR")
    parser.add_argument("--frames", type=int, help="frames per run (default: the scene's)")
    parser.add_argument("--no-half-step", action="store_true", help="only the scene's step")
    parser.add_argument("--cb", default=os.environ.get("CB_CONTACTBENCH", "build/bin/contactbench"))
    parser.add_argument("--data", help="the authors' data folder (default: as contactbench chooses)")
    parser.add_argument("--force", action="store_true", help="run again even when cached")
    parser.add_argument("--control", action="store_true",
                        help="add the authors-exact chain (the exact solver on the authors' kept rows)")
    args = parser.parse_args(argv)
    if args.report:
        for c in report(args.report):
            print(f"{c['key']}: {c['verdict']} ({c['ours']})")
        return 0
    if not args.out or not args.scenes:
        parser.error("SCENE.json ... and --out DIR are needed (or --report DIR)")
    ok = True
    for scene in args.scenes:
        if not os.path.isfile(scene):
            print(f"decoupling: {scene}: no such scene file", file=sys.stderr)
            return 2
        name = os.path.splitext(os.path.basename(scene))[0]
        with open(scene, encoding="utf-8") as f:
            frames = args.frames if args.frames is not None else int(json.load(f).get("frames", 100))
        full = os.path.join(args.out, "chains", name, "h")
        done, what = run_chains(args.cb, scene, full, frames, None, args.data, args.force, args.control)
        print(f"chains {name} h: {what}", file=sys.stderr)
        ok = ok and done
        if done and not args.no_half_step:
            record = read_json(os.path.join(full, "chains.json"))
            half = record["h"] / 2
            done, what = run_chains(args.cb, scene, os.path.join(args.out, "chains", name, "h2"), frames, half,
                                    args.data, args.force, args.control)
            print(f"chains {name} h/2: {what}", file=sys.stderr)
            ok = ok and done
    for c in report(args.out):
        print(f"{c['key']}: {c['verdict']} ({c['ours']})")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
