#include "solvers/solve_loop.hpp"

#include <sstream>

namespace cb {

SolveLoop::SolveLoop(std::string solver, const QpView& qp, const CommonSettings& common, const SolveContext& context)
    : m_solver(std::move(solver)), m_qp(qp), m_time_limit_s(common.time_limit_s),
      m_max_iterations(common.max_iterations), m_context(context)
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

SolveStatus SolveLoop::limit_status(long iterations) const
{
    if (iterations >= m_max_iterations) return SolveStatus::MAX_ITERATIONS;
    if (time_up()) return SolveStatus::TIME_LIMIT;
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

SolverResult SolveLoop::finish(SolverResult& result, SolveStatus status, std::string criterion,
                               std::string message) const
{
    result.status = status;
    result.criterion = std::move(criterion);
    if (!message.empty()) result.message = std::move(message);
    result.iterations = result.counters.iterations;
    result.setup_s = setup_s();
    result.solve_s = solve_s();
    if (result.x.size() == 0 && m_qp.n() > 0) result.x = m_qp.x0;
    if (result.lambda.size() == 0 && m_qp.m() > 0) result.lambda = Vec::Zero(m_qp.m());
    return std::move(result);
}

}  // namespace cb
