#pragma once
/// The one way a registry entry runs a frictional method that is not a SolveLoop solver (our local-form
/// solvers of solvers/friction/mprgp_tresca.hpp, Siconos' fc3d/gfc3d peers) on a snapshot (solvers/core/qp.hpp,
/// Friction): the contact frame, the setup inside the solver's clock, the method's own tolerance, and the harness's
/// verdict on the returned (x, lambda, lambda_t).
///
/// Frame: a snapshot with friction fields keeps them; one without (version 1) is the frictional problem
/// with mu = 0 and zero tangent rows (frictionless_frame; local forms: pin_frictionless_tangents). Such a
/// run returns no lambda_t.
///
/// Tolerance: the method is called with its own stop (FCLIB's relative error, or Siconos' global error)
/// at tol. With stop=kkt the judge is the frictional accuracy error e at the returned point: when the
/// method met its own stop but e > tol, it is called again (from its start: none of the methods takes
/// a start point here) with its tolerance scaled down by min(0.1, tol / e), at most `max_rounds`
/// rounds; iterations and times are summed and each round is in the message. With stop=native one
/// round, judged on the method's own error. Each status is SolveLoop's verdict, never the method's word.
/// The monitor is called once, at the returned point (the methods have no iteration callback here).
#include "solvers/core/friction_problem.hpp"
#include "solvers/core/qp.hpp"
#include "solvers/core/settings.hpp"
#include "solvers/core/solver.hpp"

#include <functional>
#include <string>

namespace cb {

/// One call of the method: its run (r in the local frame, 3 per contact; its error, status and note)
/// and the primal point x it gives back.
struct SnapshotFrictionRun {
    FrictionRun run;
    Vec x;
};

/// What a setup returns: the method, called with (own tolerance, iterations left, seconds left: 0
/// means none), and the counters its setup and primal solves spent so far (CHOLMOD's).
struct SnapshotFrictionMethod {
    std::function<SnapshotFrictionRun(double tol, long max_iterations, double time_limit_s)> run;
    std::function<Counters()> counters;
};

/// Builds the method on `framed` (the snapshot with a complete friction frame); may throw InputError
/// (the run ends `invalid_input` with its message).
using SnapshotFrictionSetup = std::function<SnapshotFrictionMethod(const QpView& framed)>;

struct SnapshotFrictionOptions {
    long max_contacts = 700;  ///< more contacts: not_applicable (dense 3m x 3m W, or Siconos' reduction)
    int max_rounds = 4;
    std::string native_definition;  ///< what the native residual is, for the record
};

/// The frame of a snapshot without friction fields: mu = 0 and zero tangent rows (2m x n).
Friction frictionless_frame(const QpView& qp);

/// `local` with every contact of mu = 0 whose tangent rows and columns of W are zero (a frictionless
/// frame's) given W_TT = W_nn I and q_T = 0: at mu = 0 r_T = 0 and the error ignores u_T, so the solution
/// and FCLIB's error are unchanged, and W's diagonal stays positive (Jacobi, Siconos' one-contact solvers).
FrictionLocal pin_frictionless_tangents(const FrictionLocal& local);

SolverResult solve_frictional_snapshot(const std::string& name, const QpView& qp, const CommonSettings& common,
                                       const SolveContext& context, const SnapshotFrictionOptions& options,
                                       const SnapshotFrictionSetup& setup);

}  // namespace cb
