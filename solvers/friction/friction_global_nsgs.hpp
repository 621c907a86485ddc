#pragma once
/// `nsgs` on a global frictional problem: our NSGS (friction_nsgs.hpp) on its reduced problem
/// (friction_global_reduction.hpp), v = M^-1 (H r + f) recovered from the factor of M. NSGS stops
/// on the reduced problem's error; the verdict is the global error at (r, v) (friction_error.hpp),
/// which weighs the natural map by max(||u||, ||r||) instead of ||q||. When the first has met tol
/// and the second has not, NSGS runs again from r = 0 with its tolerance scaled by their ratio
/// (at most 3 rounds; iterations and times summed, each round's tolerance in `note`).
#include "solvers/core/friction_global.hpp"
#include "solvers/friction/friction_global_reduction.hpp"
#include "solvers/friction/friction_nsgs.hpp"

namespace cb {

FrictionGlobalRun friction_nsgs_global(const FrictionGlobal& problem, const GlobalReduction& reduction,
                                       const FrictionNsgsSettings& settings);

}  // namespace cb
