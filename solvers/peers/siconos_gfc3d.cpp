// Siconos numerics' gfc3d solvers on a global frictional problem, in a child process (see
// siconos_gfc3d.hpp).
#include "solvers/peers/siconos_gfc3d.hpp"

#include "solvers/measure/friction_error.hpp"
#include "solvers/peers/siconos_friction_driver.hpp"

#ifdef CB_HAVE_SICONOS
#include "solvers/peers/siconos_numerics_matrix.hpp"

#include <Friction_cst.h>
#include <GlobalFrictionContactProblem.h>
#include <NonSmoothDrivers.h>
#include <SolverOptions.h>
#include <gfc3d_compute_error.h>

#include <algorithm>
#include <cmath>
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
    throw InputError("siconos-" + method + ": not built (" + siconos_install_hint() + ")");
}

double siconos_gfc3d_error(const FrictionGlobal&, const Vec&, const Vec&)
{
    throw InputError(std::string("Siconos numerics is not built (") + siconos_install_hint() + ")");
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
    auto gfc3d_from_zero = [&](SolverOptions* options, std::vector<double>& rv) {  // r, then v
        SiconosGlobalProblem sp(p);
        std::vector<double> u(size_t(m3), 0.0);
        return gfc3d_driver(&sp.problem, rv.data(), u.data(), rv.data() + m3, options);
    };
    const SiconosDriverRun driven =
        run_siconos_driver(id, max_iterations, tol, time_limit_s, size_t(m3 + n), gfc3d_from_zero);
    run.seconds = driven.seconds;
    if (!driven.status.empty()) {
        run.status = driven.status;
        run.note = driven.failure;
        run.error = global_relative_error(p, run.r, out.v, &run.u);  // at the start, as the local peers
        return out;
    }
    run.r = Eigen::Map<const Vec>(driven.values.data(), m3);
    out.v = Eigen::Map<const Vec>(driven.values.data() + m3, n);
    run.iterations = driven.iterations;
    run.native_error = driven.residual;
    run.note = "gfc3d_driver info " + std::to_string(driven.info);
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
