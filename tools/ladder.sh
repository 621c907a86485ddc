#!/usr/bin/env bash
# One ladder of "which solver when" (issue 29): simulate each scene of the ladder (two frames; the
# contact frame is frame 1; cached: a folder with simulation.json is kept), run the ladder's suite
# on those snapshots, and write the figure and table.
# usage: tools/ladder.sh resolution|density CONTACTBENCH [OUT]    (`make ladder LADDER=...`)
# OUT defaults to results/ladder; the suites read their snapshots from results/ladder/sim.
set -euo pipefail
ladder=$1 cb=$2 out=${3:-results/ladder}
cd "$(dirname "$0")/.."
case "$ladder" in
resolution) scenes=(press_8k press_30k press_120k press_500k press_1m) axis=n ;;
density) scenes=(density_10 density_100 density_1000 density_10000) axis=m ;;
*) echo "ladder: unknown ladder '$ladder' (resolution or density)" >&2; exit 2 ;;
esac
if [ "$out" != results/ladder ]; then
    echo "ladder: the suites read snapshots from results/ladder/sim; OUT must be results/ladder" >&2
    exit 2
fi
# A folder is reused only when its simulation.json says it is this scene's whole two-frame run by
# this simulator version, and the scene file has not changed since; anything else is simulated
# again (a planted or stale folder once gave the ladder another scene's snapshots).
simver=$("$cb" --version --json | /usr/bin/python3 -c 'import json, sys; print(json.load(sys.stdin)["simulator_version"])')
stale_reason() {  # stale_reason SIMULATION_JSON SCENE_FILE: prints why the folder is not reusable
    /usr/bin/python3 - "$1" "$2" "$simver" <<'PY'
import json, os, sys
path, scene_file, version = sys.argv[1], sys.argv[2], int(sys.argv[3])
try:
    rec = json.load(open(path, encoding="utf-8"))
    name = json.load(open(scene_file, encoding="utf-8"))["name"]
except (OSError, ValueError, KeyError) as err:
    print(f"unreadable ({err})")
    sys.exit()
why = []
if rec.get("scene") != name:
    why.append(f"scene {rec.get('scene')!r}, not {name!r}")
if rec.get("simulator_version") != version:
    why.append(f"simulator version {rec.get('simulator_version')!r}, not {version}")
if rec.get("frames_done") != 2 or rec.get("blow_up") is not False or rec.get("solver") != "mprgp":
    why.append("not a whole two-frame mprgp run")
if os.path.getmtime(scene_file) > os.path.getmtime(path):
    why.append("the scene file changed since")
print("; ".join(why))
PY
}
for s in "${scenes[@]}"; do
    dir="$out/sim/$s"
    if [ -f "$dir/simulation.json" ]; then
        why=$(stale_reason "$dir/simulation.json" "scenes/ladder/$s.json")
        if [ -z "$why" ]; then
            echo "ladder: $s: simulated already ($dir)"
            continue
        fi
        echo "ladder: $s: $dir is stale ($why): simulating again"
    fi
    # The stepping solver only moves frame 0 (no contact yet); frame 1's snapshot is the QP.
    start=$SECONDS
    "$cb" simulate "scenes/ladder/$s.json" --frames 2 --out "$dir" --solver mprgp
    echo "ladder: $s: simulated in $((SECONDS - start)) s (time and peak memory of each stage per step in $dir/steps.csv)"
done
"$cb" run "suites/ladder_$ladder.json" --out "$out/$ladder"
/usr/bin/python3 -m plots.which_solver "$out/$ladder" --axis "$axis"
