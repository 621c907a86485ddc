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
# this simulator version, and its resume.state names the scene file's present content; anything else
# is simulated again, with --fresh (a planted or stale folder once gave the ladder another scene's snapshots).
simver=$("$cb" --version --json | /usr/bin/python3 -c 'import json, sys; print(json.load(sys.stdin)["simulator_version"])')
for s in "${scenes[@]}"; do
    dir="$out/sim/$s"
    fresh=()
    if [ -f "$dir/simulation.json" ]; then
        why=$(/usr/bin/python3 tools/ladder_reuse.py "$dir/simulation.json" "scenes/ladder/$s.json" "$simver")
        if [ -z "$why" ]; then
            echo "ladder: $s: simulated already ($dir)"
            continue
        fi
        echo "ladder: $s: $dir is stale ($why): simulating again"
        fresh=(--fresh)
    fi
    # The stepping solver only moves frame 0 (no contact yet); frame 1's snapshot is the QP.
    start=$SECONDS
    "$cb" simulate "scenes/ladder/$s.json" --frames 2 --out "$dir" --solver mprgp "${fresh[@]}"
    echo "ladder: $s: simulated in $((SECONDS - start)) s (time and peak memory of each stage per step in $dir/steps.csv)"
done
"$cb" run "suites/ladder_$ladder.json" --out "$out/$ladder"
/usr/bin/python3 -m plots.which_solver "$out/$ladder" --axis "$axis"
# the page again, now with the which-solver map among its figures
/usr/bin/python3 -m plots.html_report "$out/$ladder"
