#!/bin/bash
# A real one-node Slurm on this machine: munged with a generated key, slurmctld and slurmd on
# localhost with a generated slurm.conf, state and spool in a scratch folder. Submits the files
# `contactbench cluster slurm` writes (a 4-task array, then a merge that depends on it) with the
# sbatch commands it prints, once with the array 0-3 and once with 5-8, and checks that the merged
# summary.csv equals a single-machine run's (time columns aside) and that `compare` finds the
# counters equal. Every daemon started here is stopped by its pid on exit.
#
# Needs root (the daemons) and Debian's slurm-wlm and munge (installed here when missing).
# Exit 0 pass, 77 skipped (ctest SKIP_RETURN_CODE), 1 fail.
# Environment: CB_CONTACTBENCH (the binary), CB_SLURM_SUITE (a suite to run instead of the small
# one written here, e.g. suites/ci.json for timings), CB_SLURM_KEEP=1 keeps the scratch folder.
set -uo pipefail

skip() { echo "SKIPPED: $*"; exit 77; }
fail() { echo "FAIL: $*"; dump_logs; exit 1; }
log() { echo "[slurm-test $(date -u +%H:%M:%S)] $*"; }

CB=${CB_CONTACTBENCH:-}
[ -n "$CB" ] && [ -x "$CB" ] || { echo "FAIL: CB_CONTACTBENCH is not an executable: '$CB'"; exit 1; }
CB=$(readlink -f "$CB")

[ "$(id -u)" = 0 ] || skip "not root: a test Slurm needs root to start munged, slurmctld and slurmd"

# Packages: slurm-wlm (slurmctld, slurmd, sbatch) and munge, installed when missing.
if ! command -v slurmctld >/dev/null || ! command -v slurmd >/dev/null || ! command -v sbatch >/dev/null ||
   ! command -v munged >/dev/null; then
    log "installing slurm-wlm and munge with apt-get"
    export DEBIAN_FRONTEND=noninteractive
    if ! timeout 300 apt-get install -y -qq slurm-wlm munge >/dev/null 2>&1; then
        timeout 120 apt-get update -qq >/dev/null 2>&1
        timeout 300 apt-get install -y -qq slurm-wlm munge >/dev/null 2>&1 ||
            skip "apt-get could not install slurm-wlm and munge (no network or no Debian mirror?)"
    fi
fi
for tool in slurmctld slurmd sbatch squeue sinfo scontrol munged mungekey; do
    command -v "$tool" >/dev/null || skip "$tool not found after installing slurm-wlm and munge"
done

S=$(mktemp -d /tmp/cb_slurm.XXXXXX)
chmod 755 "$S"
PIDS=()
dump_logs() {
    for f in "$S"/log/*.log "$S"/*/slurm/*.out; do
        [ -f "$f" ] || continue
        echo "---- $f (last 20 lines)"
        tail -n 20 "$f"
    done
}
JOBS=()
cleanup() {
    local pid
    # Jobs still queued or running (a failure mid-way) are cancelled while slurmctld is up.
    if [ "${#JOBS[@]}" -gt 0 ] && [ -n "$(timeout 5 squeue -h -o %i 2>/dev/null)" ]; then
        timeout 5 scancel "${JOBS[@]}" 2>/dev/null
        for _ in $(seq 25); do [ -z "$(timeout 5 squeue -h -o %i 2>/dev/null)" ] && break; sleep 0.2; done
    fi
    for pid in "${PIDS[@]}"; do
        kill -TERM "$pid" 2>/dev/null
    done
    for pid in "${PIDS[@]}"; do
        # Bounded: a daemon that ignores TERM for 10 s gets KILL.
        for _ in $(seq 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.2; done
        kill -0 "$pid" 2>/dev/null && kill -KILL "$pid" 2>/dev/null
    done
    if [ "${CB_SLURM_KEEP:-0}" = 1 ]; then echo "kept $S"; else rm -rf "$S"; fi
}
trap cleanup EXIT
trap 'exit 1' INT TERM

mkdir -p "$S"/{log,state,spool,run,munge,cache}
export CB_CACHE="$S/cache" OPENBLAS_NUM_THREADS=1

# munge: a fresh key, its own socket, pid and seed files; the daemon in the foreground so its pid is ours.
mungekey --create --keyfile="$S/munge/munge.key" --force >/dev/null 2>&1 ||
    dd if=/dev/urandom of="$S/munge/munge.key" bs=1024 count=1 status=none
chmod 600 "$S/munge/munge.key"
munged --foreground --force --key-file="$S/munge/munge.key" --socket="$S/munge/munge.socket" \
    --pid-file="$S/munge/munged.pid" --seed-file="$S/munge/munged.seed" --log-file="$S/log/munged.log" \
    >"$S/log/munged.stdout.log" 2>&1 &
PIDS+=($!)
for _ in $(seq 50); do [ -S "$S/munge/munge.socket" ] && break; sleep 0.2; done
[ -S "$S/munge/munge.socket" ] || fail "munged did not create its socket within 10 s"

# slurm.conf for this host alone, with the CPUs and memory slurmd detects; ports chosen per run.
HOST=$(hostname -s)
NODE=$(slurmd -C 2>/dev/null | head -n 1 | sed 's/^NodeName=[^ ]* //')
[ -n "$NODE" ] || NODE="CPUs=$(nproc)"
PORT=$((20000 + ($$ % 20000)))
cat >"$S/slurm.conf" <<EOF
ClusterName=cbtest
SlurmctldHost=$HOST(127.0.0.1)
SlurmctldPort=$PORT
SlurmdPort=$((PORT + 1))
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$S/munge/munge.socket
StateSaveLocation=$S/state
SlurmdSpoolDir=$S/spool
SlurmctldPidFile=$S/run/slurmctld.pid
SlurmdPidFile=$S/run/slurmd.pid
SlurmctldLogFile=$S/log/slurmctld.log
SlurmdLogFile=$S/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
SchedulerType=sched/backfill
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
MpiDefault=none
ReturnToService=2
SlurmdParameters=config_overrides
SlurmctldTimeout=30
SlurmdTimeout=30
NodeName=$HOST NodeAddr=127.0.0.1 $NODE State=UNKNOWN
PartitionName=cbtest Nodes=$HOST Default=YES MaxTime=INFINITE State=UP
EOF
export SLURM_CONF="$S/slurm.conf"

slurmctld -D -i -f "$SLURM_CONF" >"$S/log/slurmctld.stdout.log" 2>&1 &
PIDS+=($!)
slurmd -D -f "$SLURM_CONF" >"$S/log/slurmd.stdout.log" 2>&1 &
PIDS+=($!)
state=""
for _ in $(seq 60); do
    state=$(timeout 5 sinfo -h -n "$HOST" -o %t 2>/dev/null | head -n 1)
    [ "$state" = idle ] && break
    sleep 0.5
done
[ "$state" = idle ] || fail "the node did not become idle within 30 s (state '$state')"
log "Slurm up: $(timeout 5 sinfo -h -o '%P %D %t %c CPUs' | head -n 1), daemons ${PIDS[*]}"

# The suite: a small one of 3 snapshots x 3 solvers (9 jobs: 4 shards of 3, 2, 2, 2), or CB_SLURM_SUITE.
if [ -n "${CB_SLURM_SUITE:-}" ]; then
    SUITE=$(readlink -f "$CB_SLURM_SUITE")
else
    SUITE="$S/small.json"
    cat >"$SUITE" <<'EOF'
{"name": "slurm-small",
 "generate": [
  {"id": "plane-a", "family": "plane", "seed": 1, "params": {"nx": 3, "ny": 2, "nz": 3}},
  {"id": "plane-b", "family": "plane", "seed": 2, "params": {"nx": 3, "ny": 3, "nz": 3}},
  {"id": "box-a", "family": "box", "seed": 3, "params": {"nx": 3, "ny": 3, "nz": 3}}],
 "solvers": ["mprgp", "pgs", "active-set"],
 "tol": 1e-6, "time_limit_s": 30}
EOF
fi

# Time and memory columns differ between any two runs; everything else must be equal.
strip_times() {
    awk -F, 'NR == 1 { for (i = 1; i <= NF; ++i) if ($i != "setup_s" && $i != "solve_s" && $i != "time_s" && $i != "peak_rss_mb") keep[i] = 1 }
             { line = ""; for (i = 1; i <= NF; ++i) if (i in keep) line = line (line == "" ? "" : ",") $i; print line }' "$1"
}

cd "$S" || fail "cannot enter $S"
# `cluster slurm` resolves the suite: generated snapshots are cached before either timing starts.
"$CB" cluster slurm "$SUITE" --out "$S/warm" --shards 1 >/dev/null 2>"$S/log/warm.log" || fail "cluster slurm: $(cat "$S/log/warm.log")"
log "single-machine run of $SUITE"
t0=$(date +%s.%N)
timeout 600 "$CB" run "$SUITE" --out "$S/single" >"$S/log/single.log" 2>&1 || fail "single run failed: $(tail -n 5 "$S/log/single.log")"
t1=$(date +%s.%N)
SINGLE_S=$(awk "BEGIN { printf \"%.1f\", $t1 - $t0 }")
log "single run: $(tail -n 1 "$S/log/single.log") in ${SINGLE_S} s"
strip_times "$S/single/summary.csv" >"$S/single.csv"

# One array through the generated files and the printed commands; FIRST is the first array index.
submit_and_check() {
    local name=$1 first=$2 out="$S/$1"
    shift 2  # further options of `cluster slurm`
    "$CB" cluster slurm "$SUITE" --out "$out" --shards 4 --first-index "$first" --time 00:10:00 "$@" \
        >"$S/log/$name.submit.sh" 2>"$S/log/$name.cluster.log" || fail "cluster slurm failed: $(cat "$S/log/$name.cluster.log")"
    log "$name: $(cat "$S/log/$name.cluster.log")"
    sed 's/^/    /' "$S/log/$name.submit.sh"
    local t0 t1 jobid="" merge_output
    t0=$(date +%s.%N)
    # The printed commands, as a user pastes them: jobid=$(sbatch --parsable ...); sbatch --dependency=afterok:$jobid ...
    local first_line second_line
    first_line=$(sed -n 1p "$S/log/$name.submit.sh")
    second_line=$(sed -n 2p "$S/log/$name.submit.sh")
    eval "${first_line/(sbatch /(timeout 30 sbatch }" || fail "$name: '$first_line' failed"
    merge_output=$(eval "timeout 30 $second_line" 2>&1) || fail "$name: '$second_line' failed: $merge_output"
    [ -n "$jobid" ] || fail "$name: no job id from sbatch --parsable"
    JOBS+=("$jobid")
    local merge_id=${merge_output##* }
    JOBS+=("$merge_id")
    log "$name: array job $jobid, merge job $merge_id ($merge_output)"
    local waited=0 queued t_array=""
    while queued=$(timeout 5 squeue -h -j "$jobid,$merge_id" -o %F 2>/dev/null) && [ -n "$queued" ]; do
        [ -z "$t_array" ] && ! grep -qx "$jobid" <<<"$queued" && t_array=$(date +%s.%N)
        [ "$waited" -lt 900 ] || { timeout 5 squeue; fail "$name: jobs still queued after 90 s"; }
        sleep 0.1; waited=$((waited + 1))
    done
    t1=$(date +%s.%N)
    [ -n "$t_array" ] || t_array=$t1
    ARRAY_S=$(awk "BEGIN { printf \"%.1f s (array %.1f s, then merge %.1f s)\", $t1 - $t0, $t_array - $t0, $t1 - $t_array }")
    [ -f "$out/summary.csv" ] || fail "$name: the merge job wrote no $out/summary.csv"
    for i in 1 2 3 4; do
        [ -f "$out/shard-$i-of-4/summary.csv" ] || fail "$name: shard $i of 4 missing ($out/shard-$i-of-4)"
    done
    strip_times "$out/summary.csv" >"$S/$name.csv"
    if ! diff "$S/single.csv" "$S/$name.csv" >"$S/log/$name.diff"; then
        fail "$name: merged summary.csv differs from the single run's (times aside): $(head -n 20 "$S/log/$name.diff")"
    fi
    "$CB" compare "$S/single" "$out" >"$S/log/$name.compare.log" 2>&1 ||
        fail "$name: compare found a difference: $(tail -n 5 "$S/log/$name.compare.log")"
    # Each run records its array task and node; the task ids are the array's.
    local tasks
    tasks=$(/usr/bin/python3 - "$out" <<'EOF'
import glob, json, sys
tasks, nodes, cpus, jobs = set(), set(), set(), set()
for f in glob.glob(sys.argv[1] + "/runs/*.json"):
    p = json.load(open(f))["provenance"]
    s = p["slurm"]
    tasks.add(int(s["array_task_id"])); nodes.add(s["node"]); cpus.add(p["cpu"]); jobs.add(s["array_job_id"])
    assert len(p["load_average"]) == 3, f
print(" ".join(map(str, sorted(tasks))), "| nodes:", ",".join(sorted(nodes)), "| array jobs:", ",".join(sorted(jobs)),
      "| cpu models:", "; ".join(sorted(cpus)))
EOF
) || fail "$name: run provenance lacks the Slurm job, node, CPU or load"
    local want
    want=$(seq -s ' ' "$first" $((first + 3)))
    [ "${tasks%% |*}" = "$want" ] || fail "$name: runs came from array tasks '${tasks%% |*}', expected '$want'"
    log "$name: merged summary.csv equals the single run's (times aside); compare: $(grep -o 'verdict: .*' "$S/log/$name.compare.log")"
    log "$name: provenance: array tasks $tasks"
    local solve_s
    solve_s=$(awk -F, 'NR == 1 { for (i = 1; i <= NF; ++i) if ($i == "time_s") c = i } NR > 1 { t += $c } END { printf "%.2f", t }' "$out/summary.csv")
    log "$name: wall time from submission ${ARRAY_S} vs ${SINGLE_S} s single run; solver time in the runs: $solve_s s"
}

submit_and_check array0 0
# The offset array also tries the other options on the real sbatch: whole nodes, memory, a throttle.
submit_and_check array5 5 --exclusive --mem 500M --max-parallel 2 --sbatch-option=--comment=contactbench-test
log "merge log: $(cat "$S"/array5/slurm/*merge*.out | tail -n 2 | tr '\n' ' ')"
echo "PASSED: 4-task Slurm arrays 0-3 and 5-8 merged equal to the single run"
exit 0
