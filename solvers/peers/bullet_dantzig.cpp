// Bullet's Dantzig LCP pivoting on the dual LCP, in a child process (see bullet_dantzig.hpp).
#include "solvers/peers/bullet_dantzig.hpp"
#include "solvers/dual_lcp.hpp"
#include "solvers/peers/child_process.hpp"
#include "solvers/peers/siconos_report.hpp"
#include "solvers/solve_loop.hpp"

#include <BulletDynamics/MLCPSolvers/btDantzigLCP.h>

#include <cstring>
#include <sstream>
#include <vector>

namespace cb {

BulletDantzigSettings BulletDantzigSettings::from_json(const nlohmann::json& settings)
{
    SettingsReader reader(settings, "bullet-dantzig");
    BulletDantzigSettings s;
    s.common = reader.common();
    s.max_rows = reader.integer("max_rows", s.max_rows, 0);
    reader.finish();
    return s;
}

nlohmann::json BulletDantzigSettings::to_json() const
{
    nlohmann::json j = common.to_json();
    j["max_rows"] = max_rows;
    return j;
}

namespace {

static_assert(sizeof(btScalar) == sizeof(double), "bullet-dantzig needs Bullet's double-precision build");

/// In the child: Bullet's A x = b + w with lo = 0, hi = inf is our w = W lambda + q with b = -q
/// (Bullet overwrites A and b: the child's copies). Returns lambda (m doubles), then a
/// SiconosReport: info 0 when Bullet returned true with a finite lambda (btDantzigSolver's own
/// test), iterations = m (the driving indexes; Bullet does not count the pivots within each).
std::vector<char> run_dantzig(Eigen::MatrixXd& W, const Vec& q)
{
    const int m = static_cast<int>(q.size());
    std::vector<double> x(static_cast<size_t>(m), 0.0), b(static_cast<size_t>(m)), w(static_cast<size_t>(m), 0.0),
        lo(static_cast<size_t>(m), 0.0), hi(static_cast<size_t>(m), BT_INFINITY);
    for (int i = 0; i < m; ++i) b[static_cast<size_t>(i)] = -q[i];
    std::vector<int> findex(static_cast<size_t>(m), -1);  // no friction dependencies
    btDantzigScratchMemory scratch;
    // W is symmetric, so its column-major storage is the row-major m x m matrix Bullet expects.
    const bool ok =
        btSolveDantzigLCP(m, W.data(), x.data(), b.data(), w.data(), 0, lo.data(), hi.data(), findex.data(), scratch);
    SiconosReport report;
    report.info = ok && Eigen::Map<const Vec>(x.data(), m).allFinite() ? 0 : 1;
    report.iterations = m;
    std::vector<char> out(x.size() * sizeof(double) + sizeof report);
    std::memcpy(out.data(), x.data(), x.size() * sizeof(double));
    std::memcpy(out.data() + x.size() * sizeof(double), &report, sizeof report);
    return out;
}

}  // namespace

SolverResult BulletDantzigSolver::solve(const QpView& qp, const SolveContext& context)
{
    const BulletDantzigSettings& s = m_settings;
    const Eigen::Index m = qp.m();
    SolverResult result;
    Counters& counters = result.counters;
    result.x = qp.x0;
    result.lambda = Vec::Zero(m);
    result.info["library"] = std::string("Bullet ") + CB_BULLET_VERSION;
    result.info["history"] = "final point only (Bullet's Dantzig pivoting has no iteration callback)";
    result.info["child_process"] = true;
    result.info["native_residual_definition"] = "||min(lambda, W lambda + q)||_2 / (1 + ||q||_2) on the dual LCP";
    result.info["not_passed"] = "tol and max_iterations (Dantzig's method takes neither; tol is the harness's verdict)";
    if (m > s.max_rows) {
        result.status = SolveStatus::NOT_APPLICABLE;
        result.message = "bullet-dantzig: m = " + std::to_string(m) +
                         " rows exceeds max_rows = " + std::to_string(s.max_rows) +
                         " (W = J A^-1 J' is dense m x m); raise max_rows to allow it";
        return result;
    }
    SolveLoop loop("bullet-dantzig", qp, s.common, context);
    DualLcp dual;
    std::string error;
    if (!dual.form(qp, counters, error))
        return loop.finish(result, SolveStatus::INVALID_INPUT, "", "bullet-dantzig: " + error);
    if (!loop.end_setup()) return loop.finish(result, SolveStatus::TIME_LIMIT, "", loop.time_limit_message());
    if (m == 0) {  // btSolveDantzigLCP asserts n > 0
        result.x = dual.unconstrained();
        const Vec g = qp.A * result.x - qp.b;
        ++counters.a_products;
        const bool ok = accuracy_converged(qp, accuracy_scale(qp), result.x, g, result.lambda, s.common.tol);
        return loop.finish(result, ok ? SolveStatus::CONVERGED : SolveStatus::STALLED, ok ? "kkt" : "",
                           "bullet-dantzig: no constraints: x = A^-1 b (Bullet not called)");
    }
    const size_t expected = static_cast<size_t>(m) * sizeof(double) + sizeof(SiconosReport);
    const ChildOutcome child =
        run_in_child([&]() { return run_dantzig(dual.W(), dual.q()); }, loop.stopwatch(), s.common.time_limit_s);
    const std::vector<char>& bytes = child.bytes;
    if (child.timed_out)
        return loop.finish(result, SolveStatus::TIME_LIMIT, "",
                           loop.time_limit_message() + "; the child process was killed");
    if (child.failed || bytes.size() != expected) {
        result.info["crashed"] = true;
        std::ostringstream msg;
        msg << "bullet-dantzig: the Bullet child process " << (child.failed ? child.failure : "sent") << " ("
            << bytes.size() << " of " << expected << " bytes received)";
        return loop.finish(result, SolveStatus::DIVERGED, "", msg.str());
    }
    result.info["crashed"] = false;
    std::memcpy(result.lambda.data(), bytes.data(), static_cast<size_t>(m) * sizeof(double));
    SiconosReport report;
    std::memcpy(&report, bytes.data() + static_cast<size_t>(m) * sizeof(double), sizeof report);
    counters.iterations = report.iterations;
    counters.lcp_iterations = report.iterations;
    // Bullet reports no error of its own: the LCP's natural residual, on the W the parent kept.
    report.residual = result.lambda.cwiseMin(dual.W() * result.lambda + dual.q()).norm() / (1.0 + dual.q().norm());
    result.x = dual.primal(qp, result.lambda, counters);  // x from lambda, before the final measure
    result.setup_s = loop.setup_s();                      // the final monitor call's stamp
    result.solve_s = loop.solve_s();
    finish_siconos_result(qp, s.common, context, report, "bullet-dantzig: Bullet btSolveDantzigLCP",
                          "driving indexes (m: Bullet counts neither its pivots nor where it stopped)", counters,
                          result);
    return loop.finish(result, result.status, result.criterion);
}

SolverEntry bullet_dantzig_entry()
{
    SolverEntry e;
    e.library = std::string("Bullet ") + CB_BULLET_VERSION;
    e.make = [](const nlohmann::json& settings) -> std::unique_ptr<Solver> {
        return std::make_unique<BulletDantzigSolver>(BulletDantzigSettings::from_json(settings));
    };
    e.description = std::string("peer: Bullet ") + CB_BULLET_VERSION +
                    " Dantzig pivoting (btDantzigSolver's LCP) on the dual LCP W = J A^-1 J' (CHOLMOD, dense; "
                    "child process)";
    e.settings = {{"max_rows", "4000", "refuse (not_applicable) problems with more rows of J (W is dense m x m)"}};
    return e;
}

}  // namespace cb
