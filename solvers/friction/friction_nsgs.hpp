#pragma once
/// `nsgs`: our non-smooth Gauss-Seidel on a frictional local problem (solvers/core/friction_problem.hpp),
/// the frictional extension of `pgs` (which is its mu = 0, normal-only case on S = J A^-1 J').
/// Ref: Jean (1999), "The non-smooth contact dynamics method"; Acary et al. (2018), Sec. 5.
///
/// One iteration = one ascending sweep over the contacts. Contact i sees the others frozen:
///   u_i = W_ii r_i + b_i,  b_i = q_i + sum_{j != i} W_ij r_j,
/// and its one-contact problem is solved in closed form where it has one (b_in >= 0: r_i = 0,
/// take-off; the sticking r_i = -W_ii^-1 b_i inside K_mu: u_i = 0), otherwise sliding: r_i on the
/// cone's boundary against the slip direction t, r_i = r_n (1, -mu t) with u_in = 0, t found by a
/// scan of 64 angles and bisection on u_iT x t = 0 (u_iT along t), solved to rounding. The projected
/// fixed point r_i <- P_K(r_i - rho (u_i + mu ||u_iT|| e_n)), rho = 1 / lambda_max(W_ii), polishes
/// whatever remains above 1e-3 of the global error (at most `local_iterations` steps). W_ii is
/// factored by LU: Capsules-i125-1213's blocks are not symmetric (by up to 1e-3), and an LDLT,
/// which reads one triangle, made NSGS stall there at 9.9e-6. After every sweep
/// the harness's FCLIB relative error (solvers/measure/friction_error.hpp) is evaluated: the stop rule is
/// error <= tol, so `converged` means exactly what it means for every peer.
#include "solvers/core/friction_problem.hpp"

#include <Eigen/Dense>
#include <vector>

namespace cb {

/// The sweeps of nsgs on u = W r + q, for a solver that owns its loop (friction_nsgs below, and
/// `nsgs-friction` on a snapshot's exact dual, solvers/friction/nsgs_friction.hpp). A contact with mu = 0
/// is solved in closed form (r_T = 0, r_n = max(0, -b_n / W_nn): its cone is the normal ray), so
/// on a frictionless problem a sweep is pgs's (only W_nn > 0 is needed there).
class FrictionSweeps {
public:
    /// Takes W's diagonal blocks and factors them. Throws InputError("name: W: ...") when a
    /// frictional contact's block is not positive definite, or a frictionless one has W_nn <= 0.
    FrictionSweeps(const SpMat& W, const Vec& mu, const std::string& name);
    /// One ascending sweep over the contacts of r (3m): contact i sees the others frozen and its
    /// one-contact problem is solved to the squared local residual `target` (at most
    /// `local_iterations` projected steps after the closed forms).
    void sweep(const SpMat& W, const Vec& q, Vec& r, double target, long local_iterations) const;

private:
    Vec m_mu;
    std::vector<Eigen::Matrix3d> m_block;
    std::vector<Eigen::PartialPivLU<Eigen::Matrix3d>> m_factor;
    std::vector<double> m_rho;
};

struct FrictionNsgsSettings {
    double tol = 1e-8;             ///< FCLIB relative error to reach
    long max_iterations = 10000;   ///< sweeps
    long local_iterations = 1000;  ///< projected fixed-point steps per contact and sweep (cap)
    double time_limit_s = 0.0;     ///< 0: none
    const Vec* start = nullptr;    ///< r to start from (3m, finite), or null: r = 0
};

/// Starts from settings.start (e.g. MPRGP's frictionless r_n, mprgp+ica-friction) or r = 0. Throws
/// InputError when the start is not 3m finite numbers, or when a diagonal block W_ii is not
/// positive definite (a one-contact problem without a unique solution), naming the contact.
FrictionRun friction_nsgs(const FrictionLocal& problem, const FrictionNsgsSettings& settings);

}  // namespace cb
