#pragma once
/// Siconos numerics' solvers of the global frictional problem (gfc3d, solvers/core/friction_global.hpp)
/// as peers, each run through gfc3d_driver in a forked child process (Siconos can abort):
///   nsgs  SICONOS_GLOBAL_FRICTION_3D_NSGS_WR  (reduced to the local problem, fc3d NSGS on it)
///   nsn   SICONOS_GLOBAL_FRICTION_3D_NSN_AC   (non-smooth Newton on Alart-Curnier's function)
///   admm  SICONOS_GLOBAL_FRICTION_3D_ADMM     (alternating direction method of multipliers)
///   prox  SICONOS_GLOBAL_FRICTION_3D_PROX_WR  (proximal point on the reduced problem)
/// M and H are passed as sparse (triplet) NumericsMatrix, f as Siconos' q and w as its b. Siconos
/// stops on gfc3d_compute_error, which is the harness's global_relative_error (friction_error.hpp)
/// by definition; the verdict is still the harness's own evaluation at the returned (r, v).
///
/// Compiled with or without Siconos: without it, siconos_gfc3d_built() is false and the other
/// functions throw InputError saying so.
#include "solvers/core/friction_global.hpp"
#include "solvers/core/friction_problem.hpp"

#include <string>
#include <vector>

namespace cb {

bool siconos_gfc3d_built();

/// The methods above, in that order.
const std::vector<std::string>& siconos_gfc3d_methods();

/// Starts from r = 0, v = 0. tol is Siconos' tolerance; the child is killed at time_limit_s (0: none).
FrictionGlobalRun siconos_gfc3d_solve(const FrictionGlobal& problem, const std::string& method, long max_iterations,
                                      double tol, double time_limit_s);

/// Siconos' own gfc3d_compute_error at (r, v) with norm_q = ||f||, norm_b = ||w|| (in this
/// process: it does not abort on finite input); the reference global_relative_error is tested against.
double siconos_gfc3d_error(const FrictionGlobal& problem, const Vec& r, const Vec& v);

}  // namespace cb
