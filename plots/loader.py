"""Load a contactbench results folder (INTERFACES.md "Results folder") into pandas DataFrames.

A results folder holds summary.csv (one row per run), runs/<snapshot>__<label>.json (the full
per-run records, with histories when recorded), suite.json and provenance.json. Simulation
folders (``contactbench simulate``) hold snapshots/*.qpsnap, steps.csv and frames.csv.

Everything here only reads; nothing is computed that the harness already computed.

This is the pandas entry point of contactbench (docs/INTERFACES.md gives every column's unit):

    from plots.loader import load_results, load_simulation
    res = load_results("results/demo")        # .summary, .runs, .histories DataFrames
    res.history("plane-s1", "mprgp")          # one run's history
    load_simulation("results/demo/sim")       # steps.csv, frames.csv, snapshot headers
"""
from __future__ import annotations

import json
import math
import fcntl
import os
import stat
import struct
from dataclasses import dataclass, field
from typing import Dict, List, Optional

import numpy as np
import pandas as pd

from plots.record_schema import accuracy_of, current_column_names, with_current_columns, work_counted

#: history columns (harness/history.cpp); used when a record omits "columns". `accuracy` is the
#: error e of docs/accuracy.md on the original QP (old files' names are read by record_schema).
HISTORY_COLUMNS = ["iteration", "time_s", "a_products", "step", "stationarity", "primal", "dual",
                   "complementarity", "gap", "accuracy", "objective", "native_residual", "active_set", "work"]

#: summary.csv columns (harness/results.cpp)
SUMMARY_COLUMNS = ["suite", "snapshot", "label", "solver", "status", "solver_status", "criterion",
                   "status_confirmed", "iterations", "a_products", "work", "cholmod_factorizations", "accuracy",
                   "stationarity", "primal", "dual", "complementarity", "gap", "accuracy_solved", "m_solved",
                   "objective", "energy_gap", "violation", "native_residual", "nonfinite", "monotone",
                   "setup_s", "solve_s", "time_s", "peak_rss_mb", "n", "m", "tol", "length_scale",
                   "length_scale_source", "fclib_error", "solved_problem", "mu_min", "mu_max"]

#: run statuses beside the solvers' own (harness/runner.hpp)
RELAXATION_STATUS = "solved_relaxation"
UNCONFIRMED_STATUS = "unconfirmed"
#: a run that met tol on the problem it solved: the original QP, or the one it changed
SOLVED_OWN_PROBLEM = ("converged", RELAXATION_STATUS)
#: a problem class the solver does not take (mprgp-box on general rows, pgs over max_rows): "n/a",
#: neither a success nor a failure
NOT_APPLICABLE_STATUS = "not_applicable"

#: History times are solve-only until the shared solve loop (issue 14) stamps them from the start
#: of setup; history_time() then adds the run's setup_s. Set to False (and simplify
#: history_time) once every history is stamped from the start of setup.
def history_time(history: pd.DataFrame, run, include_setup: bool = True) -> np.ndarray:
    """The time axis of a history, from the start of setup (include_setup) or solve-only.

    Histories with a `solve_time_s` column are stamped from the start of setup (time_origin
    "setup_start"): time_s is used as it is and solve_time_s gives the solve-only axis. Older
    files stamped solve-only times: setup_s is added to every row, capped at the run's total time
    (their last row, the returned point, was already stamped with setup + solve)."""
    def column(name):
        return pd.to_numeric(history[name], errors="coerce").to_numpy(dtype=float) if name in history \
            else np.full(len(history), np.nan)
    t = column("time_s")
    if "solve_time_s" in history:
        return t if include_setup else column("solve_time_s")
    setup = _number(run.get("setup_s")) if run is not None else float("nan")
    total = _number(run.get("time_s")) if run is not None else float("nan")
    setup = setup if math.isfinite(setup) else 0.0
    if not include_setup:
        return np.minimum(t, total - setup) if math.isfinite(total) else t
    out = t + setup
    return np.minimum(out, total) if math.isfinite(total) else out


_BOOL_COLUMNS = ("status_confirmed", "nonfinite", "monotone")


def _to_bool(value) -> bool:
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if isinstance(value, (int, float, np.integer, np.floating)):
        return bool(value) and not (isinstance(value, float) and math.isnan(value))
    return str(value).strip().lower() in ("true", "1", "yes")


def _number(value) -> float:
    """JSON numbers, plus null/"nan"/"inf" strings as some writers emit for non-finite values."""
    if value is None:
        return float("nan")
    if isinstance(value, (int, float)):
        return float(value)
    try:
        return float(str(value))
    except ValueError:
        return float("nan")


@dataclass
class Results:
    """One results folder, loaded."""
    path: str
    summary: pd.DataFrame                      #: summary.csv (or rebuilt from runs when absent)
    runs: pd.DataFrame                         #: one row per run JSON (flattened scalars)
    histories: pd.DataFrame                    #: long form: snapshot, label + history columns
    records: Dict[tuple, dict] = field(default_factory=dict)  #: (snapshot, label) -> run JSON
    suite: dict = field(default_factory=dict)
    provenance: dict = field(default_factory=dict)
    _by_run: Optional[dict] = field(default=None, repr=False)

    def history(self, snapshot: str, label: str) -> pd.DataFrame:
        """History of one run (empty DataFrame with the standard columns when not recorded)."""
        if self.histories.empty:
            return pd.DataFrame(columns=HISTORY_COLUMNS)
        if self._by_run is None:  # one pass over the long table, not one filter per lookup
            self._by_run = {key: g.reset_index(drop=True)
                            for key, g in self.histories.groupby(["snapshot", "label"], sort=False)}
        found = self._by_run.get((snapshot, label))
        return found if found is not None else pd.DataFrame(columns=self.histories.columns)

    def labels(self) -> List[str]:
        return list(dict.fromkeys(self.runs["label"])) if not self.runs.empty else []

    def snapshots(self) -> List[str]:
        return list(dict.fromkeys(self.runs["snapshot"])) if not self.runs.empty else []


def flatten_run(record: dict, source: str = "run record") -> dict:
    """The scalar facts of one run record, as one flat row (`source` names it in warnings)."""
    snap = record.get("snapshot", {}) or {}
    meta = snap.get("meta", {}) or {}
    counters = record.get("counters", {}) or {}
    times = record.get("time", {}) or {}
    accuracy = accuracy_of(record, source)  # e on the original QP (old names with a warning)
    solved = record.get("accuracy_solved") or accuracy
    ref = record.get("reference") or {}
    dec = record.get("decouple") or {}
    row = {
        "snapshot": snap.get("id", ""),
        "snapshot_path": snap.get("path", ""),
        "label": record.get("label", record.get("solver", "")),
        "solver": record.get("solver", ""),
        "status": record.get("status", ""),
        "solver_status": record.get("solver_status", record.get("status", "")),
        "criterion": record.get("criterion", ""),
        "message": record.get("message", ""),
        "status_confirmed": _to_bool(record.get("status_confirmed", True)),
        "iterations": _number(record.get("iterations")),
        "objective": _number(record.get("objective")),
        "accuracy": _number(accuracy.get("max")),
        "accuracy_solved": _number(solved.get("max")),
        "m_solved": _number(record.get("m_solved", snap.get("m"))),
        "energy_gap": _number(record.get("energy_gap")),
        "length_scale": _number(record.get("length_scale")),
        "length_scale_source": record.get("length_scale_source", ""),
        "violation": _number(record.get("violation")),
        "native_residual": _number(record.get("native_residual")),
        "nonfinite": _to_bool(record.get("nonfinite", False)),
        "monotone": _to_bool(record.get("monotone", True)),
        "tol": _number(record.get("tol")),
        "accuracy_tol": _number(record.get("accuracy_tol", record.get("tol"))),
        "solved_problem": record.get("solved_problem"),
        # friction (issue 48): NaN for a frictionless run
        "fclib_error": _number(record.get("fclib_error")),
        "mu_min": _number((record.get("friction") or {}).get("mu_min")),
        "mu_max": _number((record.get("friction") or {}).get("mu_max")),
        "peak_rss_mb": _number((record.get("memory") or {}).get("peak_rss_mb")),
        "setup_s": _number(times.get("setup_s")),
        "solve_s": _number(times.get("solve_s")),
        "time_s": _number(times.get("total_s", _number(times.get("setup_s")) + _number(times.get("solve_s")))),
        "n": _number(snap.get("n")),
        "m": _number(snap.get("m")),
        "frame": _number(meta.get("frame")),
        "newton_iteration": _number(meta.get("newton_iteration")),
        "scene": meta.get("scene", ""),
        "h": _number(meta.get("h")),
        "vertices": _number(meta.get("vertices")),
        "tets": _number(meta.get("tets")),
        "reference_objective": _number(ref.get("objective")),
        "rows_before": _number(dec.get("rows_before")),
        "rows_after": _number(dec.get("rows_after")),
    }
    for key, value in counters.items():
        row["counters." + key] = _number(value)
    row["a_products"] = _number(counters.get("a_products"))
    row["work"] = _number(counters.get("work"))  # A-product equivalents (docs/work.md); NaN in older files
    row["work_counted"] = work_counted(record)  # false: an external program's (null counters)
    for key, value in (record.get("settings") or {}).items():
        if isinstance(value, (str, int, float, bool)) or value is None:
            row["settings." + key] = value
    return row


#: statuses of runs that measured nothing (the solver refused or never ran)
UNMEASURED_STATUSES = ("invalid_input", "not_run", NOT_APPLICABLE_STATUS)


def measured(runs: pd.DataFrame) -> pd.DataFrame:
    """The runs that actually ran (not invalid_input / not_run / not_applicable)."""
    if runs.empty or "status" not in runs:
        return runs
    return runs[~runs["status"].isin(UNMEASURED_STATUSES)]


def unmeasured_notes(runs: pd.DataFrame, labels=None) -> list:
    """One line per label whose runs did not run, with the first message."""
    notes = []
    if runs.empty or "status" not in runs:
        return notes
    bad = runs[runs["status"].isin(UNMEASURED_STATUSES)]
    for label, g in bad.groupby("label", sort=False):
        if labels is not None and label not in labels:
            continue
        msg = str(g.iloc[0].get("message", "") or "")
        notes.append(f"{label}: {len(g)} run(s) {g.iloc[0]['status']}" + (f" ({msg})" if msg else ""))
    return notes


#: the one vocabulary of run statuses (harness/runner.hpp, solvers/core/solver.cpp), as figures, tables
#: and the report use them; figures mark every status but `converged` with the same black x
STATUS_MEANINGS = {
    "converged": "the solver said converged and the accuracy error e on the original QP is <= tol",
    RELAXATION_STATUS: "tol met only on the problem the solver changed (decoupled rows, or J ignored); "
                       "e on the original QP is above tol",
    UNCONFIRMED_STATUS: "the solver's own stopping test was met, but e of the QP it solved is above the "
                        "common tolerance",
    "max_iterations": "stopped at its iteration limit",
    "time_limit": "stopped at its time limit",
    "stalled": "stopped making progress",
    "diverged": "diverged",
    "infeasible": "reported the problem infeasible",
    "stopped_by_monitor": "stopped by the harness's monitor",
    NOT_APPLICABLE_STATUS: "a problem class the solver does not take (n/a: neither a success nor a failure)",
    "invalid_input": "refused its input (settings or problem)",
    "not_run": "not run (solver not built or not registered)",
}

#: what the report says about a run with status `unconfirmed` (harness/README.md, docs/accuracy.md)
UNCONFIRMED_MEANING = ("`unconfirmed`: the solver's own stopping test was met (with stop=native the paper's "
                       "residual at the paper's tolerance) but the accuracy error e (docs/accuracy.md) of "
                       "the QP it solved was above the common tolerance `accuracy_tol`, so the harness "
                       "does not confirm it as converged.")


def status_notes(runs: pd.DataFrame) -> list:
    """The meaning of the statuses that need one (`unconfirmed`), when some run has it, with its count."""
    if runs.empty or "status" not in runs:
        return []
    count = int((runs["status"] == UNCONFIRMED_STATUS).sum())
    return [f"{count} run(s) {UNCONFIRMED_MEANING}"] if count else []


def history_frame(record: dict, source: str = "run record") -> pd.DataFrame:
    """The history of one run record as a DataFrame (empty when not recorded)."""
    hist = record.get("history")
    if not hist:
        return pd.DataFrame(columns=HISTORY_COLUMNS)
    columns = current_column_names(hist.get("columns") or HISTORY_COLUMNS, source)
    rows = hist.get("rows") or []
    df = pd.DataFrame(rows, columns=columns)
    for col in df.columns:
        if col != "step":
            df[col] = pd.to_numeric(df[col], errors="coerce")
    return df


def _require_regular(file: str) -> None:
    """A FIFO would block open() forever and a device would be read as data: refused by name."""
    try:
        mode = os.stat(file).st_mode
    except OSError as err:  # a dangling link or a link loop
        raise ValueError(f"{file}: cannot open: {err.strerror}") from err
    if not stat.S_ISREG(mode):
        kind = ("a folder" if stat.S_ISDIR(mode) else "a FIFO" if stat.S_ISFIFO(mode) else
                "a socket" if stat.S_ISSOCK(mode) else "a device" if stat.S_ISCHR(mode) or stat.S_ISBLK(mode)
                else "not a plain file")
        raise ValueError(f"{file}: not a regular file ({kind})")


def _require_finished(path: str, run_names: List[str]) -> bool:
    """The rules of harness/results_folder.hpp: a folder that `contactbench run` is writing (it holds
    .lock) or that a killed run left (suite.pending.json) is incomplete, and with jobs.json the run
    files are exactly the jobs listed. Returns True for a folder of `run` (it has jobs.json)."""
    lock = os.path.join(path, ".lock")
    try:
        fd = os.open(lock, os.O_RDONLY | os.O_NOFOLLOW | os.O_NONBLOCK)
    except OSError:
        fd = None
    if fd is not None:
        try:
            if stat.S_ISREG(os.fstat(fd).st_mode):
                try:
                    fcntl.flock(fd, fcntl.LOCK_SH | fcntl.LOCK_NB)
                except BlockingIOError:
                    raise ValueError(f"{path}: being written by `contactbench run` (holding .lock): "
                                     "not a finished result; wait for it to finish") from None
        finally:
            os.close(fd)
    if os.path.lexists(os.path.join(path, "suite.pending.json")):
        raise ValueError(f"{path}: suite.pending.json: present: the folder's `contactbench run` was interrupted "
                         "or is still running, so its results are incomplete (run it again to finish)")
    jobs_path = os.path.join(path, "jobs.json")
    if not os.path.lexists(jobs_path):
        return False
    _require_regular(jobs_path)
    with open(jobs_path, encoding="utf-8") as f:
        try:
            jobs = json.load(f)
        except json.JSONDecodeError as err:
            raise ValueError(f"{jobs_path}: not valid JSON: {err}") from err
    listed = jobs.get("jobs") if isinstance(jobs, dict) else None
    if not isinstance(listed, list) or not all(isinstance(j, str) for j in listed):
        raise ValueError(f"{jobs_path}: /jobs: missing or not a list of run files")
    if jobs.get("complete", True) is not True:
        raise ValueError(f"{jobs_path}: /complete: {json.dumps(jobs.get('complete'))}: some jobs have no run file "
                         "(run the suite again)")
    for name in run_names:
        if name not in listed:
            raise ValueError(f"{os.path.join(path, 'runs', name)}: not a job of {jobs_path}: a stray or stale file "
                             "(remove it, or run again)")
    for name in listed:
        if name not in run_names:
            raise ValueError(f"{os.path.join(path, 'runs', name)}: missing: the results are incomplete "
                             "(run the suite again)")
    return True


def _check_job_record(record, file: str, name: str) -> None:
    """In a folder of `run`: the record is its own job's (run_file_name(snapshot.id, label)) and final."""
    snap = record.get("snapshot") if isinstance(record, dict) else None
    sid = snap.get("id") if isinstance(snap, dict) else None
    label = record.get("label") if isinstance(record, dict) else None
    if not isinstance(sid, str) or not isinstance(label, str):
        raise ValueError(f"{file}: /snapshot/id, /label: missing or not strings: not a run record of "
                         "`contactbench run`")
    if f"{sid}__{label}.json" != name:
        raise ValueError(f"{file}: /snapshot/id, /label: the record is of job {sid}__{label}.json, not of this "
                         "file: a copy or another job's record (remove it, or run again)")
    if record.get("final", True) is False:
        raise ValueError(f"{file}: /final: false: the run ended in an error to be retried, not a result "
                         "(run the suite again)")


def load_results(path: str, with_history: bool = True) -> Results:
    """Load a results folder. Raises FileNotFoundError naming the folder when it holds no runs, and
    ValueError naming the file when the folder is not a finished result (_require_finished) or a run
    file is not a regular file holding its job's record."""
    runs_dir = os.path.join(path, "runs")
    summary_path = os.path.join(path, "summary.csv")
    if not os.path.isdir(runs_dir) and not os.path.isfile(summary_path):
        raise FileNotFoundError(f"{path}: not a results folder (no runs/ and no summary.csv)")
    records: Dict[tuple, dict] = {}
    rows, hists = [], []
    names = sorted(n for n in os.listdir(runs_dir) if n.endswith(".json")) if os.path.isdir(runs_dir) else []
    run_folder = _require_finished(path, names)
    if os.path.isdir(runs_dir):
        for name in names:
            file = os.path.join(runs_dir, name)
            _require_regular(file)
            with open(file, encoding="utf-8") as f:
                try:
                    record = json.load(f)
                except json.JSONDecodeError as err:
                    raise ValueError(f"{file}: not valid JSON: {err}") from err
            if run_folder:
                _check_job_record(record, file, name)
            elif not isinstance(record, dict):
                raise ValueError(f"{file}: expected a run record (a JSON object)")
            row = flatten_run(record, file)
            row["file"] = name
            stem_label = os.path.splitext(name)[0].partition("__")[2]
            if (row["snapshot"], row["label"]) in records and stem_label and stem_label != row["label"]:
                # two runs of one solver under one label (the stress table writes "cg" for both cg
                # and cg:precond=ichol): the file name keeps them apart, as one label per run
                row["label"] = stem_label
            rows.append(row)
            records[(row["snapshot"], row["label"])] = record
            if with_history:
                h = history_frame(record, file)
                if not h.empty:
                    h.insert(0, "label", row["label"])
                    h.insert(0, "snapshot", row["snapshot"])
                    hists.append(h)
    runs = pd.DataFrame(rows)
    if os.path.isfile(summary_path):
        summary = with_current_columns(pd.read_csv(summary_path), summary_path)
        for col in _BOOL_COLUMNS:
            if col in summary.columns:
                summary[col] = summary[col].map(_to_bool)
    else:
        summary = runs[[c for c in SUMMARY_COLUMNS if c in runs.columns]].copy() if not runs.empty \
            else pd.DataFrame(columns=SUMMARY_COLUMNS)
    if runs.empty and not summary.empty:
        runs = summary.copy()   # summary-only folders still give profiles and tables
    histories = pd.concat(hists, ignore_index=True) if hists else pd.DataFrame(
        columns=["snapshot", "label"] + HISTORY_COLUMNS)
    return Results(path=path, summary=summary, runs=runs, histories=histories, records=records,
                   suite=_read_json(os.path.join(path, "suite.json")),
                   provenance=_read_json(os.path.join(path, "provenance.json")))


def _read_json(path: str) -> dict:
    if not os.path.lexists(path):
        return {}
    _require_regular(path)
    with open(path, encoding="utf-8") as f:
        return json.load(f)


def read_qpsnap_header(path: str) -> dict:
    """The JSON header of a .qpsnap file (8-byte little-endian length, then UTF-8 JSON)."""
    with open(path, "rb") as f:
        raw = f.read(8)
        if len(raw) != 8:
            raise ValueError(f"{path}: shorter than the 8-byte header length")
        (length,) = struct.unpack("<Q", raw)
        if length > 64 * 1024 * 1024:
            raise ValueError(f"{path}: header length {length} is implausible")
        text = f.read(length)
    try:
        return json.loads(text.decode("utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as err:
        raise ValueError(f"{path}: header is not UTF-8 JSON: {err}") from err


def snapshot_table(folder: str) -> pd.DataFrame:
    """One row per *.qpsnap in folder (recursively): path, n, m and the meta fields."""
    rows = []
    for root, _dirs, files in os.walk(folder):
        for name in sorted(files):
            if not name.endswith(".qpsnap"):
                continue
            file = os.path.join(root, name)
            try:
                header = read_qpsnap_header(file)
            except (OSError, ValueError):
                continue
            meta = header.get("meta", {}) or {}
            rows.append({"path": file, "name": name, "n": header.get("n"), "m": header.get("m"),
                         "scene": meta.get("scene", ""), "frame": meta.get("frame"),
                         "newton_iteration": meta.get("newton_iteration", 0), "h": meta.get("h"),
                         "vertices": meta.get("vertices"), "tets": meta.get("tets")})
    df = pd.DataFrame(rows, columns=["path", "name", "n", "m", "scene", "frame", "newton_iteration",
                                     "h", "vertices", "tets"])
    if not df.empty:
        df = df.sort_values(["frame", "newton_iteration", "name"], na_position="last").reset_index(drop=True)
    return df


def load_simulation(folder: str) -> dict:
    """A simulation output folder: {"steps": DataFrame|None, "frames": DataFrame|None, "snapshots": DataFrame}."""
    out = {"path": folder, "steps": None, "frames": None}
    for key in ("steps", "frames"):
        file = os.path.join(folder, key + ".csv")
        if os.path.isfile(file):
            out[key] = with_current_columns(pd.read_csv(file), file)
    snaps = os.path.join(folder, "snapshots")
    out["snapshots"] = snapshot_table(snaps) if os.path.isdir(snaps) else snapshot_table(folder) \
        if os.path.isdir(folder) else pd.DataFrame()
    return out
