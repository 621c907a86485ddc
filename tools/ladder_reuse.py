#!/usr/bin/python3
"""Why a ladder's cached simulation folder may not be reused (tools/ladder.sh): prints nothing when
DIR/simulation.json says it is SCENE's whole two-frame mprgp run by simulator VERSION and the scene
file has not changed since; else one line of reasons. A planted or stale folder once gave the
ladder another scene's snapshots.

usage: ladder_reuse.py SIMULATION_JSON SCENE_FILE VERSION"""
import json
import os
import sys


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
    if os.path.getmtime(scene_file) > os.path.getmtime(simulation_json):
        why.append("the scene file changed since")
    return "; ".join(why)


if __name__ == "__main__":
    if len(sys.argv) != 4:
        sys.exit(__doc__.splitlines()[-1])
    print(stale_reason(sys.argv[1], sys.argv[2], int(sys.argv[3])))
