#pragma once
/// The run record (docs/INTERFACES.md "Run record"): the JSON of a run that happened, built from
/// its outcome, and the record of a run that could not happen (same keys, null measures).
#include "harness/runner.hpp"
#include "solvers/core/peak_memory.hpp"

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace cb {

/// Wall times of every repeat of one run (setup, solve and their sum), in seconds.
struct RepeatTimes {
    std::vector<double> setup_s, solve_s, total_s;
};

/// The facts of a run the outcome does not hold.
struct RunFacts {
    std::string solver;
    nlohmann::json settings;  ///< effective settings, as the solver reports them
    nlohmann::json snapshot;  ///< id, path, hash, n, m, meta ... (n and m filled in when absent)
    nlohmann::json decouple;  ///< SolverProblem::decouple
    bool warm_lambda0 = false, warm_eigenvector = false;
    std::string note;  ///< the harness's remark on the returned point ("" when none)
    double tol = 0.0, accuracy_tol = 0.0;
    bool native = false, native_ok = false;  ///< stop=native was met; its residual met tol
    bool changed = false, ignores_constraints = false;
    bool frictionless = false;      ///< a frictionless solver on a frictional problem (it solved mu = 0)
    bool decouple_applied = false;  ///< the solver saw decoupled rows (they carry no friction either)
    bool frictional = false;        ///< the problem has friction (some mu > 0): the record carries fclib_error
    double mu_min = 0.0, mu_max = 0.0;  ///< the range of mu over the contacts (record "friction", when frictional)
    bool lambda_fitted = false;  ///< the multipliers measured with are a least-squares fit
    double objective_x0 = 0.0;
    long a_products_harness = 0;
    double work = 0.0;  ///< A-product equivalents (docs/work.md)
    RepeatTimes times;
    PeakMemory peak;
    nlohmann::json history;  ///< null when not recorded
};

/// The record of a run that happened (RunOutcome::record).
nlohmann::json run_record(const RunOutcome& out, const RunFacts& facts, int repeat);

/// The record of a run that could not happen (unknown solver, bad settings, unreadable snapshot):
/// every key a reader needs, with null measures and zero counters.
nlohmann::json failed_record(const std::string& solver, const std::string& label, const nlohmann::json& settings,
                             const nlohmann::json& snapshot, const std::string& status, const std::string& message,
                             double tol);

}  // namespace cb
