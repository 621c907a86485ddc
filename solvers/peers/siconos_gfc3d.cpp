// Siconos numerics' gfc3d solvers on a global frictional problem, in a child process (see
// siconos_gfc3d.hpp).
#include "solvers/peers/siconos_gfc3d.hpp"

#include "solvers/friction_error.hpp"

#ifdef CB_HAVE_SICONOS
#include "solvers/peers/child_process.hpp"
#include "solvers/peers/siconos_numerics_matrix.hpp"
#include "solvers/stopwatch.hpp"

#include <Friction_cst.h>
#include <GlobalFrictionContactProblem.h>
#include <NonSmoothDrivers.h>
#include <SolverOptions.h>
#include <gfc3d_compute_error.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#endif

namespace cb {

const std::vector<std::string>& siconos_gfc3d_methods()
{
    static const std::vector<std::string> methods = {"nsgs", "nsn", "admm", "prox"};
    return methods;
}

#ifndef CB_HAVE_SICONOS

bool siconos_gfc3d_built() { return false; }

FrictionGlobalRun siconos_gfc3d_solve(const FrictionGlobal&, const std::string& method, long, double, double)
{
    throw InputError("siconos-" + method +
                     ": not built (install libsiconos-numerics-dev and reconfigure with CB_PEERS=ON)");
}

double siconos_gfc3d_error(const FrictionGlobal&, const Vec&, const Vec&)
{
    throw InputError(
        "Siconos numerics is not built (install libsiconos-numerics-dev and reconfigure with CB_PEERS=ON)");
}

#else

bool siconos_gfc3d_built() { return true; }

namespace {

/// Siconos' view of the problem; f, w and mu are copied (Siconos takes non-const pointers).
struct SiconosGlobalProblem {
    explicit SiconosGlobalProblem(const FrictionGlobal& p) : f(p.f), w(p.w), mu(p.mu)
    {
        problem.dimension = 3;
        problem.numberOfContacts = static_cast<int>(p.contacts());
        problem.M = numerics_triplet_matrix(p.M);
        problem.H = numerics_triplet_matrix(p.H);
        problem.q = f.data();
        problem.b = w.data();
        problem.mu = mu.data();
        problem.norm_q = f.norm();
        problem.norm_b = w.norm();
    }
    ~SiconosGlobalProblem()
    {
        NM_free(problem.M);
        NM_free(problem.H);
    }
    SiconosGlobalProblem(const SiconosGlobalProblem&) = delete;
    SiconosGlobalProblem& operator=(const SiconosGlobalProblem&) = delete;
    Vec f, w, mu;
    GlobalFrictionContactProblem problem{};
};

struct Gfc3dReport {
    int info = -1;
    int iterations = 0;
    double residual = -1.0;
};

int solver_id(const std::string& method)
{
    if (method == "nsgs") return SICONOS_GLOBAL_FRICTION_3D_NSGS_WR;
    if (method == "nsn") return SICONOS_GLOBAL_FRICTION_3D_NSN_AC;
    if (method == "admm") return SICONOS_GLOBAL_FRICTION_3D_ADMM;
    if (method == "prox") return SICONOS_GLOBAL_FRICTION_3D_PROX_WR;
    throw InputError("siconos gfc3d: unknown method '" + method + "' (nsgs, nsn, admm, prox)");
}

}  // namespace

FrictionGlobalRun siconos_gfc3d_solve(const FrictionGlobal& p, const std::string& method, long max_iterations,
                                      double tol, double time_limit_s)
{
    const int id = solver_id(method);
    const Eigen::Index m3 = 3 * p.contacts(), n = p.unknowns();
    FrictionGlobalRun out;
    FrictionRun& run = out.run;
    run.solver = "siconos-" + method;
    run.r = Vec::Zero(m3);
    out.v = Vec::Zero(n);
    Stopwatch watch;
    watch.start();
    const size_t expected = size_t(m3 + n) * sizeof(double) + sizeof(Gfc3dReport);
    const ChildOutcome child = run_in_child(
        [&]() {
            SiconosGlobalProblem sp(p);
            std::vector<double> r(size_t(m3), 0.0), u(size_t(m3), 0.0), v(size_t(n), 0.0);
            SolverOptions* options = solver_options_create(id);
            options->iparam[SICONOS_IPARAM_MAX_ITER] = static_cast<int>(std::min<long>(max_iterations, 1L << 30));
            options->dparam[SICONOS_DPARAM_TOL] = tol;
            Gfc3dReport report;
            report.info = gfc3d_driver(&sp.problem, r.data(), u.data(), v.data(), options);
            report.iterations = options->iparam[SICONOS_IPARAM_ITER_DONE];
            report.residual = options->dparam[SICONOS_DPARAM_RESIDU];
            std::vector<char> bytes(expected);
            std::memcpy(bytes.data(), r.data(), size_t(m3) * sizeof(double));
            std::memcpy(bytes.data() + size_t(m3) * sizeof(double), v.data(), size_t(n) * sizeof(double));
            std::memcpy(bytes.data() + size_t(m3 + n) * sizeof(double), &report, sizeof report);
            return bytes;  // the child exits without freeing: Siconos' options may hold its workspaces
        },
        watch, time_limit_s);
    watch.pause();
    run.seconds = watch.seconds();
    if (child.timed_out || child.failed || child.bytes.size() != expected) {
        run.status = child.timed_out ? "time_limit" : "diverged";
        run.note = child.timed_out
                       ? "killed at the time limit"
                       : "Siconos child " + (child.failed ? child.failure
                                                          : "sent " + std::to_string(child.bytes.size()) +
                                                                " bytes, expected " + std::to_string(expected));
        run.error = global_relative_error(p, run.r, out.v, &run.u);  // at the start, as the local peers
        return out;
    }
    std::memcpy(run.r.data(), child.bytes.data(), size_t(m3) * sizeof(double));
    std::memcpy(out.v.data(), child.bytes.data() + size_t(m3) * sizeof(double), size_t(n) * sizeof(double));
    Gfc3dReport report;
    std::memcpy(&report, child.bytes.data() + size_t(m3 + n) * sizeof(double), sizeof report);
    run.iterations = report.iterations;
    run.native_error = report.residual;
    run.note = "gfc3d_driver info " + std::to_string(report.info);
    const bool finite = run.r.allFinite() && out.v.allFinite();
    run.error = finite ? global_relative_error(p, run.r, out.v, &run.u) : INFINITY;
    run.status = !finite                            ? "diverged"
                 : run.error <= tol                 ? "converged"
                 : run.iterations >= max_iterations ? "max_iterations"
                                                    : "stalled";
    return out;
}

double siconos_gfc3d_error(const FrictionGlobal& p, const Vec& r, const Vec& v)
{
    SiconosGlobalProblem sp(p);
    Vec z = r, u = Vec::Zero(3 * p.contacts()), gv = v;
    double error = 0.0;
    SolverOptions* options = solver_options_create(SICONOS_GLOBAL_FRICTION_3D_NSGS_WR);
    gfc3d_compute_error(&sp.problem, z.data(), u.data(), gv.data(), 0.0, options, p.f.norm(), p.w.norm(), &error);
    solver_options_delete(options);
    return error;
}

#endif

}  // namespace cb
