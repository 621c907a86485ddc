#include "solvers/peers/siconos_report.hpp"

#include "solvers/linalg/a_product.hpp"
#include "solvers/measure/accuracy.hpp"

#include <limits>
#include <sstream>

namespace cb {

SolverResult finish_siconos_result(const QpView& qp, SolveLoop& loop, const SiconosReport& report,
                                   const std::string& what, const std::string& steps, Counters& counters,
                                   SolverResult& result, const std::string& extra)
{
    result.iterations = report.iterations;
    result.native_residual = report.residual;
    result.info["siconos_info"] = report.info;
    // the final point only, stamped with the solver's time (setup included)
    loop.notify({report.iterations, StepKind::FINAL, &result.x, &result.lambda, report.residual, -1, &counters});
    const Vec g = a_product(qp.A, result.x) - qp.b;
    ++counters.a_products;
    // The library's residual counts for stop=native only when it also says it solved the problem.
    const double native = report.info == 0 ? report.residual : std::numeric_limits<double>::infinity();
    const SolveStatus status = loop.verdict(
        result.x.allFinite() && result.lambda.allFinite(), native,
        [&] { return accuracy_from_gradient(qp, accuracy_scale(qp), result.x, g, result.lambda).max(); },
        report.max_iterations_reached ? SolveStatus::MAX_ITERATIONS : SolveStatus::STALLED);
    std::ostringstream msg;
    msg << what << " returned info = " << report.info << " (" << (report.info == 0 ? "solved" : "failed") << ") after "
        << report.iterations << " " << steps << ", error " << report.residual;
    if (status == SolveStatus::STALLED && report.ray_termination)
        msg << "; ray termination: Jx >= c may have no solution, or the pivoting lost accuracy (no "
               "certificate, so not reported as infeasible)";
    if (report.ray_termination) result.info["ray_termination"] = true;
    msg << extra;
    return loop.finish(result, status, msg.str());
}

}  // namespace cb
