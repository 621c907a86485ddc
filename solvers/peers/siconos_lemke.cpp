// Siconos numerics' Lemke on the dual LCP, in a child process (see siconos_lemke.hpp).
#include "solvers/peers/siconos_lemke.hpp"
#include "solvers/dual_lcp.hpp"
#include "solvers/peers/child_process.hpp"
#include "solvers/peers/siconos_report.hpp"
#include "solvers/solve_loop.hpp"

#include <LCP_Solvers.h>
#include <LinearComplementarityProblem.h>
#include <NonSmoothDrivers.h>
#include <NumericsMatrix.h>
#include <SolverOptions.h>
#include <lcp_cst.h>

#include <cstring>
#include <sstream>
#include <vector>

namespace cb {

SiconosLemkeSettings SiconosLemkeSettings::from_json(const nlohmann::json& settings)
{
    SettingsReader reader(settings, "siconos-lemke");
    SiconosLemkeSettings s;
    s.common = reader.common();
    s.max_rows = reader.integer("max_rows", s.max_rows, 0);
    reader.finish();
    return s;
}

nlohmann::json SiconosLemkeSettings::to_json() const
{
    nlohmann::json j = common.to_json();
    j["max_rows"] = max_rows;
    return j;
}

namespace {

/// What the child sends back through the pipe after the lambda values.
/// Runs Lemke on (W, q) (in the child); returns lambda (m doubles) then a SiconosReport.
std::vector<char> run_lemke(Eigen::MatrixXd& W, Vec& q, long max_iterations, double tol)
{
    const int m = static_cast<int>(q.size());
    NumericsMatrix* M = NM_new();
    M->storageType = NM_DENSE;
    M->size0 = m;
    M->size1 = m;
    M->matrix0 = W.data();  // column-major, as Siconos expects
    LinearComplementarityProblem problem{m, M, q.data()};
    std::vector<double> z(static_cast<size_t>(m), 0.0), w(static_cast<size_t>(m), 0.0);
    SolverOptions* options = solver_options_create(SICONOS_LCP_LEMKE);
    options->iparam[SICONOS_IPARAM_MAX_ITER] = static_cast<int>(std::min<long>(max_iterations, 1L << 30));
    options->dparam[SICONOS_DPARAM_TOL] = tol;
    SiconosReport report;
    report.info = linearComplementarity_driver(&problem, z.data(), w.data(), options);
    report.iterations = options->iparam[SICONOS_IPARAM_ITER_DONE];
    report.residual = options->dparam[SICONOS_DPARAM_RESIDU];
    // Lemke's info is 1 both at the cap and on a ray (a nonpositive pivot column); the count tells them apart.
    report.max_iterations_reached = report.info != 0 && report.iterations >= options->iparam[SICONOS_IPARAM_MAX_ITER];
    report.ray_termination = report.info != 0 && !report.max_iterations_reached;
    std::vector<char> out(z.size() * sizeof(double) + sizeof report);
    std::memcpy(out.data(), z.data(), z.size() * sizeof(double));
    std::memcpy(out.data() + z.size() * sizeof(double), &report, sizeof report);
    return out;
}

}  // namespace

SolverResult SiconosLemkeSolver::solve(const QpView& qp, const SolveContext& context)
{
    const SiconosLemkeSettings& s = m_settings;
    const Eigen::Index m = qp.m();
    SolverResult result;
    Counters& counters = result.counters;
    result.x = qp.x0;
    result.lambda = Vec::Zero(m);
    result.info["library"] = std::string("Siconos numerics ") + CB_SICONOS_VERSION;
    result.info["history"] = "final point only (Siconos's Lemke has no iteration callback)";
    result.info["child_process"] = true;
    result.info["native_residual_definition"] = "Siconos's LCP error (SICONOS_DPARAM_RESIDU)";
    if (m > s.max_rows) {
        result.status = SolveStatus::NOT_APPLICABLE;
        result.message = "siconos-lemke: m = " + std::to_string(m) +
                         " rows exceeds max_rows = " + std::to_string(s.max_rows) +
                         " (W = J A^-1 J' is dense m x m); raise max_rows to allow it";
        return result;
    }
    SolveLoop loop("siconos-lemke", qp, s.common, context);
    DualLcp dual;
    std::string error;
    if (!dual.form(qp, counters, error))
        return loop.finish(result, SolveStatus::INVALID_INPUT, "", "siconos-lemke: " + error);
    Eigen::MatrixXd& W = dual.W();
    Vec& q = dual.q();
    if (!loop.end_setup()) return loop.finish(result, SolveStatus::TIME_LIMIT, "", loop.time_limit_message());
    if (m == 0) {  // Siconos asserts on an empty LCP (it aborts the process: seen in the child)
        result.x = dual.unconstrained();
        const Vec g = qp.A * result.x - qp.b;
        ++counters.a_products;
        const bool ok = accuracy_converged(qp, accuracy_scale(qp), result.x, g, result.lambda, s.common.tol);
        return loop.finish(result, ok ? SolveStatus::CONVERGED : SolveStatus::STALLED, ok ? "kkt" : "",
                           "siconos-lemke: no constraints: x = A^-1 b (Siconos not called)");
    }
    const size_t expected = static_cast<size_t>(m) * sizeof(double) + sizeof(SiconosReport);
    const ChildOutcome child = run_in_child([&]() { return run_lemke(W, q, s.common.max_iterations, s.common.tol); },
                                            loop.stopwatch(), s.common.time_limit_s);
    const std::vector<char>& bytes = child.bytes;

    auto primal = [&]() { result.x = dual.primal(qp, result.lambda, counters); };
    if (child.timed_out) {
        return loop.finish(result, SolveStatus::TIME_LIMIT, "",
                           loop.time_limit_message() + "; the child process was killed");
    }
    if (child.failed || bytes.size() != expected) {
        result.info["crashed"] = true;
        std::ostringstream msg;
        msg << "siconos-lemke: the Siconos child process " << (child.failed ? child.failure : "sent") << " ("
            << bytes.size() << " of " << expected << " bytes received)";
        return loop.finish(result, SolveStatus::DIVERGED, "", msg.str());
    }
    result.info["crashed"] = false;
    std::memcpy(result.lambda.data(), bytes.data(), static_cast<size_t>(m) * sizeof(double));
    SiconosReport report;
    std::memcpy(&report, bytes.data() + static_cast<size_t>(m) * sizeof(double), sizeof report);
    counters.iterations = report.iterations;
    counters.pivots = report.iterations;
    counters.lcp_iterations = report.iterations;
    primal();                         // x from lambda, before the final measure
    result.setup_s = loop.setup_s();  // the final monitor call's stamp
    result.solve_s = loop.solve_s();
    finish_siconos_result(qp, s.common, context, report, "siconos-lemke: Siconos Lemke", "pivots", counters, result);
    return loop.finish(result, result.status, result.criterion);
}

SolverEntry siconos_lemke_entry()
{
    SolverEntry e;
    e.library = std::string("Siconos numerics ") + CB_SICONOS_VERSION;
    e.make = [](const nlohmann::json& settings) -> std::unique_ptr<Solver> {
        return std::make_unique<SiconosLemkeSolver>(SiconosLemkeSettings::from_json(settings));
    };
    e.description = std::string("peer: Siconos numerics ") + CB_SICONOS_VERSION +
                    " Lemke on the dual LCP W = J A^-1 J' (CHOLMOD, dense; child process)";
    e.settings = {{"max_rows", "4000", "refuse (not_applicable) problems with more rows of J (W is dense m x m)"}};
    return e;
}

}  // namespace cb
