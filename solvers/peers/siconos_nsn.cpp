// Siconos numerics' global nonsmooth Newton (mu = 0) in a child process (see siconos_nsn.hpp).
#include "solvers/peers/siconos_nsn.hpp"
#include "solvers/core/solve_loop.hpp"
#include "solvers/peers/child_process.hpp"
#include "solvers/peers/siconos_report.hpp"

#include <Friction_cst.h>
#include <GlobalFrictionContactProblem.h>
#include <NonSmoothDrivers.h>
#include <NumericsMatrix.h>
#include <NumericsSparseMatrix.h>
#include <SolverOptions.h>

#include <algorithm>
#include <cstring>
#include <sstream>
#include <vector>

namespace cb {

namespace {

/// Its own settings, declared once (settings.hpp SettingsTable); the common block comes first.
const SettingsTable<SiconosNsnSettings>& siconos_nsn_settings_table()
{
    static const SettingsTable<SiconosNsnSettings> table = SettingsTable<SiconosNsnSettings>();
    return table;
}

}  // namespace

SiconosNsnSettings SiconosNsnSettings::from_json(const nlohmann::json& settings)
{
    return read_settings(settings, "siconos-nsn", siconos_nsn_settings_table());
}

nlohmann::json SiconosNsnSettings::to_json() const { return write_settings(*this, siconos_nsn_settings_table()); }

namespace {

/// A sparse (triplet) NumericsMatrix; `transpose_of_rows` stores the transpose of `S`.
NumericsMatrix* numerics_matrix(const SpMat& S, Eigen::Index rows, Eigen::Index cols, bool transpose, long col_stride)
{
    NumericsMatrix* N = NM_create(NM_SPARSE, static_cast<int>(rows), static_cast<int>(cols));
    NM_triplet_alloc(N, S.nonZeros());
    N->matrix2->origin = NSM_TRIPLET;
    for (int i = 0; i < S.outerSize(); ++i)
        for (SpMat::InnerIterator it(S, i); it; ++it) {
            if (transpose)
                NM_zentry(N, static_cast<int>(it.col()), static_cast<int>(col_stride * i), it.value(), 0.0);
            else
                NM_zentry(N, i, static_cast<int>(it.col()), it.value(), 0.0);
        }
    return N;
}

/// In the child: returns v (n doubles), r (3m doubles), then a SiconosReport.
std::vector<char> run_nsn(const QpView& qp, long max_iterations, double tol)
{
    const Eigen::Index n = qp.n(), m = qp.m();
    GlobalFrictionContactProblem problem{};
    problem.dimension = 3;
    problem.numberOfContacts = static_cast<int>(m);
    problem.M = numerics_matrix(qp.A, n, n, false, 1);
    problem.H = numerics_matrix(qp.J, n, 3 * m, true, 3);  // column 3i = row i of J
    Vec q = qp.b, b = Vec::Zero(3 * m), mu = Vec::Zero(m);
    for (Eigen::Index i = 0; i < m; ++i) b[3 * i] = -qp.c[i];
    problem.q = q.data();
    problem.b = b.data();
    problem.mu = mu.data();
    problem.norm_q = -1.0;
    problem.norm_b = -1.0;
    problem.env = nullptr;
    std::vector<double> v(static_cast<size_t>(n), 0.0), r(static_cast<size_t>(3 * m), 0.0),
        u(static_cast<size_t>(3 * m), 0.0);
    for (Eigen::Index j = 0; j < n; ++j) v[static_cast<size_t>(j)] = qp.x0[j];
    SolverOptions* options = solver_options_create(SICONOS_GLOBAL_FRICTION_3D_NSN_AC);
    options->iparam[SICONOS_IPARAM_MAX_ITER] = static_cast<int>(std::min<long>(max_iterations, 1L << 30));
    options->dparam[SICONOS_DPARAM_TOL] = tol;
    SiconosReport report;
    report.info = gfc3d_driver(&problem, r.data(), u.data(), v.data(), options);
    // NSN_AC's loop test post-increments (`while (iter++ < itermax)`), so at the cap ITER_DONE is
    // one more than the Newton steps it took.
    const int cap = options->iparam[SICONOS_IPARAM_MAX_ITER];
    report.iterations = std::min(options->iparam[SICONOS_IPARAM_ITER_DONE], cap);
    report.residual = options->dparam[SICONOS_DPARAM_RESIDU];
    report.max_iterations_reached = report.info != 0 && report.iterations >= cap;
    std::vector<char> out((v.size() + r.size()) * sizeof(double) + sizeof report);
    std::memcpy(out.data(), v.data(), v.size() * sizeof(double));
    std::memcpy(out.data() + v.size() * sizeof(double), r.data(), r.size() * sizeof(double));
    std::memcpy(out.data() + (v.size() + r.size()) * sizeof(double), &report, sizeof report);
    return out;
}

}  // namespace

SolverResult SiconosNsnSolver::solve(const QpView& qp, const SolveContext& context)
{
    const SiconosNsnSettings& s = m_settings;
    const Eigen::Index n = qp.n(), m = qp.m();
    SolverResult result;
    Counters& counters = result.counters;
    result.x = qp.x0;
    result.lambda = Vec::Zero(m);
    result.info["library"] = std::string("Siconos numerics ") + CB_SICONOS_VERSION;
    result.info["history"] = "final point only (Siconos's global Newton has no iteration callback)";
    result.info["child_process"] = true;
    result.info["native_residual_definition"] = "Siconos's global friction-contact error (SICONOS_DPARAM_RESIDU)";
    SolveLoop loop("siconos-nsn", qp, s.common, context);  // no setup: the child does all the work
    loop.end_setup();
    if (!loop.inputs_finite())  // the library would abort on it (seen: Siconos's assertions)
        return loop.finish(result, loop.check(counters.iterations, false, false), "Siconos not called");
    const size_t expected = static_cast<size_t>(n + 3 * m) * sizeof(double) + sizeof(SiconosReport);
    const ChildOutcome child = run_in_child([&]() { return run_nsn(qp, s.common.max_iterations, s.common.tol); },
                                            loop.stopwatch(), s.common.time_limit_s);
    if (auto failed = finish_failed_child(child, expected, "Siconos", loop, result)) return std::move(*failed);
    const char* p = child.bytes.data();
    std::memcpy(result.x.data(), p, static_cast<size_t>(n) * sizeof(double));
    Vec r(3 * m);
    std::memcpy(r.data(), p + n * sizeof(double), static_cast<size_t>(3 * m) * sizeof(double));
    for (Eigen::Index i = 0; i < m; ++i) result.lambda[i] = r[3 * i];
    SiconosReport report;
    std::memcpy(&report, p + (n + 3 * m) * sizeof(double), sizeof report);
    counters.iterations = report.iterations;
    return finish_siconos_result(qp, loop, report, "Siconos NSN_AC", "Newton iterations", counters, result);
}

SolverEntry siconos_nsn_entry()
{
    SolverEntry e =
        solver_entry<SiconosNsnSolver>("siconos-nsn", siconos_nsn_settings_table(),
                                       std::string("peer: Siconos numerics ") + CB_SICONOS_VERSION +
                                           " global nonsmooth Newton (NSN_AC, mu = 0) on M = A, H = J' (child process)",
                                       "any J (global problem, mu = 0)");
    e.library = std::string("Siconos numerics ") + CB_SICONOS_VERSION;
    return e;
}

}  // namespace cb
