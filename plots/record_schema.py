"""The one name of the accuracy error in records and tables, and the read-compatibility shim for
the names it replaced (the Python twin of harness/record_schema.hpp; docs/INTERFACES.md).

The accuracy error e (docs/accuracy.md) is `accuracy` everywhere: the run record's "accuracy"
object (parts and "max"), the columns `accuracy` and `accuracy_solved` of summary.csv, of the
performance record and of stability.csv, the history column `accuracy`.

Files of the previous release are read for one release, with an OldNameWarning per file and name:
    run record "kkt_relative"                  -> "accuracy"
    column "kkt_rel" / "kkt_rel_solved"        -> "accuracy" / "accuracy_solved"
    stability.csv column "kkt" / "kkt_solved"  -> "accuracy" / "accuracy_solved"
Nothing here writes an old name.

Fields added later (nothing renamed; an older file lacks them and means the default):
    run record "work_counted" (issue 41): false for an external program's run, whose work
    counters are null; absent: true
    run record "fclib_error" and "accuracy"["friction"] (issue 48): only for a problem with
    friction; absent: a frictionless problem (fclib_error None, friction 0)
    run record "friction" {"mu_min", "mu_max"} and summary.csv columns fclib_error,
    solved_problem, mu_min, mu_max (issue 48): empty for a frictionless run
"""
from __future__ import annotations

import warnings

#: old column name -> current name (summary.csv, histories, performance records)
OLD_COLUMNS = {"kkt_rel": "accuracy", "kkt_rel_solved": "accuracy_solved"}
#: stability.csv (contactbench stress) named e `kkt` as well
OLD_STABILITY_COLUMNS = {"kkt": "accuracy", "kkt_solved": "accuracy_solved"}
#: old run-record key -> current key
OLD_KEYS = {"kkt_relative": "accuracy"}

#: added field -> what an older record that lacks it means
ADDED_FIELDS = {"work_counted": True, "fclib_error": None, "friction": None}

_told = set()


def work_counted(record: dict) -> bool:
    """False for a run whose work is not counted (a `command` run: its counters are null)."""
    return record.get("work_counted", ADDED_FIELDS["work_counted"]) is not False


class OldNameWarning(FutureWarning):
    """A file used a name that the record schema replaced (accepted until the next release)."""


def notice(source: str, old: str, new: str) -> None:
    """Warns once per (source, old name)."""
    if (source, old) in _told:
        return
    _told.add((source, old))
    warnings.warn(f"{source}: read the old name '{old}' as '{new}' (accepted until the next release; "
                  f"rewrite the file to use '{new}')", OldNameWarning, stacklevel=3)


def accuracy_of(record: dict, source: str = "run record") -> dict:
    """The "accuracy" object of a run record ({} when absent); an old record's "kkt_relative" with a warning."""
    value = record.get("accuracy")
    if value is None:
        for old, new in OLD_KEYS.items():
            if record.get(old) is not None:
                notice(source, old, new)
                value = record[old]
                break
    return value or {}


def current_column_names(columns, source: str, old_names: dict = OLD_COLUMNS) -> list:
    """The column names with old ones replaced by their current name (a warning each), unless the
    current name is there too (then the old column is left as it is)."""
    present = set(columns)
    out = []
    for column in columns:
        new = old_names.get(column)
        if new is not None and new not in present:
            notice(source, column, new)
            column = new
        out.append(column)
    return out


def with_current_columns(df, source: str, old_names: dict = OLD_COLUMNS):
    """A DataFrame whose old column names are renamed (the same frame when none is old)."""
    names = current_column_names(list(df.columns), source, old_names)
    return df if names == list(df.columns) else df.set_axis(names, axis=1)
