#pragma once
/// The harness's yardstick applied to a point written by any program: the accuracy measure of
/// docs/accuracy.md on the snapshot's QP at (x, lambda), exactly as `solve` measures a run
/// (measure_point), the verdict at tol, the objective and its gap to a cached reference. With
/// the run's record (`solve --json`, a suite's runs/*.json) the run's status is rebuilt too,
/// including `solved_relaxation` and `unconfirmed`, which need the solver's own word.
///
/// On a frictional snapshot the point is judged on the frictional problem only when it carries its
/// tangential multipliers (SolutionPoint::lambda_t); without them it is judged on the frictionless
/// relaxation (mu = 0), which the judgement names (`relaxation`): its verdict is then at best
/// `solved_relaxation`, never `converged`.
#include "problems/solution_io.hpp"
#include "solvers/core/qp.hpp"
#include "solvers/measure/accuracy.hpp"

#include <nlohmann/json.hpp>
#include <string>

namespace cb {

struct JudgeOptions {
    double tol = 0.0;               ///< > 0: the tolerance of the verdict; else the record's accuracy_tol, else 1e-6
    nlohmann::json record;          ///< the run's record, or null
    std::string record_path;        ///< names the record in messages
    std::string snapshot_hash;      ///< of the snapshot file (checked against the record's)
    bool look_up_reference = true;  ///< read a cached reference (never computes one)
};

struct Judgement {
    AccuracyScale scale;
    AccuracyParts accuracy;  ///< e on the snapshot's QP at (x, lambda)
    Vec lambda;              ///< the multipliers the measure used
    bool lambda_fitted = false;
    double tol = 0.0;
    bool meets_tol = false;    ///< e <= tol: the verdict `converged` of the point (`solved_relaxation` if relaxation)
    bool relaxation = false;   ///< a frictional snapshot judged without lambda_t: e is the frictionless relaxation's
    bool frictional = false;   ///< the snapshot has friction (some mu > 0)
    double fclib_error = 0.0;  ///< FCLIB's relative error at (x, lambda, lambda_t); NaN unless judged with friction
    double objective = 0.0, violation = 0.0;
    std::string status;             ///< the run's status, only with a record ("" otherwise)
    AccuracyParts accuracy_solved;  ///< with a record of a changed problem: e on the problem it solved
    bool have_solved = false;
    nlohmann::json reference;  ///< the cached reference, or null
    double energy_gap = 0.0;   ///< |F - F*| / (d_ref l^2), NaN without a reference
    nlohmann::json to_json() const;
};

/// Judges `point` on `qp`. InputError naming the record and field when the record is not a run
/// record of this snapshot.
Judgement judge_point(const Qp& qp, const SolutionPoint& point, const JudgeOptions& options);

}  // namespace cb
