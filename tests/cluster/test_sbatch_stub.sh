#!/bin/bash
# Issue 27: the sbatch files of `contactbench cluster slurm` run nothing but what they mean to.
# The binary and the suite live in a folder whose name holds shell syntax ($(...), backticks, ';',
# quotes); the generated array.sbatch and merge.sbatch are run with bash, with a stub `srun` and
# `sbatch` first on PATH and the copied binary replaced by a stub, and bash's trace proves that
# the only commands run are set, export, srun and the binary, each with its arguments intact. A
# suite path, --out or --sbatch-option holding a line break, and --shards 1000000000, end in
# exit 2 with the field named and nothing written.
# Exit 0 pass, 1 fail. Environment: CB_CONTACTBENCH (the binary).
set -uo pipefail

fail() { echo "FAIL: $*"; exit 1; }

CB=${CB_CONTACTBENCH:-}
[ -n "$CB" ] && [ -x "$CB" ] || fail "CB_CONTACTBENCH is not an executable: '$CB'"
CB=$(readlink -f "$CB")

S=$(mktemp -d /tmp/cb_sbatch_stub.XXXXXX)
trap 'rm -rf "$S"' EXIT
export CB_CACHE="$S/cache"
# A folder name an attacker would choose: each piece would run a command if it reached a shell unquoted.
D="$S/we ird \$(touch PWNED-1);\`touch PWNED-2\`'q'"
mkdir -p "$D" "$S/bin" || fail "cannot create $D"
cp "$CB" "$D/contactbench" || fail "cannot copy the binary"
SUITE="$D/suite \$(touch PWNED-3).json"
cat >"$SUITE" <<'EOF'
{"name": "stub-4",
 "generate": [{"id": "plane-a", "family": "plane", "seed": 1, "params": {"nx": 1, "ny": 1, "nz": 1}}],
 "solvers": ["pgs"], "tol": 1e-6, "time_limit_s": 5}
EOF
OUT="$S/out"

# Refused before anything is written: line breaks in a path or option, an absurd shard count.
expect_refused() {  # WHAT EXPECTED_STDERR_PART ARGS...
    local what=$1 expected=$2
    shift 2
    local rc=0
    (cd "$S" && "$D/contactbench" cluster slurm "$@") >"$S/stdout" 2>"$S/stderr" || rc=$?
    [ "$rc" = 2 ] || fail "$what: exit $rc, expected 2 ($(cat "$S/stderr"))"
    grep -qF -- "$expected" "$S/stderr" || fail "$what: stderr '$(cat "$S/stderr")' lacks '$expected'"
    [ ! -e "$OUT" ] || fail "$what: $OUT was created"
}
NL_SUITE="$S/nl
touch PWNED-5
.json"
cp "$SUITE" "$NL_SUITE"
expect_refused "newline in the suite path" "cluster: suite: holds the control character 0x0a" "$NL_SUITE" --out "$OUT" --shards 2
expect_refused "newline in --out" "cluster: --out: holds the control character 0x0a" "$SUITE" --out "$OUT
x" --shards 2
expect_refused "carriage return in --sbatch-option" "cluster: --sbatch-option: holds the control character 0x0d" \
    "$SUITE" --out "$OUT" --shards 2 "--sbatch-option=--comment=a$(printf '\r')b"
expect_refused "--shards 1000000000" "cluster: --shards: must be in 1..10000, got 1000000000" \
    "$SUITE" --out "$OUT" --shards 1000000000

# Written: the hostile but printable names are quoted.
(cd "$S" && "$D/contactbench" cluster slurm "$SUITE" --out "$OUT" --shards 2 --sbatch-option=--comment='$(touch x)') \
    >"$S/submit.sh" 2>"$S/cluster.log" || fail "cluster slurm: $(cat "$S/cluster.log")"
[ -f "$OUT/slurm/array.sbatch" ] && [ -f "$OUT/slurm/merge.sbatch" ] || fail "no sbatch files in $OUT/slurm"

# Stubs: each records its arguments, one per line, after a header line with its name.
for tool in srun sbatch; do
    cat >"$S/bin/$tool" <<EOF
#!/bin/bash
{ echo "== $tool"; printf '%s\n' "\$@"; } >>"$S/calls"
EOF
    chmod +x "$S/bin/$tool"
done
cat >"$D/contactbench" <<EOF
#!/bin/bash
{ echo "== contactbench"; printf '%s\n' "\$@"; } >>"$S/calls"
EOF
chmod +x "$D/contactbench"

for script in array merge; do
    # xtrace to its own file: every simple command bash runs, after expansion.
    (cd "$S" && exec 9>"$S/$script.trace" && BASH_XTRACEFD=9 PS4='+ ' PATH="$S/bin:$PATH" \
        SLURM_ARRAY_TASK_ID=0 bash -x "$OUT/slurm/$script.sbatch") >"$S/$script.log" 2>&1 ||
        fail "bash $script.sbatch failed: $(cat "$S/$script.log")"
    while IFS= read -r line; do
        case "$line" in
        "+ set -euo pipefail" | "+ export OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1") ;;
        "+ OPENBLAS_NUM_THREADS=1" | "+ OMP_NUM_THREADS=1") ;;  # bash traces the assignments of export
        "+ srun "* | "+ '$S/we ird "*"/contactbench' merge "*) ;;
        *) fail "$script.sbatch ran an unexpected command: $line" ;;
        esac
    done <"$S/$script.trace"
done
for n in 1 2 3 4 5; do
    [ ! -e "$S/PWNED-$n" ] || fail "PWNED-$n exists: a name reached a shell unquoted"
done
found=$(find "$S" \( -name 'PWNED*' -o -name x \) -print)
[ -z "$found" ] || fail "a marker file was created: $found"

expected="== srun
--ntasks=1
--cpus-per-task=1
--cpu-bind=cores
$D/contactbench
run
$SUITE
--out
$OUT
== contactbench
merge
$OUT
$OUT/shard-1-of-2
$OUT/shard-2-of-2"
[ "$(cat "$S/calls")" = "$expected" ] || fail "the stubs saw
$(cat "$S/calls")
expected
$expected"
grep -q '^#SBATCH --job-name=cb-stub-4$' "$OUT/slurm/array.sbatch" ||
    fail "job name not reduced to safe characters: $(grep job-name "$OUT/slurm/array.sbatch")"
echo "PASSED: generated sbatch files ran only srun and the binary, arguments intact; 4 hostile values refused"
exit 0
