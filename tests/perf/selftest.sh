#!/usr/bin/env bash
# End to end through `make perf-gate` with a real worktree build of BASE (make perf-gate-selftest):
#  1. a scratch clone of this repository's HEAD gets a planted regression committed on top (one more
#     counted A-product per CG step of mprgp); `make perf-gate BASE=<the unplanted commit>` must
#     build BASE in a worktree under the cache and fail with the gate's exit status 3, naming
#     a_products, a_products_harness and instructions;
#  2. the clone goes back to the unplanted commit and the gate, made to use the worktree-built BASE
#     (--no-reuse: two separate builds of the same code), must pass, twice in a row.
# Only the mprgp runs of the CI suite are measured (PERF_GATE_ARGS) to keep it short; the logs are
# kept in results/perf-gate-selftest/. Slow: two full builds of contactbench.
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
LOGS="$ROOT/results/perf-gate-selftest"
# Scratch space inside the checkout's git-ignored .cache/ by default: with ccache's base_dir set
# above the checkout, the clone's builds then hit the cache.
SCRATCH=${TMPDIR:-$ROOT/.cache}
mkdir -p "$SCRATCH"
WORK=$(mktemp -d "$SCRATCH/cb-perf-gate-selftest.XXXXXX")
trap 'rm -rf "$WORK"' EXIT
mkdir -p "$LOGS"
GATE_ARGS="--filter /mprgp\$\$"
started=$(date +%s)

git clone --quiet "$ROOT" "$WORK/clone"
cd "$WORK/clone"
base=$(git rev-parse HEAD)
/usr/bin/python3 - solvers/mprgp/mprgp_decoupled_steps.cpp <<'PY'
import re, sys
path = sys.argv[1]
text = open(path).read()
anchor = re.search(r"double (DecoupledMprgp::)?product_dot\([^)]*\)\s*\{", text)
if not anchor:
    sys.exit("selftest: no product_dot(...) { in " + path)
plant = "\n        { Vec extra; a_product(m_A, v, extra); ++m_cnt.a_products; }  // planted regression"
open(path, "w").write(text[:anchor.end()] + plant + text[anchor.end():])
PY
git -c user.name=selftest -c user.email=selftest@localhost commit --quiet -am "planted: one more counted A-product per CG step of mprgp"

gate() {  # gate LOG [extra make arguments]: runs make perf-gate, returns make's status
    local log=$1; shift
    local t0; t0=$(date +%s)
    set +e
    make --no-print-directory perf-gate BASE="$base" CB_CACHE="$WORK/cache" "$@" >"$LOGS/$log" 2>&1
    local status=$?
    set -e
    echo "selftest: $log: make exit $status in $(( $(date +%s) - t0 )) s"
    return $status
}
fail() { echo "selftest: FAIL: $*"; exit 1; }

status=0; gate planted.log PERF_GATE_ARGS="$GATE_ARGS" || status=$?
grep -q "perf-gate: BASE ${base:0:12} .*, built in" "$LOGS/planted.log" || fail "BASE was not built in a worktree (planted.log)"
grep -q "\[Makefile:[0-9]*: perf-gate\] Error 3" "$LOGS/planted.log" || fail "the gate did not exit 3 (planted.log)"
grep -q "FAIL regressed: a_products a_products_harness instructions" "$LOGS/planted.log" \
    || fail "the planted product was not named (planted.log)"
echo "selftest: planted regression caught (exit 3):"
grep -E "^(snapshot|[a-z-]+ +mprgp ).*" "$LOGS/planted.log" || true

git checkout --quiet --detach "$base"
for round in 1 2; do
    gate "unchanged-$round.log" PERF_GATE_ARGS="$GATE_ARGS --no-reuse" || fail "unchanged code failed (unchanged-$round.log)"
    grep -q "verdict: PASS" "$LOGS/unchanged-$round.log" || fail "no PASS verdict (unchanged-$round.log)"
    grep -q ", cached in" "$LOGS/unchanged-$round.log" || fail "BASE not taken from the cache (unchanged-$round.log)"
done
echo "selftest: unchanged code passed twice against the worktree-built BASE"
echo "selftest: PASS in $(( $(date +%s) - started )) s (logs in $LOGS)"
