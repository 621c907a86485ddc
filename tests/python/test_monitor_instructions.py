"""The monitor's work stays off every solver's clock, measured deterministically: the instructions
a solver executes on its clock (callgrind's count inside `solve` with the monitor call left out,
the perf gate's toggles) are the same with the recording monitor (`--history`) as without it.

Work done only for the monitor outside the paused call (pgs once formed x from lambda every sweep
there, x21.9 in time) adds instructions to the monitored run; this test fails on it on any machine,
where the wall-clock ratio (`make timing`) needs a quiet one. What stays is the call itself (a few
dozen instructions per iteration), far below the bound.

The project's own solvers only: peers that run in a child process do their work where callgrind
does not look (their monitored and unmonitored times are compared by `make timing`)."""
import json
import os
import shutil
import subprocess
import sys
import tempfile
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(ROOT, "tools"))
import perf_gate  # noqa: E402  (the toggles that define "on the solver's clock")

BINARY = os.environ.get("CB_CONTACTBENCH", os.path.join(ROOT, "build", "bin", "contactbench"))
# A stiff body on a plane (n = 588, 98 rows; E = 1e9 as in `make timing`), and the same body under
# bounds for the bounds-only solvers.
PROBLEM = ["--param", "nx=6", "--param", "ny=3", "--param", "nz=6", "--param", "youngs=1e9"]
# Enough iterations for the monitor's per-iteration call to show, few enough that the slow sweeps
# (ica and nsgs-friction take thousands on this stiff body) stay seconds under callgrind.
ITERATION_CAP = ["--set", "max_iterations=300"]
MAX_EXTRA = 0.01  # relative: the call itself is ~1e-4; allocator paths vary run to run by ~0.3%


def run(*args):
    result = subprocess.run([BINARY, *args], capture_output=True, text=True,
                            env=dict(os.environ, OPENBLAS_NUM_THREADS="1"))
    if result.returncode != 0:
        raise AssertionError("contactbench %s failed (exit %d): %s" % (" ".join(args), result.returncode, result.stderr))
    return result.stdout


def instructions(solve_args, out_file):
    """callgrind's Ir inside the solve with the monitor call excluded (tools/perf_gate.py TOGGLES)."""
    args = ["valgrind", "--tool=callgrind", "--callgrind-out-file=" + out_file, "--collect-atstart=no"]
    args += ["--toggle-collect=" + t for t in perf_gate.TOGGLES]
    result = subprocess.run(args + [BINARY] + solve_args, capture_output=True, text=True,
                            env=dict(os.environ, OPENBLAS_NUM_THREADS="1"))
    if result.returncode != 0:
        raise AssertionError("callgrind of %s failed: %s" % (" ".join(solve_args), result.stderr[-2000:]))
    with open(out_file) as f:
        totals = [int(line.split()[1]) for line in f if line.startswith(("summary:", "totals:"))]
    if not totals or totals[0] == 0:
        raise AssertionError("callgrind counted nothing for %s (no function matched %s)"
                             % (" ".join(solve_args), perf_gate.TOGGLES))
    return totals[0]


@unittest.skipUnless(os.path.isfile(BINARY), "no contactbench binary (set CB_CONTACTBENCH)")
class MonitorInstructions(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        if shutil.which("valgrind") is None:
            raise unittest.SkipTest("valgrind is not installed (make deps installs it)")
        cls.work = tempfile.mkdtemp(prefix="cb_test_monitor_instructions_")
        cls.snapshots = {}
        for family in ("plane", "box"):
            path = os.path.join(cls.work, family + ".qpsnap")
            run("generate", family, "--out", path, *PROBLEM)
            cls.snapshots[family] = path

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.work, ignore_errors=True)

    def solve_args(self, name, family, monitored):
        args = ["solve", self.snapshots[family], "--solver", name, "--json", os.path.join(self.work, "r.json")]
        args += ITERATION_CAP
        return args + (["--history"] if monitored else [])

    def test_monitored_runs_execute_the_same_instructions_on_the_solvers_clock(self):
        listed = json.loads(run("solvers", "--json"))
        own = [e["name"] for e in listed if not e["library"] and not e.get("needs_settings")]  # not command
        self.assertIn("pgs", own)
        for name in own:
            with self.subTest(solver=name):
                family = "plane"
                run(*self.solve_args(name, family, False))
                with open(os.path.join(self.work, "r.json")) as f:
                    if json.load(f)["status"] == "not_applicable":  # bounds-only solvers
                        family = "box"
                out = os.path.join(self.work, "callgrind.out")
                plain = instructions(self.solve_args(name, family, False), out)
                monitored = instructions(self.solve_args(name, family, True), out)
                extra = monitored / plain - 1.0
                print("monitor instructions: %-14s %s: %d unmonitored, %d monitored (%+.4f%%)"
                      % (name, family, plain, monitored, 100 * extra), flush=True)
                self.assertLessEqual(abs(extra), MAX_EXTRA, "%s: %d -> %d instructions on the solver's clock"
                                     % (name, plain, monitored))


if __name__ == "__main__":
    unittest.main()
