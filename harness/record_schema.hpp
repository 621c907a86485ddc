#pragma once
/// The names of the run record (docs/INTERFACES.md "Run record"), and the read-compatibility shim
/// for the names they replaced. The accuracy error e (docs/accuracy.md) is called `accuracy`
/// everywhere: the JSON object "accuracy" {parts, "max"}, the CSV columns `accuracy` (its max)
/// and `accuracy_solved`, the history column `accuracy`.
///
/// Old names (accepted on read for one release, with a notice on stderr once per file and name):
///   JSON "kkt_relative" {..., "max"}      -> "accuracy"
///   CSV / history column "kkt_rel"        -> "accuracy"
///   CSV column "kkt_rel_solved"           -> "accuracy_solved"
/// Nothing writes an old name.
///
/// Fields added later (nothing renamed; an older record lacks them and means the default):
///   "work_counted" (issue 41): false for an external program's run, whose work counters are
///   null; absent: true (compare reads it so).
///   "fclib_error" and "accuracy"."friction" (issue 48): only in records of problems with
///   friction (docs/accuracy.md "e for Coulomb friction"); absent: a frictionless problem.
///   "solved_problem" gains the value "frictionless" (a frictionless solver on a frictional problem,
///   or a frictional one that returned no tangential multipliers).
///   "friction" {"mu_min", "mu_max"}: only in records of problems with friction.
///   summary.csv columns fclib_error, solved_problem, mu_min, mu_max (appended; empty when absent).
#include <nlohmann/json.hpp>
#include <string>

namespace cb {

/// The current name of a CSV or history column: an old name (above) maps to its new one, with a
/// notice naming `source`; any other name comes back unchanged.
std::string current_column_name(const std::string& column, const std::string& source);

/// The accuracy object of a run record: "accuracy", else the old "kkt_relative" (with a notice
/// naming `source`), else null.
const nlohmann::json& accuracy_object(const nlohmann::json& run, const std::string& source);

/// accuracy_object(run, source)["max"], or null when absent.
nlohmann::json accuracy_max(const nlohmann::json& run, const std::string& source);

}  // namespace cb
