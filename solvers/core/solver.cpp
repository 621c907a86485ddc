#include "solvers/core/solver.hpp"

namespace cb {

const char* to_string(SolveStatus status)
{
    switch (status) {
    case SolveStatus::NOT_RUN:
        return "not_run";
    case SolveStatus::CONVERGED:
        return "converged";
    case SolveStatus::MAX_ITERATIONS:
        return "max_iterations";
    case SolveStatus::TIME_LIMIT:
        return "time_limit";
    case SolveStatus::STALLED:
        return "stalled";
    case SolveStatus::DIVERGED:
        return "diverged";
    case SolveStatus::INFEASIBLE:
        return "infeasible";
    case SolveStatus::INVALID_INPUT:
        return "invalid_input";
    case SolveStatus::NOT_APPLICABLE:
        return "not_applicable";
    case SolveStatus::STOPPED_BY_MONITOR:
        return "stopped_by_monitor";
    }
    return "unknown";
}

SolveStatus solve_status_from_string(const std::string& name)
{
    for (SolveStatus s : {SolveStatus::NOT_RUN, SolveStatus::CONVERGED, SolveStatus::MAX_ITERATIONS,
                          SolveStatus::TIME_LIMIT, SolveStatus::STALLED, SolveStatus::DIVERGED, SolveStatus::INFEASIBLE,
                          SolveStatus::INVALID_INPUT, SolveStatus::NOT_APPLICABLE, SolveStatus::STOPPED_BY_MONITOR})
        if (name == to_string(s)) return s;
    throw InputError("unknown solve status '" + name + "'");
}

const char* to_string(StopCriterion criterion)
{
    switch (criterion) {
    case StopCriterion::NONE:
        return "";
    case StopCriterion::ACCURACY:
        return "kkt";
    case StopCriterion::NATIVE:
        return "native";
    case StopCriterion::PROGRAM:
        return "program";
    }
    return "unknown";
}

const char* to_string(StepKind kind)
{
    switch (kind) {
    case StepKind::START:
        return "start";
    case StepKind::CG:
        return "cg";
    case StepKind::EXPANSION:
        return "expansion";
    case StepKind::PROPORTIONING:
        return "proportioning";
    case StepKind::SAFEGUARD:
        return "safeguard";
    case StepKind::PGS_SWEEP:
        return "pgs-sweep";
    case StepKind::PIVOT:
        return "pivot";
    case StepKind::OUTER:
        return "outer";
    case StepKind::FINAL:
        return "final";
    }
    return "unknown";
}

nlohmann::json Counters::to_json() const
{
    return {{"iterations", iterations},
            {"cg_steps", cg_steps},
            {"expansion_steps", expansion_steps},
            {"proportioning_steps", proportioning_steps},
            {"safeguard_steps", safeguard_steps},
            {"a_products", a_products},
            {"precond_applications", precond_applications},
            {"precond_factorizations", precond_factorizations},
            {"projections", projections},
            {"power_products", power_products},
            {"cholmod_analyses", cholmod_analyses},
            {"cholmod_factorizations", cholmod_factorizations},
            {"cholmod_solves", cholmod_solves},
            {"lcp_iterations", lcp_iterations},
            {"pgs_sweeps", pgs_sweeps},
            {"pivots", pivots},
            {"work_flops", work_flops}};
}

bool notify_monitor(const SolveContext& context, Stopwatch& watch, IterationInfo info)
{
    if (!context.monitor) return true;
    PausedScope paused(watch);
    info.elapsed_s = watch.seconds();
    return context.monitor->on_iteration(info);
}

bool notify_monitor(const SolveContext& context, Stopwatch& watch, IterationInfo& info, double setup_s,
                    void (*prepare)(void*), void* prepare_data)
{
    if (!context.monitor) return true;
    PausedScope paused(watch);
    if (prepare) {
        if (context.monitor->wants_iterate())
            prepare(prepare_data);
        else
            info.x = nullptr;  // not formed: the pointer would show a stale iterate
    }
    info.elapsed_s = watch.seconds();
    info.setup_s = setup_s;
    return context.monitor->on_iteration(info);
}

bool accuracy_converged(const QpView& qp, const AccuracyScale& scale, const Vec& x, const Vec& g, const Vec& lambda,
                        double tol)
{
    return accuracy_from_gradient(qp, scale, x, g, lambda).max() <= tol;
}

}  // namespace cb
