// The shared solve of the dual-LCP peers (see dual_lcp_peer.hpp).
#include "solvers/peers/dual_lcp_peer.hpp"
#include "solvers/core/solve_loop.hpp"
#include "solvers/linalg/dual_lcp.hpp"
#include "solvers/peers/child_process.hpp"

#include <cstring>
#include <limits>
#include <sstream>

namespace cb {

std::vector<char> encode_child_reply(const double* lambda, size_t m, const SiconosReport& report)
{
    std::vector<char> out(m * sizeof(double) + sizeof report);
    std::memcpy(out.data(), lambda, m * sizeof(double));
    std::memcpy(out.data() + m * sizeof(double), &report, sizeof report);
    return out;
}

SolverResult solve_dual_lcp_peer(const QpView& qp, const SolveContext& context, const CommonSettings& common,
                                 const DualLcpPeer& peer, SolverResult result)
{
    const Eigen::Index m = qp.m();
    Counters& counters = result.counters;
    result.x = qp.x0;
    result.lambda = Vec::Zero(m);
    result.info["child_process"] = true;
    if (m > peer.max_rows) {
        result.status = SolveStatus::NOT_APPLICABLE;
        result.message = peer.name + ": m = " + std::to_string(m) +
                         " rows exceeds max_rows = " + std::to_string(peer.max_rows) +
                         " (W = J A^-1 J' is dense m x m); raise max_rows to allow it";
        return result;
    }
    SolveLoop loop(peer.name, qp, common, context);
    DualLcp dual;
    std::string error;
    if (!dual.form(qp, counters, error))
        return loop.finish(result, SolveStatus::INVALID_INPUT, peer.name + ": " + error);
    if (!loop.end_setup()) return loop.finish(result, SolveStatus::TIME_LIMIT);
    if (!loop.inputs_finite())  // the library would abort on it (seen: Siconos's assertions)
        return loop.finish(result, loop.check(counters.iterations, false, false), peer.library + " not called");
    if (m == 0) {  // both libraries assert on an empty LCP (an abort of the process, seen in the child)
        result.x = dual.unconstrained();
        const Vec g = qp.A * result.x - qp.b;
        ++counters.a_products;
        const SolveStatus status = loop.verdict(result.x.allFinite(), std::numeric_limits<double>::infinity(), [&] {
            return accuracy_from_gradient(qp, accuracy_scale(qp), result.x, g, result.lambda).max();
        });
        return loop.finish(result, status, "no constraints: x = A^-1 b (" + peer.library + " not called)");
    }
    const size_t expected = static_cast<size_t>(m) * sizeof(double) + sizeof(SiconosReport);
    const ChildOutcome child =
        run_in_child([&]() { return peer.run(dual.matrix(), dual.q()); }, loop.stopwatch(), common.time_limit_s);
    const std::vector<char>& bytes = child.bytes;
    if (auto failed = finish_failed_child(child, expected, peer.library, loop, result)) return std::move(*failed);
    std::memcpy(result.lambda.data(), bytes.data(), static_cast<size_t>(m) * sizeof(double));
    SiconosReport report;
    std::memcpy(&report, bytes.data() + static_cast<size_t>(m) * sizeof(double), sizeof report);
    counters.iterations = report.iterations;
    counters.lcp_iterations = report.iterations;
    if (peer.steps_are_pivots) counters.pivots = report.iterations;
    if (peer.residual_from_lcp)  // on the W the parent kept
        report.residual =
            result.lambda.cwiseMin(dual.matrix() * result.lambda + dual.q()).norm() / (1.0 + dual.q().norm());
    result.x = dual.primal(qp, result.lambda, counters);  // x from lambda, before the final measure
    return finish_siconos_result(qp, loop, report, peer.method, peer.steps, counters, result);
}

}  // namespace cb
