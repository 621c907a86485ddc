#pragma once
/// MPRGP-based solvers of a frictional local problem (solvers/core/friction_problem.hpp), each judged by
/// the FCLIB relative error the harness computes (solvers/measure/friction_error.hpp), as `nsgs` is.
///
/// `mprgp-tresca-fp`: Coulomb friction as a fixed point on Tresca's slip bounds (Dostal et al.,
/// CMAME 2012): outer iteration k fixes s = mu r_n^k and solves the Tresca problem
///     min 1/2 r'W r + q'r   s.t.  r_n >= 0,  ||r_T|| <= s   (per contact)
/// by MPGP, the MPRGP engine (solvers/mprgp/mprgp_engine.hpp) over the Tresca set (solvers/mprgp/tresca_set.hpp)
/// with Jacobi preconditioning, warm-started from r^k, to a tolerance that tightens with the outer
/// FCLIB error e_k; it stops when the FCLIB error at r^{k+1} is <= tol. Starting from r = 0, the first Tresca solve is
/// frictionless; at mu = 0 it is the only one and its iterates are mprgp-box's on (W_NN, q_N)
/// (tests/solvers/test_mprgp_tresca.cpp). The dual QP needs W symmetric positive semidefinite. A W that is not
/// symmetric (Capsules': by 3.4e-4) is split W = S + K, S = (W + W')/2: each Tresca QP is S's, with the skew part K r^k
/// of the outer iterate moved into q (lag_skew, the default), so the fixed point is the given problem's; with lag_skew
/// off K is dropped and the fixed point is S's problem, not the given one. Either way the note says so and the status
/// reads the FCLIB error on the given W (never `converged` for S's problem). An S that is not positive semidefinite is
/// refused (`not_applicable`). Sizes: W dense-checked for definiteness up to 3000 rows; beyond, the check is the
/// engine's own (p'Wp <= 0 ends the solve, `diverged`).
///
/// `mprgp+ica-friction` (the paper's suggestion after OTSG09): frictionless mprgp-box on (W_NN, q_N),
/// then our `nsgs` started from (r_n, 0).
#include "solvers/core/friction_problem.hpp"
#include "solvers/core/solver.hpp"
#include "solvers/friction/friction_nsgs.hpp"

#include <string>

namespace cb {

struct MprgpTrescaSettings {
    double tol = 1e-8;            ///< FCLIB relative error to reach
    long max_outer = 200;         ///< fixed-point iterations (Tresca solves)
    long max_inner = 100000;      ///< MPRGP iterations per Tresca solve
    double inner_fraction = 0.5;  ///< a Tresca solve stops at ||phi + beta|| <= max(inner_fraction tol,
    double inner_relative = 0.1;  ///< inner_relative e_k) ||q||, e_k the FCLIB error at the outer iterate
                                  ///< (inner_relative 0, or every mu = 0: inner_fraction tol alone)
    double time_limit_s = 0.0;    ///< 0: none (setup and every solve included)
    double gamma = 1.0;           ///< proportioning constant Gamma
    long power_max = 100;         ///< power-method products for alpha_bar = 2 / (1.01 ||W||)
    double power_tol = 1e-8;      ///< the power method's relative change
    bool lag_skew = true;         ///< W not symmetric: its skew part at the outer iterate in q (else dropped)
    Monitor* monitor = nullptr;   ///< sees every inner MPRGP iterate (x = r, 3m); tests only
};

/// What mprgp-tresca-fp did beside its FrictionRun (iterations there: all inner MPRGP iterations).
struct MprgpTrescaRun {
    FrictionRun run;
    long outer = 0;            ///< Tresca solves
    Counters counters;         ///< the inner solves' counters, summed
    bool symmetrised = false;  ///< W is not symmetric beyond rounding (> 1e-12): the QP is (W + W')/2's
    double asymmetry = 0.0;    ///< ||W - W'||_F / ||W||_F
    double alpha_bar = 0.0;
    double setup_s = 0.0;  ///< symmetry, definiteness check, D^-1 and the power method (in run.seconds)
};

MprgpTrescaRun mprgp_tresca_fp(const FrictionLocal& problem, const MprgpTrescaSettings& settings);

struct MprgpIcaFrictionSettings {
    double tol = 1e-8;          ///< FCLIB relative error nsgs stops at
    double normal_tol = 1e-10;  ///< mprgp-box's native tolerance on (W_NN, q_N), relative to ||q_N||
    long max_mprgp = 100000;    ///< mprgp-box iterations
    long max_sweeps = 10000;    ///< nsgs sweeps
    double time_limit_s = 0.0;  ///< 0: none (for each of the two stages)
};

/// The FrictionRun's iterations are nsgs's sweeps; the note gives mprgp-box's status and iterations.
FrictionRun mprgp_ica_friction(const FrictionLocal& problem, const MprgpIcaFrictionSettings& settings);

}  // namespace cb
