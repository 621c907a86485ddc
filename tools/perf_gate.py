#!/usr/bin/python3
"""The CI performance gate and the compact baseline (docs: harness/README.md "Performance gate").

    perf_gate.py gate    [--base REV | --base-binary BIN] [--new-binary BIN]   same-machine A/B
    perf_gate.py check   [--new-binary BIN]        against the committed record (across machines)
    perf_gate.py record  [--binary BIN]            rewrite results/baselines/ci.csv (clean tree only)
    perf_gate.py measure --binary BIN --out F.csv  one side, for tests and by hand

`gate` builds BASE (by default the commit that last changed the committed record) in a git
worktree under $CB_CACHE/perf-gate, runs every (snapshot, label) of the suite with both binaries on
this machine, interleaved, and lets `contactbench compare` judge the two compact records: work
counters exactly, instructions executed in the solve (valgrind's callgrind, collection toggled
around the solvers' `solve` by symbol, so any old BASE can be measured from outside) within a
stated threshold, and wall time (minimum of k samples, with a noise band) only beyond a generous
ratio. When BASE cannot be built (no git, shallow clone, no recording commit, failed build) it
says so and falls back to `check`.

Exit status: 0 pass, 3 regression, 2 bad input (suite, dirty tree for `record`), 1 internal error.
"""
import argparse
import concurrent.futures
import csv
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
RECORD = "results/baselines/ci.csv"
SUITE = "suites/ci.json"
# What goes into the contactbench binary: when these trees are equal, so are the binaries.
SOURCE_PATHS = ["solvers", "problems", "harness", "cmake", "CMakeLists.txt"]
# Callgrind collects only inside the solvers' solve (entry toggles on, exit off) and not in the
# monitor the harness installs (its calls are paused on the solver's stopwatch too). The patterns
# match whole demangled names: not the lambdas inside solve ("...) const") nor "[clone .cold]".
TOGGLES = ["cb::*Solver::solve(cb::QpView const&, cb::SolveContext const&)", "cb::notify_monitor(*)"]
COLUMNS = ["snapshot", "label", "status", "iterations", "a_products", "a_products_harness",
           "cholmod_factorizations", "precond_applications", "work", "accuracy", "tol", "instructions",
           "time_min_s", "time_noise", "time_samples", "work_counted"]
# work: A-product equivalents counting factorisations and triangular solves (docs/work.md), the
# one counter in which pgs's and active-set's CHOLMOD work shows.
COUNTERS = ["a_products", "a_products_harness", "cholmod_factorizations", "precond_applications", "work"]
CALLGRIND_TIME_LIMIT_FACTOR = 100  # valgrind runs ~50x slower: keep time limits from firing


class GateError(Exception):
    """Bad input (exit 2)."""


def log(message):
    print("perf-gate: " + message, flush=True)


def git(*args, check=True):
    result = subprocess.run(["git", "-C", ROOT] + list(args), capture_output=True, text=True)
    if check and result.returncode != 0:
        raise RuntimeError("git %s failed: %s" % (" ".join(args), result.stderr.strip()))
    return result.stdout.strip() if result.returncode == 0 else None


def cache_dir():
    return os.environ.get("CB_CACHE") or os.path.join(os.path.expanduser("~"), ".cache", "contactbench")


# --- the suite's runs --------------------------------------------------------------------------

class Job:
    """One (snapshot, label) of the suite, as `contactbench solve` arguments."""

    def __init__(self, snapshot, path, label, solver, settings, decouple, decouple_seed):
        self.snapshot, self.path, self.label, self.solver = snapshot, path, label, solver
        self.settings, self.decouple, self.decouple_seed = settings, decouple, decouple_seed

    def key(self):
        return self.snapshot + "/" + self.label

    def arguments(self, time_limit_factor=1):
        args = ["solve", self.path, "--solver", self.solver, "--decouple", self.decouple,
                "--decouple-seed", str(self.decouple_seed)]
        for k, v in sorted(self.settings.items()):
            if k == "time_limit_s":
                v = v * time_limit_factor
            args += ["--set", "%s=%s" % (k, json.dumps(v) if not isinstance(v, str) else v)]
        return args


def suite_jobs(binary, suite_path, work, snapshot_filter=""):
    if snapshot_filter:
        try:
            re.compile(snapshot_filter)
        except re.error as e:
            raise GateError("--filter: not a regular expression: %r (%s)" % (snapshot_filter, e))
    """Resolves the suite's snapshots with `contactbench run` (it generates and caches them) and
    returns one Job per (snapshot, label), sorted."""
    try:
        with open(suite_path) as f:
            suite = json.load(f)
    except (OSError, ValueError) as e:
        raise GateError("%s: cannot read the suite: %s" % (suite_path, e))
    for key in ("chain", "reference"):
        if suite.get(key):
            raise GateError("%s: %s: the perf gate runs each (snapshot, label) on its own; a suite with "
                            "\"%s\": true cannot be measured that way" % (suite_path, key, key))
    entries = {}
    for s in suite.get("solvers", []):
        entry = {"label": s, "solver": s, "settings": {}} if isinstance(s, str) else s
        settings = dict(entry.get("settings", {}))
        settings.setdefault("tol", suite.get("tol", 1e-6))
        settings.setdefault("time_limit_s", suite.get("time_limit_s", 60))
        for k, v in settings.items():
            if not isinstance(v, (int, float, str, bool)):
                raise GateError("%s: solvers: %s: setting %s: only scalar settings can be passed to "
                                "`contactbench solve --set`" % (suite_path, entry.get("label"), k))
        entries[entry.get("label", entry.get("solver"))] = (entry.get("solver", entry.get("label")), settings)
    resolved = os.path.join(work, "suite-run")
    run = subprocess.run([binary, "run", suite_path, "--out", resolved, "--force"], capture_output=True, text=True)
    if run.returncode != 0:
        raise RuntimeError("%s run %s failed (exit %d):\n%s" % (binary, suite_path, run.returncode, run.stderr))
    jobs = []
    runs_dir = os.path.join(resolved, "runs")
    for name in sorted(os.listdir(runs_dir)):
        with open(os.path.join(runs_dir, name)) as f:
            rec = json.load(f)
        label = rec["label"]
        snap = rec["snapshot"]
        if label not in entries:
            continue
        job = Job(snap["id"], snap.get("path", ""), label, entries[label][0], entries[label][1],
                  suite.get("decouple", "auto"), suite.get("decouple_seed", 0))
        if snapshot_filter and not re.search(snapshot_filter, job.key()):
            continue
        if not os.path.isabs(job.path) and not os.path.exists(job.path):
            job.path = os.path.join(os.path.dirname(os.path.abspath(suite_path)), job.path)
        jobs.append(job)
    if not jobs:
        raise GateError("%s: no runs%s" % (suite_path, " match --filter " + snapshot_filter if snapshot_filter else ""))
    return sorted(jobs, key=lambda j: (j.snapshot, j.label))


# --- measuring one binary ----------------------------------------------------------------------

def solve_native(binary, job, repeats, json_path):
    args = [binary] + job.arguments() + ["--repeat", str(repeats), "--json", json_path]
    result = subprocess.run(args, capture_output=True, text=True)
    if result.returncode != 0:
        raise RuntimeError("%s failed (exit %d): %s" % (" ".join(args), result.returncode, result.stderr.strip()))
    with open(json_path) as f:
        return json.load(f)


def solve_callgrind(binary, job, out_file):
    """Instructions executed inside the solve (callgrind's Ir between the toggles)."""
    args = ["valgrind", "--tool=callgrind", "--callgrind-out-file=" + out_file, "--collect-atstart=no"]
    args += ["--toggle-collect=" + t for t in TOGGLES]
    args += [binary] + job.arguments(CALLGRIND_TIME_LIMIT_FACTOR)
    result = subprocess.run(args, capture_output=True, text=True)
    if result.returncode != 0:
        raise RuntimeError("callgrind of %s failed (exit %d): %s" % (job.key(), result.returncode, result.stderr[-2000:]))
    total = None
    with open(out_file) as f:
        for line in f:
            m = re.match(r"^(summary|totals):\s+(\d+)", line)
            if m:
                total = int(m.group(2))
    os.remove(out_file)
    if not total:
        raise RuntimeError("callgrind collected no instructions for %s with %s: no function matches %s "
                           "(was the binary stripped?)" % (job.key(), binary, " / ".join(TOGGLES)))
    return total


_OLD_KEY_TOLD = set()


def accuracy_object(rec, source):
    """The run's "accuracy" object. A BASE binary of the previous release may write it only under
    its old name "kkt_relative": read with a notice (harness/record_schema.hpp; one release)."""
    if rec.get("accuracy") is not None:
        return rec["accuracy"]
    old = rec.get("kkt_relative")
    if old is not None and source not in _OLD_KEY_TOLD:
        _OLD_KEY_TOLD.add(source)
        print("notice: %s: read the old name 'kkt_relative' as 'accuracy' (accepted until the next release)"
              % source, file=sys.stderr)
    return old


def row_from_record(job, rec, samples):
    counters = rec.get("counters", {})
    row = {"snapshot": job.snapshot, "label": job.label, "status": rec.get("status", ""),
           "iterations": rec.get("iterations")}
    for c in COUNTERS:
        row[c] = counters.get(c)
    # An external program's work is not counted (null counters): written as 0, only then, so that
    # the column appears only in records that have such a run.
    row["work_counted"] = 0 if rec.get("work_counted") is False else None
    accuracy = (accuracy_object(rec, job.key()) or {}).get("max")
    row["accuracy"] = "%.3g" % accuracy if isinstance(accuracy, (int, float)) else None
    row["tol"] = "%g" % rec["tol"] if isinstance(rec.get("tol"), (int, float)) else None
    if samples:
        ordered = sorted(samples)
        k = len(ordered)
        median = ordered[k // 2] if k % 2 else 0.5 * (ordered[k // 2 - 1] + ordered[k // 2])
        row["time_min_s"] = "%.6g" % ordered[0]
        row["time_noise"] = "%.3f" % (median / ordered[0] - 1.0) if ordered[0] > 0 else None
        row["time_samples"] = k
    return row


def fingerprint(rec, binary):
    p = rec.get("provenance", {})
    fp = {k: p.get(k, "unknown") for k in ("cpu", "blas", "suitesparse", "compiler")}
    fp["source_commit"] = p.get("git_commit", "unknown")
    return fp


def measure(sides, jobs, work, repeats, with_instructions, parallel, rounds=1):
    """Measures every job with every binary of `sides` ({name: binary}), interleaved: in each of
    `rounds` rounds, for each job, the binaries take turns (the order alternates between jobs and
    rounds), each process timing `repeats` solves; the samples of all rounds are pooled, so a load
    burst during one process neither sets the minimum nor hides in the noise band.
    Returns {name: (rows, fingerprint)} and the seconds spent natively and under callgrind."""
    names = list(sides)
    rows = {n: {} for n in names}
    machine = {n: None for n in names}
    samples = {n: {job.key(): [] for job in jobs} for n in names}
    records = {n: {} for n in names}
    t0 = time.time()
    for r in range(rounds):
        for i, job in enumerate(jobs):
            order = names if (i + r) % 2 == 0 else list(reversed(names))
            for n in order:
                rec = solve_native(sides[n], job, repeats, os.path.join(work, "%s-%d.json" % (n, i)))
                t = rec.get("time", {})
                samples[n][job.key()] += t.get("samples_total_s") or ([t["total_s"]] if "total_s" in t else [])
                records[n].setdefault(job.key(), rec)  # counters and status: the first round's
                machine[n] = machine[n] or fingerprint(rec, sides[n])
    for n in names:
        for job in jobs:
            pooled = samples[n][job.key()]
            rows[n][job.key()] = row_from_record(job, records[n][job.key()], pooled if len(pooled) > 1 else None)
            rows[n][job.key()]["_native_s"] = min(pooled) if pooled else 0.0  # orders the callgrind runs
    native_s = time.time() - t0
    t0 = time.time()
    if with_instructions:
        # Longest first (by native time), so the parallel processes finish together.
        cost = {job.key(): max(rows[n][job.key()]["_native_s"] for n in names) for job in jobs}
        tasks = [(n, i, job) for i, job in enumerate(jobs) for n in names]
        tasks.sort(key=lambda t: -cost[t[2].key()])
        with concurrent.futures.ThreadPoolExecutor(max_workers=max(1, parallel)) as pool:
            futures = {pool.submit(solve_callgrind, sides[n], job, os.path.join(work, "callgrind-%s-%d.out" % (n, i))):
                       (n, job) for n, i, job in tasks}
            for future in concurrent.futures.as_completed(futures):
                n, job = futures[future]
                rows[n][job.key()]["instructions"] = future.result()
    callgrind_s = time.time() - t0
    return {n: ([rows[n][j.key()] for j in jobs], machine[n]) for n in names}, native_s, callgrind_s


def write_record(path, rows, machine):
    """The compact CSV and its -machine.json, each written to a temporary name and renamed."""
    folder = os.path.dirname(os.path.abspath(path))
    os.makedirs(folder, exist_ok=True)
    columns = [c for c in COLUMNS if any(r.get(c) is not None for r in rows) or c in ("snapshot", "label", "status")]
    tmp = path + ".tmp"
    with open(tmp, "w", newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(columns)
        for r in rows:
            w.writerow(["" if r.get(c) is None else r[c] for c in columns])
    machine_path = os.path.join(folder, os.path.splitext(os.path.basename(path))[0] + "-machine.json")
    with open(machine_path + ".tmp", "w") as f:
        json.dump(machine, f, indent=1, sort_keys=True)
        f.write("\n")
    os.replace(tmp, path)
    os.replace(machine_path + ".tmp", machine_path)


def compare(binary, base_csv, new_csv, args, cross_machine=False, extra=()):
    command = [binary, "compare", base_csv, new_csv, "--instructions-rtol", str(args.instructions_rtol),
               "--time-ratio", str(args.time_ratio)]
    if args.only_changes:
        command.append("--only-changes")
    if cross_machine:
        command.append("--cross-machine")
    command += list(extra)
    print(flush=True)
    return subprocess.run(command).returncode


# --- building BASE -----------------------------------------------------------------------------

def base_unavailable_reason(rev_given):
    """Why no BASE revision can be built here, or None."""
    if shutil.which("git") is None:
        return "git is not installed"
    if git("rev-parse", "--is-inside-work-tree", check=False) != "true":
        return "%s is not a git checkout (a tarball?)" % ROOT
    if not rev_given and git("rev-parse", "--is-shallow-repository", check=False) == "true":
        return "this is a shallow clone: the commit that recorded %s may be missing" % RECORD
    return None


def resolve_base(rev):
    if rev:
        sha = git("rev-parse", "--verify", "--quiet", rev + "^{commit}", check=False)
        if not sha:
            raise GateError("BASE=%s: no such commit in this clone" % rev)
        return sha, "BASE=%s" % rev
    sha = git("log", "-1", "--format=%H", "--", RECORD, check=False)
    if not sha:
        return None, "no commit records %s" % RECORD
    return sha, "the commit that last changed %s" % RECORD


def same_source(sha):
    """True when the working tree's binary sources (tracked and untracked, docs aside) equal BASE's."""
    paths = SOURCE_PATHS + [":(exclude)*.md"]
    differs = subprocess.run(["git", "-C", ROOT, "diff", "--quiet", sha, "--"] + paths).returncode != 0
    untracked = git("ls-files", "--others", "--exclude-standard", "--", *paths, check=False)
    return not differs and not untracked


def build_base(sha, jobs):
    """BASE's contactbench, built in a worktree under $CB_CACHE/perf-gate and cached by commit."""
    root = os.path.join(cache_dir(), "perf-gate")
    cached = os.path.join(root, "bin", sha, "contactbench")
    if os.path.exists(cached):
        return cached, "cached"
    # One worktree per clone, reused across BASE commits: a checkout touches only the files that
    # changed, so the build is incremental (and ccache, when installed, serves the rest).
    clone_key = re.sub(r"[^A-Za-z0-9]+", "-", os.path.realpath(git("rev-parse", "--git-common-dir")).strip("/"))
    tree = os.path.join(root, "worktree-" + clone_key[-80:])
    git("worktree", "prune")
    # A folder left by an earlier clone at the same path (deleted and cloned again) is not a
    # worktree of this repository: its checkout would fail, so it is made anew.
    registered = os.path.realpath(tree) in [os.path.realpath(line[len("worktree "):])
                                            for line in git("worktree", "list", "--porcelain").splitlines()
                                            if line.startswith("worktree ")]
    if not registered:
        shutil.rmtree(tree, ignore_errors=True)
        os.makedirs(root, exist_ok=True)
        git("worktree", "add", "--detach", tree, sha)
    else:
        subprocess.run(["git", "-C", tree, "checkout", "--quiet", "--force", "--detach", sha], check=True)
    build = os.path.join(tree, "build-perf-gate")
    configure = ["cmake", "-S", tree, "-B", build, "-DCMAKE_BUILD_TYPE=Release", "-DCB_BUILD_TESTS=OFF",
                 "-DCB_BUILD_BENCH=OFF"]
    if shutil.which("ccache"):
        configure.append("-DCMAKE_CXX_COMPILER_LAUNCHER=ccache")
    # ccache's base_dir at the worktree, whatever BASE's own CMakeLists.txt says: sources and
    # include paths become relative to the build folder, as in this tree's build, so unchanged
    # files are hits of the build that `make test` just made.
    env = dict(os.environ, CCACHE_BASEDIR=os.path.realpath(tree))
    for command in (configure, ["cmake", "--build", build, "-j", str(jobs), "--target", "contactbench"]):
        result = subprocess.run(command, capture_output=True, text=True, env=env)
        if result.returncode != 0:
            raise RuntimeError("building BASE %s failed: %s\n%s" % (sha[:12], " ".join(command),
                                                                   (result.stdout + result.stderr)[-3000:]))
    os.makedirs(os.path.dirname(cached), exist_ok=True)
    shutil.copy2(os.path.join(build, "bin", "contactbench"), cached + ".tmp")
    os.replace(cached + ".tmp", cached)
    return cached, "built"


# --- commands ----------------------------------------------------------------------------------

def work_dir(args):
    path = os.path.abspath(args.out)
    shutil.rmtree(path, ignore_errors=True)
    os.makedirs(path)
    return path


def check_tools(args):
    if not args.no_instructions and shutil.which("valgrind") is None:
        raise RuntimeError("valgrind is not installed (make deps installs it); instructions cannot be counted "
                           "(--no-instructions skips them, and so the check that catches uncounted work)")


def cmd_gate(args):
    started = time.time()
    check_tools(args)
    new = os.path.abspath(args.new_binary)
    if args.base_binary:
        base, how = os.path.abspath(args.base_binary), "given binary %s" % args.base_binary
    else:
        reason = base_unavailable_reason(bool(args.base))
        sha = None
        if reason is None:
            sha, why = resolve_base(args.base)
            if sha is None:
                reason = why
        if reason is not None:
            log("cannot build a BASE revision: %s" % reason)
            log("falling back to the committed record %s with the across-machines rules" % RECORD)
            return cmd_check(args, started)
        if not args.no_reuse and same_source(sha):
            base, how = new, ("%s (%s): its %s equal the working tree's (docs aside), so the current "
                              "binary serves as BASE" % (sha[:12], why, " ".join(SOURCE_PATHS)))
        else:
            t0 = time.time()
            try:
                base, state = build_base(sha, args.jobs)
            except (RuntimeError, subprocess.CalledProcessError) as e:
                log("cannot build BASE %s: %s" % (sha[:12], e))
                log("falling back to the committed record %s with the across-machines rules" % RECORD)
                return cmd_check(args, started)
            how = "%s (%s), %s in %.0f s" % (sha[:12], why, state, time.time() - t0)
    log("BASE %s" % how)
    log("NEW  %s (the working tree)" % args.new_binary)
    work = work_dir(args)
    jobs = suite_jobs(new, args.suite, work, args.filter)
    sides = {"base": base, "new": new}
    if os.path.realpath(base) == os.path.realpath(new):
        # BASE's sources equal the working tree's: a second measurement of the same binary would
        # compare its noise only. Measured once, its record serves as both sides (halves the stage).
        sides = {"new": new}
    measured, native_s, callgrind_s = measure(sides, jobs, work, args.repeats, not args.no_instructions, args.jobs,
                                              args.rounds)
    measured.setdefault("base", measured["new"])
    for name in ("base", "new"):
        write_record(os.path.join(work, name + ".csv"), *measured[name])
    log("%d runs x %s: wall time %d rounds x %d samples each (%.0f s), instructions under callgrind (%.0f s)"
        % (len(jobs), "2 binaries" if len(sides) == 2 else "1 binary (BASE is the same binary)", args.rounds,
           args.repeats, native_s, callgrind_s if not args.no_instructions else 0))
    status = compare(new, os.path.join(work, "base.csv"), os.path.join(work, "new.csv"), args)
    log("records in %s/{base,new}.csv; gate time %.0f s; exit %d" % (args.out, time.time() - started, status))
    return status


def cmd_check(args, started=None):
    started = started or time.time()
    check_tools(args)
    record = os.path.join(ROOT, RECORD)
    if not os.path.exists(record):
        raise GateError("%s: no committed record (run `make baseline` and commit it)" % record)
    new = os.path.abspath(args.new_binary)
    work = work_dir(args)
    jobs = suite_jobs(new, args.suite, work, args.filter)
    measured, _, _ = measure({"new": new}, jobs, work, 1, not args.no_instructions, args.jobs)
    write_record(os.path.join(work, "new.csv"), *measured["new"])
    extra = ["--filter", args.filter] if args.filter else []
    status = compare(new, record, os.path.join(work, "new.csv"), args, cross_machine=True, extra=extra)
    log("compared with the committed record (across machines); gate time %.0f s; exit %d"
        % (time.time() - started, status))
    return status


def round_significant(value, digits=3):
    """10804963 -> 10800000: the committed record keeps what a re-record must not churn on
    (instruction counts move by a few instructions with heap alignment)."""
    if not value:
        return value
    scale = 10 ** max(0, len(str(int(value))) - digits)
    return int(round(value / scale) * scale)


def cmd_measure(args, significant=None):
    check_tools(args)
    binary = os.path.abspath(args.binary)
    with tempfile.TemporaryDirectory(prefix="perf-gate-") as work:
        jobs = suite_jobs(binary, args.suite, work, args.filter)
        measured, native_s, callgrind_s = measure({"side": binary}, jobs, work, args.repeats,
                                                  not args.no_instructions, args.jobs)
    rows, machine = measured["side"]
    if significant:
        for r in rows:
            r["instructions"] = round_significant(r.get("instructions"), significant)
    write_record(args.out, rows, machine)
    log("%s: %d runs (%.0f s natively, %.0f s under callgrind)" % (args.out, len(jobs), native_s, callgrind_s))
    return 0


def cmd_record(args):
    dirty = git("status", "--porcelain", check=False)
    if dirty is None:
        raise GateError("%s: not a git checkout: a baseline must name the commit it measured" % ROOT)
    if dirty:
        raise GateError("the working tree is not clean; commit the change first, then record the baseline "
                        "from the clean tree:\n" + dirty)
    args.out = os.path.join(ROOT, RECORD)
    args.repeats = 1
    cmd_measure(args, significant=3)
    old = os.path.join(ROOT, "results", "baselines", "ci")
    if os.path.isdir(old):  # the former per-run folder, replaced by the compact record
        shutil.rmtree(old)
    changed = git("status", "--porcelain", "--", "results/baselines", check=False)
    if not changed:
        log("the record did not change: nothing to commit")
        return 0
    print(changed)
    # What the reviewer of the baseline commit reads: the changed rows of the record.
    print(git("diff", "--no-color", "--", RECORD, check=False))
    log("commit it alone, right after the change that explains it; that commit becomes the gate's BASE:\n"
        "    git add -A results/baselines && git commit -m 'CI baseline: re-recorded after <change>'")
    return 0


def main(argv):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="command", required=True)

    def common(p, out):
        p.add_argument("--suite", default=os.path.join(ROOT, SUITE))
        p.add_argument("--filter", default="", help="only runs whose snapshot/label matches this regular expression")
        p.add_argument("--jobs", type=int, default=2, help="parallel callgrind processes and build jobs")
        p.add_argument("--no-instructions", action="store_true", help="skip callgrind (not for the gate)")
        if out:
            p.add_argument("--out", default=out)

    for name in ("gate", "check"):
        p = sub.add_parser(name)
        common(p, os.path.join(ROOT, "results", "perf-gate"))
        p.add_argument("--new-binary", default=os.path.join(ROOT, "build", "bin", "contactbench"))
        p.add_argument("--rounds", type=int, default=3, help="interleaved processes per run and side")
        p.add_argument("--repeats", type=int, default=3, help="timed solves per process (the min of all is judged)")
        p.add_argument("--instructions-rtol", type=float, default=0.03)
        p.add_argument("--time-ratio", type=float, default=1.5, help="0: wall time shown, not judged")
        p.add_argument("--only-changes", action="store_true")
        if name == "gate":
            p.add_argument("--base", default="", help="BASE revision (default: the commit that last changed %s)" % RECORD)
            p.add_argument("--base-binary", default="", help="a built BASE binary instead of a revision")
            p.add_argument("--no-reuse", action="store_true",
                           help="build BASE even when its source equals the working tree's")
    p = sub.add_parser("measure")
    common(p, None)
    p.add_argument("--binary", required=True)
    p.add_argument("--out", required=True)
    p.add_argument("--repeats", type=int, default=1)
    p = sub.add_parser("record")
    common(p, None)
    p.add_argument("--binary", default=os.path.join(ROOT, "build", "bin", "contactbench"))
    args = parser.parse_args(argv)
    if getattr(args, "repeats", 1) < 1 or getattr(args, "rounds", 1) < 1:
        parser.error("--repeats and --rounds must be >= 1")
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    os.environ.setdefault("CB_REPORT", "0")  # the suite runs it starts need no HTML page
    try:
        return {"gate": cmd_gate, "check": cmd_check, "measure": cmd_measure, "record": cmd_record}[args.command](args)
    except GateError as e:
        print("perf-gate: error: %s" % e, file=sys.stderr)
        return 2
    except (RuntimeError, OSError, subprocess.CalledProcessError) as e:
        print("perf-gate: internal error: %s" % e, file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
