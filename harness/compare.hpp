#pragma once
/// The regression judge between two results folders (`contactbench compare BASE NEW`).
///
/// For each (snapshot id, label) present in BASE:
///  - missing in NEW: failure;
///  - status changed: failure;
///  - counters iterations, a_products, cholmod_factorizations, precond_applications compared
///    exactly (deterministic; lower is better): higher in NEW is a regression;
///  - KKT: regressed when kkt_rel(NEW) > kkt_rel(BASE) * (1 + kkt_rtol) and above the run's tol;
///  - time: NEW/BASE total time ratio (min..max of the per-repeat ratios when repeat > 1),
///    reported, never judged (timings are not deterministic).
/// Runs only in NEW are listed as "new" and are not failures.
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace cb {

struct CompareOptions {
    double kkt_rtol = 0.1;
};

/// The exactly compared counters, in table order.
const std::vector<std::string>& compared_counters();

struct CompareRow {
    std::string snapshot, label;
    std::string base_status, new_status;
    std::string verdict;                   ///< "equal", "improved", "regressed", "status-changed", "missing", "new"
    std::vector<std::string> regressed;    ///< names of regressed quantities ("a_products", "kkt_rel" ...)
    std::vector<std::string> improved;
    nlohmann::json base, next;             ///< compared values (counters, kkt_rel, tol, time)
    double time_ratio = 0.0;               ///< NEW/BASE total time (0 when unknown)
    double time_ratio_min = 0.0, time_ratio_max = 0.0;
    bool failure() const { return verdict == "regressed" || verdict == "status-changed" || verdict == "missing"; }
};

struct CompareReport {
    std::vector<CompareRow> rows;
    long equal = 0, improved = 0, regressed = 0, status_changed = 0, missing = 0, added = 0;
    bool failed() const { return regressed + status_changed + missing > 0; }
    std::string table() const;    ///< aligned, human-readable
    std::string verdict() const;  ///< one line: "verdict: PASS ..." or "verdict: FAIL ..."
    nlohmann::json to_json() const;
};

CompareReport compare_runs(const std::vector<nlohmann::json>& base, const std::vector<nlohmann::json>& next,
                           const CompareOptions& options = {});
/// Reads BASE/runs/*.json and NEW/runs/*.json (InputError when a folder has no runs).
CompareReport compare_folders(const std::string& base_dir, const std::string& new_dir,
                              const CompareOptions& options = {});

} // namespace cb
