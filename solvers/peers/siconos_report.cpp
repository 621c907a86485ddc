#include "solvers/peers/siconos_report.hpp"

#include "solvers/a_product.hpp"
#include "solvers/accuracy.hpp"

#include <sstream>

namespace cb {

void finish_siconos_result(const QpView& qp, const CommonSettings& common, const SolveContext& context,
                           const SiconosReport& report, const std::string& what, const std::string& steps,
                           Counters& counters, SolverResult& result)
{
    result.iterations = report.iterations;
    result.native_residual = report.residual;
    result.info["siconos_info"] = report.info;

    if (context.monitor) {  // the final point only, stamped with the solver's time (setup included)
        IterationInfo info{report.iterations, StepKind::FINAL, &result.x,       &result.lambda, report.residual, -1,
                           &counters,         result.setup_s + result.solve_s, result.setup_s};
        context.monitor->on_iteration(info);
    }
    const Vec g = a_product(qp.A, result.x) - qp.b;
    ++counters.a_products;
    const bool finite = result.x.allFinite() && result.lambda.allFinite();
    std::ostringstream msg;
    msg << what << " returned info = " << report.info << " (" << (report.info == 0 ? "solved" : "failed") << ") after "
        << report.iterations << " " << steps << ", error " << report.residual;
    if (!finite) {
        result.status = SolveStatus::DIVERGED;
    } else if (common.stop == StopRule::NATIVE
                   ? (report.info == 0 && report.residual <= common.tol)
                   : accuracy_converged(qp, accuracy_scale(qp), result.x, g, result.lambda, common.tol)) {
        result.status = SolveStatus::CONVERGED;
        result.criterion = common.stop == StopRule::NATIVE ? "native" : "kkt";
    } else if (report.max_iterations_reached) {
        result.status = SolveStatus::MAX_ITERATIONS;
    } else {
        result.status = SolveStatus::STALLED;
        if (report.ray_termination)
            msg << "; ray termination: Jx >= c may have no solution, or the pivoting lost accuracy (no "
                   "certificate, so not reported as infeasible)";
        msg << "; the accuracy error at its point is above tol";
    }
    if (report.ray_termination) result.info["ray_termination"] = true;
    result.message = msg.str();
}

}  // namespace cb
