#pragma once
/// FCLIB's relative natural-map error (solvers/measure/friction_error.hpp) of a frictional snapshot, a QP
/// with Coulomb friction (solvers/core/qp.hpp Friction: FCLIB's global form with M = A, f = b,
/// H' = J_all, w = -c_all). Contact i's local velocity and reaction are
///   u_i = (J_i x - c_i, T_2i x - cT_2i, T_2i+1 x - cT_2i+1),   r_i = (lambda_i, lambda_T,2i, lambda_T,2i+1),
/// and the error is ||F_nat(r)||_2 / ||q||_2 with F_nat the local form's, per contact
///   F_nat(r)_i = r_i - P_K_mu_i(r_i - (u_i + mu_i ||u_iT|| e_n)),
/// q = J_all A^-1 b - c_all. Why that q: stationarity A x - b = J_all' r gives x = A^-1 (b + J_all' r),
/// hence u = J_all x - c_all = W r + q with W = J_all A^-1 J_all': (W, q, mu) is the snapshot's
/// local problem, the reduction Acary et al. (2018) apply to global problems. At a point whose x
/// comes from r (every dual solver's: nsgs-friction, pgs) this is the local form's error to
/// rounding (tests/solvers/test_friction_snapshot_error.cpp); at another point it reads the
/// Coulomb law of (u(x), r) alone, and the frictional e's stationarity part judges the rest.
#include "solvers/core/qp.hpp"

namespace cb {

/// ||q||_2, q = J_all A^-1 b - c_all: one sparse LDL' of A (Eigen's SimplicialLDLT). NaN when the
/// problem has no friction fields or A cannot be factored.
double friction_local_q_norm(const QpView& qp);

/// ||F_nat(r)||_2 at (x, r) as above; lambda (m normal multipliers) or lambda_t (2m tangential) of
/// another size counts as 0. NaN when the problem has no friction fields or x has not size n.
double friction_natural_map_norm(const QpView& qp, const Vec& x, const Vec& lambda, const Vec& lambda_t);

/// The relative error: friction_natural_map_norm / norm_q, absolute when norm_q <= DBL_EPSILON
/// (as fclib_relative_error does).
double friction_snapshot_error(const QpView& qp, const Vec& x, const Vec& lambda, const Vec& lambda_t, double norm_q);

/// J_all (3m x n): contact i's normal row J_i then its tangent rows T_2i, T_2i+1 (FCLIB's local
/// frame, normal first), and c_all (3m) likewise from c and cT (0 where cT is absent).
SpMat contact_frame_rows(const QpView& qp, Vec* c_all = nullptr);

}  // namespace cb
