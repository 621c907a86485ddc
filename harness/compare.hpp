#pragma once
/// The regression judge between two result sets (`contactbench compare BASE NEW`). Each side is a
/// results folder (runs/*.json, as `contactbench run` writes) or a compact performance record
/// (a .csv, harness/perf_record.hpp, as the perf gate and `make baseline` write).
///
/// For each (snapshot id, label) present in BASE:
///  - missing in NEW: failure; status changed: failure;
///  - work counters (iterations, a_products, a_products_harness, cholmod_factorizations,
///    precond_applications; lower is better): on the same machine any growth is a regression
///    (they are deterministic); across machines growth beyond counter_rtol * BASE + counter_atol;
///  - a_products_harness counts the products made through solvers/linalg/a_product, whoever asked for
///    them: growth that the solver's own a_products does not show is named "uncounted";
///  - accuracy (the error e, docs/accuracy.md): regressed when accuracy(NEW) > accuracy(BASE) *
///    (1 + accuracy_rtol) and above the run's tol (files of an older version use old names, read
///    with a notice: harness/record_schema.hpp);
///  - instructions executed in the solve (callgrind, deterministic on one machine): regressed
///    when NEW > BASE * (1 + instructions_rtol); not judged across machines;
///  - wall time: the ratio of the minimum times NEW/BASE with a noise band (the sum of both
///    sides' relative spreads, median/min - 1); regressed only when the ratio exceeds
///    time_ratio_max and 1 + band, and never from a single sample per side.
/// A counter or measure absent on either side is shown and not judged, except in a compact BASE
/// (InputError: the baseline must record what it judges); a counter or the accuracy that is NaN or
/// infinite on either side is an InputError naming the side, the run and the quantity. Runs only in NEW are
/// listed as "new" and are not failures.
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace cb {

struct CompareOptions {
    double accuracy_rtol = 0.1;       ///< relative growth of the accuracy error e judged a regression (above tol)
    double instructions_rtol = 0.03;  ///< relative growth of instructions judged a regression
    double time_ratio_max = 1.5;      ///< NEW/BASE min-time ratio judged a regression (0: never judged)
    double counter_rtol = 0.25;       ///< across machines: allowed relative growth of a counter ...
    long counter_atol = 2;            ///< ... plus this many
    bool cross_machine = false;       ///< force the across-machines rules even when fingerprints agree
};

/// The compared counters, in table order.
const std::vector<std::string>& compared_counters();

/// One side of a comparison: where it came from, its runs and the machine that measured them.
struct CompareInput {
    std::string source;
    std::vector<nlohmann::json> runs;
    nlohmann::json machine = nlohmann::json::object();  ///< machine_fingerprint(); empty when unknown
    /// A compact record (CSV): as BASE, every judged quantity NEW records must be in it (an
    /// absent column or empty cell would leave that quantity unjudged); a results folder of an
    /// older binary may lack newer counters, which are then shown and not judged.
    bool compact = false;
};

/// Reads a results folder (machine from provenance.json or the runs' provenance) or a compact
/// CSV (machine from the -machine.json beside it). InputError naming the path when neither.
CompareInput read_compare_input(const std::string& path);

struct CompareRow {
    std::string snapshot, label;
    std::string base_status, new_status;
    std::string verdict;                 ///< "equal", "improved", "regressed", "status-changed", "missing", "new"
    std::vector<std::string> regressed;  ///< names of regressed quantities ("a_products", "instructions" ...)
    std::vector<std::string> improved;
    nlohmann::json base, next;  ///< compared values (counters, accuracy, instructions, time)
    double time_ratio = 0.0;    ///< NEW/BASE minimum time (0 when unknown)
    double time_band = -1.0;    ///< relative noise band of the ratio (< 0: unknown, not judged)
    bool failure() const { return verdict == "regressed" || verdict == "status-changed" || verdict == "missing"; }
    /// True when anything differs (a counter, instructions, the status), judged or not.
    bool changed() const;
};

struct CompareReport {
    std::vector<CompareRow> rows;
    long equal = 0, improved = 0, regressed = 0, status_changed = 0, missing = 0, added = 0;
    std::string base_source, new_source;
    nlohmann::json base_machine = nlohmann::json::object(), new_machine = nlohmann::json::object();
    bool cross_machine = false;
    CompareOptions options;
    bool failed() const { return regressed + status_changed + missing > 0; }
    /// The two sides, their machines, and the rules applied (stated thresholds).
    std::string header() const;
    /// Aligned, human-readable; only the rows that changed when `only_changes`.
    std::string table(bool only_changes = false) const;
    std::string verdict() const;  ///< one line: "verdict: PASS ..." or "verdict: FAIL ..."
    nlohmann::json to_json() const;
};

CompareReport compare_runs(const std::vector<nlohmann::json>& base, const std::vector<nlohmann::json>& next,
                           const CompareOptions& options = {});
/// Compares two inputs; the across-machines rules apply when both fingerprints are known and
/// differ (or options.cross_machine). `filter`: only runs whose "snapshot/label" matches this
/// regular expression (searched, ECMAScript; empty: all).
CompareReport compare_inputs(const CompareInput& base, const CompareInput& next, const CompareOptions& options = {},
                             const std::string& filter = "");
/// Reads BASE and NEW (folders or compact CSVs) and compares them (InputError when BASE has no runs).
CompareReport compare_folders(const std::string& base_dir, const std::string& new_dir,
                              const CompareOptions& options = {});

}  // namespace cb
