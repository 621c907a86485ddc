#include "solvers/core/solve_loop.hpp"

#include <algorithm>
#include <limits>
#include <sstream>

namespace cb {

SolveLoop::SolveLoop(std::string solver, const QpView& qp, const CommonSettings& common, const SolveContext& context)
    : m_solver(std::move(solver)), m_qp(qp), m_time_limit_s(common.time_limit_s),
      m_max_iterations(common.max_iterations), m_tol(common.tol), m_stop(common.stop), m_context(context)
{
    m_watch.start();
}

bool SolveLoop::end_setup()
{
    if (!m_setup_done) {
        m_setup_s = elapsed_s();
        m_setup_done = true;
    }
    return !(m_time_limit_s > 0.0 && m_setup_s >= m_time_limit_s);
}

void SolveLoop::setup_phase(const char* name)
{
    if (m_setup_done) return;
    const double now = elapsed_s();
    m_phases.emplace_back(name, now - m_phase_mark);
    m_phase_mark = now;
}

double SolveLoop::setup_phase_s(const std::string& name) const
{
    double s = 0.0;
    for (const auto& [phase, seconds] : m_phases)
        if (phase == name) s += seconds;
    return s;
}

SolveStatus SolveLoop::check(long iterations, bool finite, bool converged)
{
    if (!finite) return decide(SolveStatus::DIVERGED);
    if (converged) return decide(SolveStatus::CONVERGED);
    return limit_status(iterations);
}

SolveStatus SolveLoop::limit_status(long iterations)
{
    if (iterations >= m_max_iterations) return decide(SolveStatus::MAX_ITERATIONS);
    if (time_up()) return decide(SolveStatus::TIME_LIMIT);
    return SolveStatus::NOT_RUN;
}

std::string SolveLoop::time_limit_reason() const
{
    std::ostringstream msg;
    msg << "time limit of " << m_time_limit_s << " s reached ";
    if (in_setup() || m_setup_s >= m_time_limit_s)
        msg << "during setup (after " << setup_s() << " s of setup)";
    else
        msg << "(setup " << setup_s() << " s + solve " << solve_s() << " s)";
    return msg.str();
}

bool SolveLoop::owns(SolveStatus status) const
{
    switch (status) {
    case SolveStatus::CONVERGED:
    case SolveStatus::MAX_ITERATIONS:
    case SolveStatus::TIME_LIMIT:
    case SolveStatus::STOPPED_BY_MONITOR:
        return true;
    case SolveStatus::DIVERGED:  // only when its finiteness check fired (not a breakdown)
    case SolveStatus::STALLED:   // only when a verdict found the rule unmet
        return m_decided == status;
    default:
        return false;
    }
}

std::string SolveLoop::standard_reason(SolveStatus status) const
{
    if (!owns(status)) return std::string();  // the solver's own word: no stream built for it
    const char* measure = m_stop == StopRule::NATIVE ? "native residual " : "accuracy error ";
    std::ostringstream msg;
    switch (status) {
    case SolveStatus::CONVERGED:
        if (m_met_value == -std::numeric_limits<double>::infinity())  // a library's yes/no test
            msg << "converged: the library's own test met tol " << m_tol;
        else
            msg << "converged: " << measure << m_met_value << " <= tol " << m_tol;
        break;
    case SolveStatus::MAX_ITERATIONS:
        msg << "iteration cap " << m_max_iterations << " reached";
        break;
    case SolveStatus::TIME_LIMIT:
        msg << time_limit_reason();
        break;
    case SolveStatus::STOPPED_BY_MONITOR:
        msg << "stopped by the monitor";
        break;
    case SolveStatus::DIVERGED:
        msg << "non-finite iterate";
        break;
    case SolveStatus::STALLED:
        msg << "the stop rule does not hold at the returned point: " << measure << m_unmet_value << " > tol " << m_tol;
        break;
    default:
        break;
    }
    return msg.str();
}

SolverResult SolveLoop::finish(SolverResult& result, SolveStatus status, const std::string& detail) const
{
    result.status = status;
    result.criterion = status != SolveStatus::CONVERGED
                           ? StopCriterion::NONE
                           : (m_stop == StopRule::NATIVE ? StopCriterion::NATIVE : StopCriterion::ACCURACY);
    const std::string reason = standard_reason(status);
    if (!reason.empty())
        result.message = m_solver + ": " + reason + (detail.empty() ? "" : "; " + detail);
    else if (!detail.empty())
        result.message = detail;
    result.iterations = result.counters.iterations;
    result.setup_s = setup_s();
    result.solve_s = solve_s();
    if (!m_phases.empty()) {
        nlohmann::json phases = nlohmann::json::object();
        double covered = 0.0;
        for (const auto& [phase, seconds] : m_phases) {
            phases[phase] = phases.value(phase, 0.0) + seconds;
            covered += seconds;
        }
        phases["other"] = std::max(0.0, result.setup_s - covered);
        result.info["setup_phases_s"] = phases;
    }
    if (result.x.size() == 0 && m_qp.n() > 0) result.x = m_qp.x0;
    if (result.lambda.size() == 0 && m_qp.m() > 0) result.lambda = Vec::Zero(m_qp.m());
    return std::move(result);
}

}  // namespace cb
