#!/bin/bash
# The build without external peers (-DCB_PEERS=OFF, as on a machine without their packages):
# configures SOURCE into a scratch folder with the same build type and compiler launcher as the
# main build, builds contactbench only (no tests, no benchmarks) and checks what it says about
# peers: `solvers` lists none, `--version` says none are built, and FCLIB conversion reports that it
# is not built (exit 2). Peer flags sit on the peers' own sources, so with ccache every other
# object is a cache hit of the main build and this takes well under a minute.
# Usage: test_no_peers.sh SOURCE_DIR SCRATCH_DIR BUILD_TYPE [LAUNCHER]. Exit 0 pass, 1 fail.
set -uo pipefail
SOURCE=$1 SCRATCH=$2 TYPE=$3 LAUNCHER=${4:-}
fail() { echo "FAIL: $*"; exit 1; }

rm -rf "$SCRATCH"
args=(-S "$SOURCE" -B "$SCRATCH" -DCMAKE_BUILD_TYPE="$TYPE" -DCB_PEERS=OFF -DCB_BUILD_TESTS=OFF -DCB_BUILD_BENCH=OFF)
[ -n "$LAUNCHER" ] && args+=(-DCMAKE_CXX_COMPILER_LAUNCHER="$LAUNCHER")
cmake "${args[@]}" >"$SCRATCH.configure.log" 2>&1 || { cat "$SCRATCH.configure.log"; fail "configure with -DCB_PEERS=OFF"; }
grep -q -- "-- peer " "$SCRATCH.configure.log" && fail "a peer was configured with CB_PEERS=OFF"
cmake --build "$SCRATCH" --parallel 2 --target contactbench >"$SCRATCH.build.log" 2>&1 ||
    { tail -50 "$SCRATCH.build.log"; fail "build of contactbench with -DCB_PEERS=OFF"; }
CB="$SCRATCH/bin/contactbench"

listed=$("$CB" solvers) || fail "contactbench solvers"
echo "$listed" | grep -q "^mprgp " || fail "mprgp is not listed: $listed"
echo "$listed" | grep -q "peer:" && fail "a peer is listed without peers: $listed"
"$CB" --version | grep -qx "peers         none built (docs/peers.md)" || fail "--version does not say that no peer is built"

"$CB" generate plane --out "$SCRATCH/p.qpsnap" --param nx=2 --param ny=2 --param nz=2 >/dev/null || fail "generate"
"$CB" convert "$SCRATCH/p.qpsnap" "$SCRATCH/p.hdf5" >"$SCRATCH/convert.out" 2>&1
status=$?
[ $status = 2 ] || fail "convert to .hdf5 exited $status, expected 2"
grep -q "FCLIB export is not built" "$SCRATCH/convert.out" || fail "convert did not say FCLIB is not built: $(cat "$SCRATCH/convert.out")"
[ -e "$SCRATCH/p.hdf5" ] && fail "convert left a partial p.hdf5"
rm -rf "$SCRATCH" "$SCRATCH.configure.log" "$SCRATCH.build.log"
echo "PASS: the CB_PEERS=OFF build compiles and has no peers"
