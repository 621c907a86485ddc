// Siconos numerics' fc3d solvers on a frictional local problem, in a child process (see
// siconos_fc3d.hpp).
#include "solvers/peers/siconos_fc3d.hpp"

#include "solvers/core/types.hpp"
#include "solvers/measure/friction_error.hpp"
#include "solvers/peers/siconos_friction_driver.hpp"

#ifdef CB_HAVE_SICONOS
#include "solvers/peers/siconos_numerics_matrix.hpp"

#include <FrictionContactProblem.h>
#include <Friction_cst.h>
#include <NonSmoothDrivers.h>
#include <SolverOptions.h>
#include <fc3d_compute_error.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#endif

namespace cb {

const std::vector<std::string>& siconos_fc3d_methods()
{
    static const std::vector<std::string> methods = {"nsgs", "nsn", "prox", "admm"};
    return methods;
}

#ifndef CB_HAVE_SICONOS

bool siconos_fc3d_built() { return false; }

FrictionRun siconos_fc3d_solve(const FrictionLocal&, const std::string& method, long, double, double)
{
    throw InputError("siconos-" + method + ": not built (" + siconos_install_hint() + ")");
}

double siconos_fc3d_error(const FrictionLocal&, const Vec&)
{
    throw InputError(std::string("Siconos numerics is not built (") + siconos_install_hint() + ")");
}

#else

bool siconos_fc3d_built() { return true; }

namespace {

/// Siconos' view of the problem; q and mu are copied (Siconos takes non-const pointers).
struct SiconosProblem {
    explicit SiconosProblem(const FrictionLocal& p) : q(p.q), mu(p.mu)
    {
        problem.dimension = 3;
        problem.numberOfContacts = static_cast<int>(p.contacts());
        problem.M = numerics_triplet_matrix(p.W);
        problem.q = q.data();
        problem.mu = mu.data();
    }
    ~SiconosProblem() { NM_free(problem.M); }  // frees the matrix and its struct
    SiconosProblem(const SiconosProblem&) = delete;
    SiconosProblem& operator=(const SiconosProblem&) = delete;
    Vec q, mu;
    FrictionContactProblem problem{};
};

int fc3d_solver_id(const std::string& method)
{
    if (method == "nsgs") return SICONOS_FRICTION_3D_NSGS;
    if (method == "nsn") return SICONOS_FRICTION_3D_NSN_AC;
    if (method == "prox") return SICONOS_FRICTION_3D_PROX;
    return SICONOS_FRICTION_3D_ADMM;
}

/// One fc3d_driver call in a child, from r (Siconos' solvers start from the reaction given).
FrictionRun siconos_round(const FrictionLocal& p, const std::string& method, long max_iterations, double tol,
                          double time_limit_s, const Vec& start)
{
    const Eigen::Index n = 3 * p.contacts();
    FrictionRun run;
    run.r = start;
    auto fc3d_from_start = [&](SolverOptions* options, std::vector<double>& r) {
        SiconosProblem sp(p);
        std::copy(start.data(), start.data() + n, r.begin());
        std::vector<double> u(size_t(n), 0.0);
        return fc3d_driver(&sp.problem, r.data(), u.data(), options);
    };
    const SiconosDriverRun driven =
        run_siconos_driver(fc3d_solver_id(method), max_iterations, tol, time_limit_s, size_t(n), fc3d_from_start);
    run.seconds = driven.seconds;
    if (!driven.status.empty()) {
        run.status = driven.status;
        run.note = driven.failure;
        return run;
    }
    run.r = Eigen::Map<const Vec>(driven.values.data(), n);
    run.iterations = driven.iterations;
    run.native_error = driven.residual;
    run.note = "fc3d_driver info " + std::to_string(driven.info);
    return run;
}

}  // namespace

FrictionRun siconos_fc3d_solve(const FrictionLocal& p, const std::string& method, long max_iterations, double tol,
                               double time_limit_s)
{
    const std::vector<std::string>& methods = siconos_fc3d_methods();
    if (std::find(methods.begin(), methods.end(), method) == methods.end())
        throw InputError("siconos fc3d: unknown method '" + method + "' (nsgs, nsn, prox, admm)");
    FrictionRun run;
    run.solver = "siconos-" + method;
    run.r = Vec::Zero(3 * p.contacts());
    // Siconos stops on its error scaled by max(||q||, ||u||, ||r||), which can be far below the
    // FCLIB error (/ ||q||): on LMGC_100_PR_PerioBox ||r|| >> ||q||, and NSN stopped at 3.6e-9 of its
    // own with 2.3e-3 of FCLIB's. So it is called again from its r with its tolerance scaled by
    // the ratio seen, at most 4 rounds; iterations and times are summed.
    double siconos_tol = tol;
    std::string notes;
    for (int round = 0; round < 4; ++round) {
        const double left = time_limit_s > 0.0 ? time_limit_s - run.seconds : 0.0;
        if (time_limit_s > 0.0 && left <= 0.0) {
            run.status = "time_limit";
            break;
        }
        const long iterations_left = max_iterations - run.iterations;
        if (iterations_left <= 0) break;
        FrictionRun one = siconos_round(p, method, iterations_left, siconos_tol, left, run.r);
        run.seconds += one.seconds;
        run.iterations += one.iterations;
        char tol_text[32];
        std::snprintf(tol_text, sizeof tol_text, "%.3g", siconos_tol);
        notes += (notes.empty() ? "" : "; ") + std::string("round ") + std::to_string(round + 1) + ": tol " + tol_text +
                 ", " + one.note;
        if (!one.status.empty()) {  // the child failed: its status stands
            run.status = one.status;
            break;
        }
        if (!one.r.allFinite()) {
            if (round == 0) run.r = one.r, run.status = "diverged";
            if (round > 0) notes += " (non-finite r: the previous round's r is kept)";
            break;
        }
        const double error = fclib_relative_error(p, one.r);
        if (round > 0 && !(error < fclib_relative_error(p, run.r))) {  // a round that made it worse
            notes += " (FCLIB error " + std::to_string(error) + ": the previous round's r is kept)";
            break;
        }
        run.r = one.r;
        run.native_error = one.native_error;
        if (error <= tol) break;
        const double ratio = siconos_relative_error(p, run.r) / error;  // Siconos' error per FCLIB's
        if (!(ratio > 0.0) || !std::isfinite(ratio)) break;
        siconos_tol = std::min(0.1 * siconos_tol, tol * ratio);
        if (siconos_tol < 1e-300) break;
    }
    run.note = notes;
    run.error = run.r.allFinite() ? fclib_relative_error(p, run.r, &run.u) : INFINITY;
    if (run.status.empty())
        run.status = run.error <= tol ? "converged" : run.iterations >= max_iterations ? "max_iterations" : "stalled";
    return run;
}

double siconos_fc3d_error(const FrictionLocal& p, const Vec& r)
{
    SiconosProblem sp(p);
    Vec z = r, w = p.W * r + p.q;
    double error = 0.0;
    // Siconos' velocity is u = W r + q, given with r; `options` is only read for its flags.
    SolverOptions* options = solver_options_create(SICONOS_FRICTION_3D_NSGS);
    fc3d_compute_error(&sp.problem, z.data(), w.data(), 0.0, options, p.q.norm(), &error);
    solver_options_delete(options);
    return error;
}

#endif

}  // namespace cb
