#pragma once
/// A frictional contact problem in FCLIB's local (reduced) form, 3-D:
///   u = W r + q,   K*_mu ∋ u + mu ||u_T|| e_n  ⊥  r ∈ K_mu
/// for each contact i (components 3i: normal, 3i+1, 3i+2: tangents), where
/// K_mu = {r : ||r_T|| <= mu r_n} is the Coulomb cone and K*_mu its dual. It has no primal A: only
/// solvers of the reduced (dual) problem take it. Ref: FCLIB, fclib.h (struct fclib_local);
/// Acary, Bremond, Huber (2018), "On solving contact problems with Coulomb friction", Sec. 2.
#include "solvers/core/types.hpp"

#include <string>

namespace cb {

struct FrictionLocal {
    SpMat W;           ///< 3m x 3m (row-major: a contact's three rows are contiguous)
    Vec q;             ///< 3m
    Vec mu;            ///< m friction coefficients, each finite and >= 0
    std::string name;  ///< the file it came from (for reports)
    Eigen::Index contacts() const { return mu.size(); }
};

/// What a frictional solver returns. The status is the harness's verdict from the FCLIB error it
/// computes itself (solvers/measure/friction_error.hpp), never the solver's own word, which goes to `note`.
struct FrictionRun {
    std::string solver;
    std::string status;          ///< converged (error <= tol), max_iterations, time_limit, diverged
    Vec r, u;                    ///< reaction and velocity (u = W r + q recomputed by the harness)
    long iterations = 0;         ///< sweeps (NSGS) or Newton steps (NSN)
    double seconds = 0.0;        ///< the solver's wall time (a peer's: the child's, fork included)
    double error = 0.0;          ///< FCLIB relative natural-map error at r, computed by the harness
    double native_error = -1.0;  ///< the solver's own error estimate (-1: none)
    std::string note;
};

}  // namespace cb
