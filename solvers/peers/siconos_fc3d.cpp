// Siconos numerics' fc3d solvers on a frictional local problem, in a child process (see
// siconos_fc3d.hpp).
#include "solvers/peers/siconos_fc3d.hpp"

#include "solvers/friction_error.hpp"
#include "solvers/types.hpp"

#ifdef CB_HAVE_SICONOS
#include "solvers/peers/child_process.hpp"
#include "solvers/peers/siconos_numerics_matrix.hpp"
#include "solvers/stopwatch.hpp"

#include <FrictionContactProblem.h>
#include <Friction_cst.h>
#include <NonSmoothDrivers.h>
#include <SolverOptions.h>
#include <fc3d_compute_error.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
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
    throw InputError("siconos-" + method +
                     ": not built (install libsiconos-numerics-dev and reconfigure with CB_PEERS=ON)");
}

double siconos_fc3d_error(const FrictionLocal&, const Vec&)
{
    throw InputError(
        "Siconos numerics is not built (install libsiconos-numerics-dev and reconfigure with CB_PEERS=ON)");
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

struct Fc3dReport {
    int info = -1;
    int iterations = 0;
    double residual = -1.0;
};

}  // namespace

namespace {

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
    Stopwatch watch;
    watch.start();
    const ChildOutcome child = run_in_child(
        [&]() {
            SiconosProblem sp(p);
            std::vector<double> r(start.data(), start.data() + n), u(size_t(n), 0.0);
            SolverOptions* options = solver_options_create(fc3d_solver_id(method));
            options->iparam[SICONOS_IPARAM_MAX_ITER] = static_cast<int>(std::min<long>(max_iterations, 1L << 30));
            options->dparam[SICONOS_DPARAM_TOL] = tol;
            Fc3dReport report;
            report.info = fc3d_driver(&sp.problem, r.data(), u.data(), options);
            report.iterations = options->iparam[SICONOS_IPARAM_ITER_DONE];
            report.residual = options->dparam[SICONOS_DPARAM_RESIDU];
            solver_options_delete(options);
            std::vector<char> out(size_t(n) * sizeof(double) + sizeof report);
            std::memcpy(out.data(), r.data(), size_t(n) * sizeof(double));
            std::memcpy(out.data() + size_t(n) * sizeof(double), &report, sizeof report);
            return out;
        },
        watch, time_limit_s);
    watch.pause();
    run.seconds = watch.seconds();
    const size_t expected = size_t(n) * sizeof(double) + sizeof(Fc3dReport);
    if (child.timed_out || child.failed || child.bytes.size() != expected) {
        run.status = child.timed_out ? "time_limit" : "diverged";
        run.note = child.timed_out
                       ? "killed at the time limit"
                       : "Siconos child " + (child.failed ? child.failure
                                                          : "sent " + std::to_string(child.bytes.size()) +
                                                                " bytes, expected " + std::to_string(expected));
        return run;
    }
    std::memcpy(run.r.data(), child.bytes.data(), size_t(n) * sizeof(double));
    Fc3dReport report;
    std::memcpy(&report, child.bytes.data() + size_t(n) * sizeof(double), sizeof report);
    run.iterations = report.iterations;
    run.native_error = report.residual;
    run.note = "fc3d_driver info " + std::to_string(report.info);
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
