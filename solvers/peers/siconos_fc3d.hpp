#pragma once
/// Siconos numerics' solvers of the frictional local problem (fc3d) as peers: `siconos-nsgs`
/// (SICONOS_FRICTION_3D_NSGS, its default one-contact solver), `siconos-nsn`
/// (SICONOS_FRICTION_3D_NSN_AC, the non-smooth Newton on Alart-Curnier's function), `siconos-prox`
/// (SICONOS_FRICTION_3D_PROX, proximal point around NSN) and `siconos-admm`
/// (SICONOS_FRICTION_3D_ADMM), each run
/// through fc3d_driver in a forked child process (Siconos can abort), like the QP peers. W is
/// passed as a sparse (triplet) NumericsMatrix. Siconos stops on its own error (fc3d_compute_error
/// or a cheaper estimate); the verdict is the harness's FCLIB error at the returned r.
///
/// Compiled with or without Siconos: without it, siconos_fc3d_built() is false and the other
/// functions throw InputError saying so.
#include "solvers/core/friction_problem.hpp"

#include <string>
#include <vector>

namespace cb {

bool siconos_fc3d_built();

/// The methods above: nsgs, nsn, prox, admm.
const std::vector<std::string>& siconos_fc3d_methods();

/// method one of siconos_fc3d_methods(); tol is Siconos' own tolerance (its relative error), max_iterations its
/// cap; the child is killed at time_limit_s (0: none). Starts from r = 0. Siconos' own stop is
/// on its scaling of the error (friction_error.hpp); while the FCLIB error is above tol, it is
/// called again from its r with a tolerance scaled down by the ratio of the two (at most 4
/// rounds; iterations and times summed, each round's tolerance in `note`).
FrictionRun siconos_fc3d_solve(const FrictionLocal& problem, const std::string& method, long max_iterations, double tol,
                               double time_limit_s);

/// Siconos' own fc3d_compute_error at r with norm ||q||_2 (in this process: it does not abort on
/// finite input); the reference our fclib_relative_error is tested against.
double siconos_fc3d_error(const FrictionLocal& problem, const Vec& r);

}  // namespace cb
