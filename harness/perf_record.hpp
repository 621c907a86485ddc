#pragma once
/// The compact performance record: one CSV row per (snapshot, label) run with the deterministic
/// work of the solve (status, counters, harness-counted A-products, instructions executed in the
/// solve) and, when the perf gate measured them, wall-time statistics. The committed CI baseline
/// is such a file (results/baselines/ci.csv); the machine it was measured on is described by a
/// fingerprint beside it (results/baselines/ci-machine.json). tools/perf_gate.py writes both.
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace cb {

/// Every column a record may have, in file order (old column names are read through
/// harness/record_schema.hpp). snapshot, label and status are required; an
/// empty cell means "not measured".
const std::vector<std::string>& perf_record_columns();

/// At most this many runs in a record (a run costs ~4 kB in memory as a record: 400 MB at most;
/// the largest suite, fig6 over every frame, has a few thousand), and this many characters a line.
constexpr std::size_t MAX_PERF_RECORD_RUNS = 100000;
constexpr std::size_t MAX_PERF_RECORD_LINE = 4096;

/// Reads a compact CSV into run records shaped like results JSON (label, snapshot.id, status,
/// iterations, counters{...}, accuracy.max, tol, instructions, time{min_total_s, noise,
/// samples}, work_counted: false where its cell is 0). InputError naming the file, line and
/// column on anything malformed: an unknown or repeated column, a cell that is not a count or a
/// finite number, too many runs or a long line.
std::vector<nlohmann::json> read_perf_record(const std::string& csv_path);

/// The fingerprint file beside a record: "dir/ci.csv" -> "dir/ci-machine.json".
std::string machine_file_for(const std::string& csv_path);

/// The facts that make instruction counts and rounding comparable: CPU model, BLAS library,
/// SuiteSparse/CHOLMOD version and compiler, taken from a provenance JSON (missing: "unknown").
nlohmann::json machine_fingerprint(const nlohmann::json& provenance);

/// One line: "AMD EPYC, openblas-pthread, SuiteSparse 5.12.0 (CHOLMOD 3.0.14), gcc 12.2.0".
std::string describe_machine(const nlohmann::json& fingerprint);

}  // namespace cb
