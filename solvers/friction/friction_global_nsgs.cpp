// Our NSGS on a global frictional problem through its reduced problem (see friction_global_nsgs.hpp).
#include "solvers/friction/friction_global_nsgs.hpp"

#include "solvers/measure/friction_error.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace cb {

FrictionGlobalRun friction_nsgs_global(const FrictionGlobal& problem, const GlobalReduction& reduction,
                                       const FrictionNsgsSettings& settings)
{
    FrictionGlobalRun out;
    FrictionRun& run = out.run;
    FrictionNsgsSettings round = settings;
    std::string notes;
    double seconds = 0.0;
    long iterations = 0;
    for (int k = 0; k < 3; ++k) {
        run = friction_nsgs(reduction.local(), round);
        seconds += run.seconds;
        iterations += run.iterations;
        const double reduced = run.error;
        out.v = reduction.velocity(run.r);
        run.error = global_relative_error(problem, run.r, out.v, &run.u);
        char text[96];
        std::snprintf(text, sizeof text, "round %d: reduced tol %.3g, reduced error %.3g, global %.3g", k + 1,
                      round.tol, reduced, run.error);
        notes += (notes.empty() ? "" : "; ") + std::string(text);
        if (run.status != "converged" || run.error <= settings.tol) break;
        if (!(run.error > 0.0) || !std::isfinite(run.error)) break;
        round.tol = std::min(0.5 * round.tol, round.tol * settings.tol / run.error);
    }
    run.solver = "nsgs";
    run.seconds = seconds;
    run.iterations = iterations;
    run.note = "on the reduced problem W = H' M^-1 H (reduction not timed here); " + notes;
    if (run.status == "converged" && !(run.error <= settings.tol)) run.status = "stalled";
    return out;
}

}  // namespace cb
