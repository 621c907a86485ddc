#!/usr/bin/python3
"""Instructions per iteration of `mprgp-coupled` and decoupled `mprgp` on snapshots (issue 31's
iteration-cost criterion, counted instead of timed).

Runs build/bin/cb_bench's coupled_iteration benchmarks under callgrind with CB_BENCH_CALLGRIND set:
each snapshot is solved once by each solver (registry defaults; decoupled mprgp on the authors' row
order, as `contactbench run` with "decouple": "auto"), and callgrind counts the instructions from the
solver's first monitor call (after its setup) to the solve's return. Instruction counts are the same
on every run of the same binary, where the thread CPU time per iteration swings ~10% between runs on a
shared VM; on flank_press frame 0 the time ratio has run ~1.09x the instruction ratio (the coupled
loop gathers more).

usage: tools/iteration_instructions.py [--binary build/bin/cb_bench] [--coupled-settings JSON] SNAPSHOT.qpsnap...
Prints one row per snapshot; takes about 4 s per 1e9 instructions (flank_press frame 0: ~20 s).
"""
import argparse
import glob
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)


def fail(message):
    print("iteration_instructions: " + message, file=sys.stderr)
    sys.exit(2)


def read_dumps(folder):
    """{label: instructions} from callgrind's client-request dumps in `folder`."""
    totals = {}
    for path in glob.glob(os.path.join(folder, "callgrind.out*")):
        label, total = None, None
        with open(path, encoding="utf-8", errors="replace") as f:
            for line in f:
                m = re.match(r"desc: Trigger: Client Request: (.*)$", line.rstrip("\n"))
                if m:
                    label = m.group(1)
                m = re.match(r"(?:summary|totals): (\d+)", line)
                if m:
                    total = int(m.group(1))
        if label is not None and total is not None:
            totals[label] = total
    return totals


def main(argv):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--binary", default=os.path.join(ROOT, "build", "bin", "cb_bench"),
                        help="cb_bench to run (default: build/bin/cb_bench)")
    parser.add_argument("--coupled-settings", default="",
                        help='mprgp-coupled\'s settings as a JSON object, e.g. \'{"precond": "scaled"}\' '
                             "(default: its registry defaults)")
    parser.add_argument("snapshots", nargs="+", help=".qpsnap files")
    args = parser.parse_args(argv)
    if args.coupled_settings:
        try:
            if not isinstance(json.loads(args.coupled_settings), dict):
                raise ValueError("not an object")
        except ValueError as e:
            fail("--coupled-settings: not a JSON object (%s)" % e)
    for path in args.snapshots:
        if not os.path.isfile(path):
            fail("%s: no such snapshot file" % path)
        if ":" in path:
            fail("%s: a path with ':' cannot be passed in CB_BENCH_SNAPSHOTS" % path)
    if not os.path.isfile(args.binary):
        fail("%s: no such binary (cmake --build build --target cb_bench)" % args.binary)
    if shutil.which("valgrind") is None:
        fail("valgrind is not installed (apt-get install valgrind)")
    stems = [os.path.splitext(os.path.basename(p))[0] for p in args.snapshots]
    if len(set(stems)) != len(stems):
        fail("two snapshots share a file name: the dumps are labelled by it")
    with tempfile.TemporaryDirectory(prefix="cb-iteration-instructions-") as work:
        env = dict(os.environ, CB_BENCH_SNAPSHOTS=":".join(os.path.abspath(p) for p in args.snapshots),
                   CB_BENCH_CALLGRIND="1", OPENBLAS_NUM_THREADS="1",
                   CB_BENCH_COUPLED_SETTINGS=args.coupled_settings)
        bench_json = os.path.join(work, "bench.json")
        command = ["valgrind", "--tool=callgrind", "--collect-atstart=no",
                   "--callgrind-out-file=" + os.path.join(work, "callgrind.out"), args.binary,
                   "--benchmark_filter=coupled_iteration", "--benchmark_out=" + bench_json,
                   "--benchmark_out_format=json"]
        run = subprocess.run(command, env=env, capture_output=True, text=True)
        if run.returncode != 0:
            fail("cb_bench under callgrind failed (exit %d): %s" % (run.returncode, run.stderr[-2000:]))
        totals = read_dumps(work)
        with open(bench_json, encoding="utf-8") as f:
            benchmarks = json.load(f)["benchmarks"]
    counters = {}
    for b in benchmarks:
        m = re.match(r"BM_mprgp_coupled_iteration_ratio/([^/]+)/", b["name"])
        if m:
            counters[m.group(1)] = b
    print("%-28s %9s %12s %9s %12s %7s %s" % ("snapshot", "coupled it", "instr/it", "mprgp it", "instr/it", "ratio",
                                             "coupled status"))
    for stem in stems:
        b = counters.get(stem)
        coupled, mprgp = totals.get("coupled " + stem), totals.get("mprgp " + stem)
        if b is None or coupled is None or mprgp is None:
            fail("%s: no benchmark or no callgrind dump for it" % stem)
        it_c, it_d = int(b["coupled_it"]), int(b["mprgp_it"])
        per_c = coupled / max(1, it_c)
        per_d = mprgp / max(1, it_d)
        status = "converged" if b["coupled_converged"] >= 1.0 else "NOT converged"
        print("%-28s %9d %12d %9d %12d %7.4f %s" % (stem, it_c, round(per_c), it_d, round(per_d), per_c / per_d,
                                                status))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
