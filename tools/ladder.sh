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
for s in "${scenes[@]}"; do
    dir="$out/sim/$s"
    if [ -f "$dir/simulation.json" ]; then
        echo "ladder: $s: simulated already ($dir)"
        continue
    fi
    # The stepping solver only moves frame 0 (no contact yet); frame 1's snapshot is the QP.
    start=$SECONDS
    "$cb" simulate "scenes/ladder/$s.json" --frames 2 --out "$dir" --solver mprgp
    echo "ladder: $s: simulated in $((SECONDS - start)) s (time and peak memory of each stage per step in $dir/steps.csv)"
done
"$cb" run "suites/ladder_$ladder.json" --out "$out/$ladder"
/usr/bin/python3 -m plots.which_solver "$out/$ladder" --axis "$axis"
# the page again, now with the which-solver map among its figures
/usr/bin/python3 -m plots.html_report "$out/$ladder"
