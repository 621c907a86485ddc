#!/usr/bin/python3
"""A simulation's picture strip with its frame numbers, times and a caption (issue 46).

`contactbench simulate` writes DIR/<scene>_strip.png, tiles of the frames spread evenly over the
run (the last included; the scene's output.strip_frames of them, default 6). This draws it again
with "frame k, t = ... s" under each tile and a caption stating the largest penetration shown (the
largest max_penetration_rel of frames.csv over the pictured frames, in % of the body size, with its
frame) and the stepping solver, so that a body sunk into another is said, not left to the eye.

usage: strip.py SIMDIR [--out FILE]   (default SIMDIR/<scene>_strip_annotated.png)
"""
from __future__ import annotations

import argparse
import json
import math
import os
import sys
from typing import List, Optional

import pandas as pd

from plots import figutil
from plots.figutil import plt


def strip_frames(frames: int, count: int) -> List[int]:
    """The pictured frames: sim/simulator.cpp's rule (evenly spread, rounded, the last included)."""
    out: List[int] = []
    for i in range(count if frames > 0 else 0):
        f = frames - 1 if count == 1 else int(math.floor(i * (frames - 1) / (count - 1) + 0.5))
        if not out or out[-1] != f:
            out.append(f)
    return out


def largest_penetration(frames: pd.DataFrame, shown: List[Optional[int]]) -> tuple:
    """(max_penetration_rel, frame) of the deepest pictured frame; (nan, None) without one."""
    rows = frames[frames["frame"].isin([f for f in shown if f is not None])] if "frame" in frames else frames.iloc[0:0]
    pen = pd.to_numeric(rows.get("max_penetration_rel", pd.Series(dtype=float)), errors="coerce")
    if rows.empty or not pen.notna().any():
        return float("nan"), None
    k = pen.idxmax()
    return float(pen[k]), int(rows.loc[k, "frame"])


def _strip_count(sim: dict, folder: str) -> int:
    """output.strip_frames of the scene the simulation ran (6 when it is not found)."""
    for path in (sim.get("scene_file") or "", os.path.join(folder, os.path.basename(sim.get("scene_file") or ""))):
        if path and os.path.isfile(path):
            try:
                with open(path, encoding="utf-8") as f:
                    return int(((json.load(f).get("output") or {}).get("strip_frames", 6)))
            except (OSError, ValueError, TypeError):
                break
    return 6


def annotate(folder: str, out: Optional[str] = None) -> Optional[str]:
    """Writes the annotated strip; returns its path, or None when the folder has no strip."""
    sim_path = os.path.join(folder, "simulation.json")
    if not os.path.isfile(sim_path):
        return None
    with open(sim_path, encoding="utf-8") as f:
        sim = json.load(f)
    png = os.path.join(folder, f"{sim.get('scene', '')}_strip.png")
    csv = os.path.join(folder, "frames.csv")
    if not os.path.isfile(png) or not os.path.isfile(csv):
        return None
    image = plt.imread(png)
    frames = pd.read_csv(csv)
    shown = strip_frames(int(sim.get("frames_done", sim.get("frames", 0))), _strip_count(sim, folder))
    tiles = max(1, image.shape[1] // max(1, image.shape[0]))
    shown = shown[:tiles] if len(shown) >= tiles else shown + [None] * (tiles - len(shown))
    width = min(7.0, 1.4 * tiles)
    fig, axes = plt.subplots(1, tiles, figsize=(width, width / tiles + 0.75), squeeze=False)
    size = image.shape[0]
    for k, ax in enumerate(axes.flat):
        ax.imshow(image[:, k * size:(k + 1) * size])
        ax.set_xticks([])
        ax.set_yticks([])
        frame = shown[k]
        row = frames[frames["frame"] == frame] if frame is not None and "frame" in frames else frames.iloc[0:0]
        if row.empty:
            ax.set_xlabel("frame ?", fontsize=7)
            continue
        ax.set_xlabel(f"frame {frame}\nt = {float(row.iloc[0]['time_s']):.2f} s", fontsize=7)
    worst = largest_penetration(frames, shown)
    solver = sim.get("solver", "?") + (f", decouple {sim['decouple']}" if sim.get("decouple") not in (None, "", "none")
                                       else "")
    caption = (f"{sim.get('scene', '')} ({solver}): largest penetration shown {100 * worst[0]:.1f}% of the body size "
               f"(frame {worst[1]})" if worst[1] is not None else f"{sim.get('scene', '')} ({solver})")
    fig.suptitle(caption, fontsize=7)
    fig.tight_layout()
    out = out or os.path.join(folder, f"{sim.get('scene', 'strip')}_strip_annotated.png")
    fig.savefig(out, dpi=figutil.DPI, bbox_inches="tight")
    plt.close(fig)
    return out


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("folder", help="a simulation folder (contactbench simulate --out DIR)")
    parser.add_argument("--out", help="the annotated PNG (default SIMDIR/<scene>_strip_annotated.png)")
    args = parser.parse_args(argv)
    try:
        path = annotate(args.folder, args.out)
    except (OSError, ValueError, KeyError) as err:
        print(f"strip.py: {args.folder}: {err}", file=sys.stderr)
        return 2
    if path is None:
        print(f"strip.py: {args.folder}: no simulation.json, <scene>_strip.png and frames.csv", file=sys.stderr)
        return 2
    print(path)
    return 0


if __name__ == "__main__":
    sys.exit(main())
