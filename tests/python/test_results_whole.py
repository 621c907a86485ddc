"""A results folder is read by plots.loader only when whole (plots/loader.py _require_finished,
the rules of harness/results_folder.hpp): a FIFO among the run files is refused by name instead of
blocking open(), a killed run (suite.pending.json) or one still writing (.lock held) is reported
as incomplete, and with jobs.json every run file is its own job's, final, and listed."""
import fcntl
import json
import os
import shutil
import subprocess
import sys
import tempfile
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, ROOT)
sys.path.insert(0, os.path.join(HERE, "fixtures"))
os.environ.setdefault("MPLBACKEND", "Agg")

import make_fixture as mf  # noqa: E402
from plots import loader  # noqa: E402


class TestResultsWhole(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.mkdtemp(prefix="cb_whole_")
        recs = [mf.make_run("p0", "a", history=False), mf.make_run("p1", "a", history=False)]
        self.folder = mf.write_results(os.path.join(self.tmp, "res"), recs)
        self.jobs = os.path.join(self.folder, "jobs.json")
        with open(self.jobs, "w", encoding="utf-8") as f:  # as `contactbench run` writes it last
            json.dump({"suite": "fixture", "jobs": ["p0__a.json", "p1__a.json"], "complete": True}, f)

    def tearDown(self):
        shutil.rmtree(self.tmp, ignore_errors=True)

    def refused(self, message):
        with self.assertRaises(ValueError) as ctx:
            loader.load_results(self.folder)
        self.assertEqual(str(ctx.exception), message)

    def test_whole_folder_loads(self):
        self.assertEqual(sorted(loader.load_results(self.folder).runs["snapshot"]), ["p0", "p1"])

    def test_fifo_run_file_is_refused_not_opened(self):
        # profiles in a child with a timeout: opening the FIFO would block it forever
        fifo = os.path.join(self.folder, "runs", "zz__a.json")
        os.remove(self.jobs)
        os.mkfifo(fifo)
        out = os.path.join(self.tmp, "prof")
        p = subprocess.run([sys.executable, "-m", "plots.profiles", self.folder, "--out", out], cwd=ROOT,
                           capture_output=True, text=True, timeout=60)
        self.assertEqual(p.returncode, 2)
        self.assertEqual(p.stderr, f"profiles.py: {fifo}: not a regular file (a FIFO)\n")

    def test_killed_run_is_incomplete(self):
        os.remove(self.jobs)
        os.rename(os.path.join(self.folder, "suite.json"), os.path.join(self.folder, "suite.pending.json"))
        self.refused(f"{self.folder}: suite.pending.json: present: the folder's `contactbench run` was "
                     "interrupted or is still running, so its results are incomplete (run it again to finish)")

    def test_running_run_is_incomplete(self):
        fd = os.open(os.path.join(self.folder, ".lock"), os.O_RDWR | os.O_CREAT, 0o644)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX)
            child = subprocess.run([sys.executable, "-c", "import sys; sys.path.insert(0, sys.argv[2]); "
                                    "from plots import loader; loader.load_results(sys.argv[1])",
                                    self.folder, ROOT], capture_output=True, text=True, timeout=60)
        finally:
            os.close(fd)
        self.assertNotEqual(child.returncode, 0)
        self.assertIn(f"ValueError: {self.folder}: being written by `contactbench run` (holding .lock)",
                      child.stderr)
        loader.load_results(self.folder)  # released: whole again

    def test_stale_copy_is_not_a_job(self):
        shutil.copy(os.path.join(self.folder, "runs", "p0__a.json"), os.path.join(self.folder, "runs", "zz.json"))
        self.refused(f"{self.folder}/runs/zz.json: not a job of {self.jobs}: a stray or stale file "
                     "(remove it, or run again)")

    def test_another_jobs_record_and_final_false(self):
        runs = os.path.join(self.folder, "runs")
        shutil.copy(os.path.join(runs, "p1__a.json"), os.path.join(runs, "p0__a.json"))
        self.refused(f"{runs}/p0__a.json: /snapshot/id, /label: the record is of job p1__a.json, not of this file: "
                     "a copy or another job's record (remove it, or run again)")
        rec = mf.make_run("p0", "a", history=False)
        rec["final"] = False
        with open(os.path.join(runs, "p0__a.json"), "w", encoding="utf-8") as f:
            json.dump(rec, f)
        self.refused(f"{runs}/p0__a.json: /final: false: the run ended in an error to be retried, not a result "
                     "(run the suite again)")


if __name__ == "__main__":
    unittest.main()
