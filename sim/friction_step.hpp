#pragma once
/// A time step with Coulomb friction (issue 48 item 5). The frictionless step is the QP
///     min 1/2 x'Ax - b'x   s.t.   J x >= c
/// (sim/integrator.hpp). With friction every contact row i gets two tangent rows T_i (an orthonormal
/// frame with its normal, the normal row's vertex weights), and the step is the Coulomb problem
///     A x = b + J_all' r,   u = J_all x - c_all,   K*_mu ∋ u + mu ||u_T|| e_n  ⊥  r ∈ K_mu,
/// where J_all stacks per contact (normal, tangent 1, tangent 2) and c_all = (c_i, T_i x_n): u_n is
/// the gap and u_T = T_i (x - x_n) the slip of the step (implicit Euler at the velocity level:
/// slip / h is the tangential velocity, and the cone law is the same for both). The reduction
///     W = J_all A^-1 J_all',   q = J_all A^-1 b - c_all,   x = A^-1 (b + J_all' r)
/// makes it FCLIB's local problem (solvers/core/friction_problem.hpp), solved by our NSGS to a
/// tolerance on FCLIB's relative natural-map error, which the harness computes itself
/// (solvers/measure/friction_error.hpp). Ref: Acary, Bremond, Huber (2018), Sec. 2; Jean (1999).
#include "sim/collision/dcd.hpp"
#include "solvers/core/friction_problem.hpp"

#include <string>
#include <vector>

namespace cb::sim {

/// The scene's "mu" and "friction_settings" (scenes/README.md).
struct FrictionSettings {
    double mu = 0.0;               ///< Coulomb coefficient of every contact; 0: the frictionless QP, unchanged
    std::string solver = "nsgs";   ///< nsgs (ours) | siconos-nsn | siconos-nsgs (Siconos' fc3d, when built)
    double tol = 1e-10;            ///< FCLIB relative error a step must reach
    long max_iterations = 100000;  ///< NSGS sweeps
    double time_limit_s = 0.0;     ///< per step; 0: none
};

/// Two unit tangents completing the unit normal n to a right-handed orthonormal frame (n, t1, t2);
/// t1 is orthogonal to the coordinate axis least aligned with n, so the frame is a fixed function of n.
void tangent_frame(const Vec3& n, Vec3& t1, Vec3& t2);

/// J_all (3m x n_dofs): row 3i is contact i's normal row, rows 3i+1 and 3i+2 its tangents, each
/// with the normal row's vertex weights (a vertex-triangle row's tangents measure the slip of
/// the vertex against the triangle's closest point).
SpMat frictional_rows(const std::vector<ContactRow>& rows, Eigen::Index n_dofs);

/// The tangent rows alone as a snapshot holds them (solvers/core/qp.hpp Friction::T): 2m x n_dofs, rows
/// 2i and 2i+1 are rows 3i+1 and 3i+2 of frictional_rows.
SpMat tangent_rows(const std::vector<ContactRow>& rows, Eigen::Index n_dofs);

/// The local problem of a step: W, q and mu (named `name` in messages), with the pieces that
/// recover x from a reaction r: x = x_free + Y r.
struct FrictionalStepProblem {
    FrictionLocal local;
    Vec x_free;         ///< A^-1 b
    Eigen::MatrixXd Y;  ///< A^-1 J_all' (n_dofs x 3m)
};

/// Builds the local problem of the step min 1/2 x'Ax - b'x with `rows` (their normal rows are J x >= c)
/// and the step's start positions x_start. Throws std::runtime_error when CHOLMOD cannot factor A.
FrictionalStepProblem frictional_step_problem(const SpMat& A, const Vec& b, const std::vector<ContactRow>& rows,
                                              const Vec& x_start, double mu, const std::string& name);

/// The step solved: positions, the NSGS run (status from FCLIB's error against settings.tol) and
/// the contacts' states at the solution.
struct FrictionalStepOutcome {
    Vec x;
    FrictionRun run;
    long contacts = 0, separated = 0, sticking = 0, sliding = 0;
    double seconds = 0;  ///< factoring A, forming W and q, NSGS and the recovery of x
};

FrictionalStepOutcome solve_frictional_step(const SpMat& A, const Vec& b, const std::vector<ContactRow>& rows,
                                            const Vec& x_start, const FrictionSettings& settings,
                                            const std::string& name);

}  // namespace cb::sim
