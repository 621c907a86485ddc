#!/usr/bin/python3
"""Why a ladder's cached simulation folder may not be reused (tools/ladder.sh): prints nothing when
DIR/simulation.json says it is SCENE's whole two-frame mprgp run by simulator VERSION and DIR/resume.state
says it was simulated from the scene file's present content; else one line of reasons. A planted or stale
folder once gave the ladder another scene's snapshots. The scene is compared by content, not by file
time: a fresh clone's files are all newer than a simulation made before it.

usage: ladder_reuse.py SIMULATION_JSON SCENE_FILE VERSION"""
import json
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "plots"))
from qpsnap import content_hash  # noqa: E402  (the FNV-1a 64 that `simulate` records for the scene file)

RESUME_MAGIC = b"cb-resume 1\n"  # sim/resume_state.cpp


def simulated_scene_hash(resume_state: str) -> str:
    """The scene file's hash recorded by `simulate` in its resume state; raises OSError/ValueError."""
    with open(resume_state, "rb") as f:
        if f.read(len(RESUME_MAGIC)) != RESUME_MAGIC:
            raise ValueError("not a resume state of this version")
        head = json.loads(f.readline())
    return head["identity"]["scene_file"]


def stale_reason(simulation_json: str, scene_file: str, version: int) -> str:
    try:
        with open(simulation_json, encoding="utf-8") as f:
            rec = json.load(f)
        with open(scene_file, encoding="utf-8") as f:
            name = json.load(f)["name"]
    except (OSError, ValueError, KeyError, TypeError) as err:
        return f"unreadable ({err})"
    if not isinstance(rec, dict):
        return "unreadable (not a JSON object)"
    why = []
    if rec.get("scene") != name:
        why.append(f"scene {rec.get('scene')!r}, not {name!r}")
    if rec.get("simulator_version") != version:
        why.append(f"simulator version {rec.get('simulator_version')!r}, not {version}")
    if rec.get("frames_done") != 2 or rec.get("blow_up") is not False or rec.get("solver") != "mprgp":
        why.append("not a whole two-frame mprgp run")
    resume_state = os.path.join(os.path.dirname(simulation_json), "resume.state")
    try:
        if simulated_scene_hash(resume_state) != content_hash(scene_file):
            why.append("the scene file changed since")
    except (OSError, ValueError, KeyError, TypeError, AttributeError) as err:
        why.append(f"no readable resume.state to compare the scene with ({err})")
    return "; ".join(why)


if __name__ == "__main__":
    if len(sys.argv) != 4:
        sys.exit(__doc__.splitlines()[-1])
    print(stale_reason(sys.argv[1], sys.argv[2], int(sys.argv[3])))
