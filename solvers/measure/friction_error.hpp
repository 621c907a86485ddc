#pragma once
/// FCLIB's relative natural-map error of a frictional local problem (solvers/core/friction_problem.hpp),
/// the measure of Acary, Bremond, Huber (2018) and of Siconos' fc3d_compute_error:
///   F_nat(r)_i = r_i - P_{K_mu_i}( r_i - (u_i + mu_i ||u_iT|| e_n) ),   u = W r + q,
///   error = ||F_nat(r)||_2 / ||q||_2   (absolute when ||q||_2 <= DBL_EPSILON, as Siconos does).
/// F_nat(r) = 0 exactly at a solution (De Saxce's modified velocity makes the natural map of the
/// Coulomb problem a projection onto the second-order cone). Computed here, by the harness, so
/// that no solver reports its own accuracy.
///
/// Siconos numerics 4.4's fc3d_compute_error, called with norm = ||q||, divides the same
/// ||F_nat(r)|| by max(||q||, ||u||, ||r||) instead (measured: tests/solvers/test_friction_error.cpp),
/// so it reads smaller than Acary et al.'s ratio wherever ||u|| or ||r|| exceeds ||q||. Both are given: the paper's
/// (fclib_relative_error, the one our tables report) and Siconos' (siconos_relative_error, which
/// the test matches to 1e-12 against the library; the two share the numerator bit for bit).
#include "solvers/core/friction_global.hpp"
#include "solvers/core/friction_problem.hpp"

namespace cb {

/// Projects the 3-vector r = (r_n, r_t1, r_t2) onto K_mu = {||r_T|| <= mu r_n} in place
/// (Euclidean projection onto the second-order cone of aperture atan(mu)).
void project_on_coulomb_cone(double* r, double mu);

/// ||F_nat||_2 at given r and u (3m each), per contact with mu.
double natural_map_norm_at(const Vec& r, const Vec& u, const Vec& mu);

/// ||F_nat(r)||_2 (absolute); fills u = W r + q when `u` is given.
double natural_map_norm(const FrictionLocal& problem, const Vec& r, Vec* u = nullptr);

/// The relative error above: natural_map_norm / ||q|| (or absolute when ||q|| <= DBL_EPSILON).
double fclib_relative_error(const FrictionLocal& problem, const Vec& r, Vec* u = nullptr);

/// Siconos 4.4's scaling: natural_map_norm / max(||q||, ||u||, ||r||) (absolute when <= DBL_EPSILON).
double siconos_relative_error(const FrictionLocal& problem, const Vec& r);

/// FCLIB's relative error of the global problem (friction_global.hpp) at (r, v), as Siconos 4.4's
/// gfc3d_compute_error defines it (with norm_q = ||f||), the error FCLIB's global benchmarks and
/// every gfc3d solver report:
///   ||f + H r - M v|| / max(||f||, ||M v||, ||H r||)      (equilibrium; each ratio absolute when its
/// + ||F_nat(r; u)|| / max(||u||, ||r||),  u = H' v + w     scale <= DBL_EPSILON)
/// Fills u when given. The reduced problem's error (fclib_relative_error on W, q of
/// friction_global_reduction.hpp, / ||q||) is the other number reported beside it.
double global_relative_error(const FrictionGlobal& problem, const Vec& r, const Vec& v, Vec* u = nullptr);

}  // namespace cb
