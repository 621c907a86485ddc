"""The one name of the accuracy error (plots/record_schema.py, harness/record_schema.hpp): readers
take files of the previous release ("kkt_relative", "kkt_rel", "kkt_rel_solved", stability.csv's
"kkt") with one OldNameWarning per file and name; the writers use `accuracy` only."""
import contextlib
import io
import json
import os
import shutil
import sys
import tempfile
import unittest
import warnings

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, ROOT)  # plots/ is a package of the repository root
sys.path.insert(0, os.path.join(HERE, "fixtures"))
sys.path.insert(0, os.path.join(ROOT, "tools"))
os.environ.setdefault("MPLBACKEND", "Agg")

import make_fixture as mf  # noqa: E402
import perf_gate  # noqa: E402
from plots import loader, record_schema, stability  # noqa: E402


def expected(source, old, new):
    return (f"{source}: read the old name '{old}' as '{new}' (accepted until the next release; "
            f"rewrite the file to use '{new}')")


class OldNames(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.mkdtemp(prefix="cb_test_record_schema_")
        record_schema._told.clear()

    def tearDown(self):
        shutil.rmtree(self.tmp, ignore_errors=True)

    def old_record(self):
        """A run record as the previous release wrote it: "kkt_relative" and the history column "kkt_rel"."""
        rec = mf.make_run("p", "mprgp", final_accuracy=1e-8)
        rec["kkt_relative"] = rec.pop("accuracy")
        rec["history"]["columns"] = ["kkt_rel" if c == "accuracy" else c for c in rec["history"]["columns"]]
        return rec

    def test_old_run_record_and_history_read_with_one_warning_each(self):
        runs = os.path.join(self.tmp, "runs")
        os.makedirs(runs)
        file = os.path.join(runs, "p__mprgp.json")
        with open(file, "w") as f:
            json.dump(self.old_record(), f)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            res = loader.load_results(self.tmp)
            loader.load_results(self.tmp)  # the same file again: no second warning
        messages = [str(w.message) for w in caught if issubclass(w.category, record_schema.OldNameWarning)]
        self.assertEqual(messages, [expected(file, "kkt_relative", "accuracy"), expected(file, "kkt_rel", "accuracy")])
        self.assertAlmostEqual(res.runs.iloc[0]["accuracy"], 1e-8, delta=1e-20)
        self.assertAlmostEqual(res.history("p", "mprgp")["accuracy"].iloc[-1], 1e-8, delta=1e-20)
        self.assertNotIn("kkt_rel", res.runs.columns)

    def test_old_summary_csv_columns_renamed(self):
        path = os.path.join(self.tmp, "summary.csv")
        with open(path, "w") as f:
            f.write("suite,snapshot,label,status,kkt_rel,kkt_rel_solved\ns,p,cg,converged,2e-3,1e-9\n")
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            res = loader.load_results(self.tmp)
        self.assertEqual([str(w.message) for w in caught],
                         [expected(path, "kkt_rel", "accuracy"), expected(path, "kkt_rel_solved", "accuracy_solved")])
        self.assertEqual(list(res.summary.columns)[4:], ["accuracy", "accuracy_solved"])
        self.assertEqual(res.summary.iloc[0]["accuracy"], 2e-3)

    def test_old_stability_csv_read(self):
        path = os.path.join(self.tmp, "stability.csv")
        with open(path, "w") as f:
            f.write("solver,case,severity,status,kkt,tol,kkt_solved\nmprgp,stiff,2,converged,1e-7,1e-6,1e-8\n")
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            df = stability.read_table(self.tmp)
        self.assertEqual([str(w.message) for w in caught],
                         [expected(path, "kkt", "accuracy"), expected(path, "kkt_solved", "accuracy_solved")])
        self.assertEqual(stability.find_column(df, "error"), "accuracy")

    def test_convergence_column_old_name(self):
        from plots import convergence
        mf.write_results(self.tmp, [mf.make_run("p", "a")])
        out = io.StringIO()
        with warnings.catch_warnings(record=True) as caught, contextlib.redirect_stdout(out):
            warnings.simplefilter("always")
            self.assertEqual(convergence.main([self.tmp, "--column", "kkt_rel"]), 0)
        self.assertEqual([str(w.message) for w in caught], [expected("--column", "kkt_rel", "accuracy")])
        self.assertIn("convergence_", out.getvalue())

    def test_current_name_wins_and_is_silent(self):
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            self.assertEqual(record_schema.accuracy_of({"accuracy": {"max": 1}, "kkt_relative": {"max": 2}}),
                             {"max": 1})
            self.assertEqual(record_schema.current_column_names(["kkt_rel", "accuracy"], "both.csv"),
                             ["kkt_rel", "accuracy"])
        self.assertEqual(caught, [])

    def test_perf_gate_writes_accuracy_and_reads_an_old_base(self):
        self.assertIn("accuracy", perf_gate.COLUMNS)
        self.assertNotIn("kkt_rel", perf_gate.COLUMNS)
        job = perf_gate.Job("box", "/x.qpsnap", "cg", "cg", {}, "auto", 0)
        new = perf_gate.row_from_record(job, {"status": "converged", "accuracy": {"max": 1.23456e-7}}, [])
        self.assertEqual(new["accuracy"], "1.23e-07")
        err = io.StringIO()
        with contextlib.redirect_stderr(err):
            old = perf_gate.row_from_record(job, {"status": "converged", "kkt_relative": {"max": 4e-9}}, [])
        self.assertEqual(old["accuracy"], "4e-09")
        self.assertEqual(err.getvalue(), "notice: box/cg: read the old name 'kkt_relative' as 'accuracy' "
                                         "(accepted until the next release)\n")


if __name__ == "__main__":
    unittest.main()
