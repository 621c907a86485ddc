#include "harness/history.hpp"

#include "solvers/measure/work_units.hpp"

#include <algorithm>
#include <cmath>

namespace cb {

namespace {

/// Whether every entry is finite, at every iteration of a run: x * 0 is NaN exactly when x is not
/// finite, and a vectorised sum of those products reads the vector at memory speed (Eigen's
/// allFinite compared entry by entry: about 1 ms an iteration on a million DOFs).
bool all_finite(const Vec& v) { return (v.array() * 0.0).sum() == 0.0; }

nlohmann::json number_or_null(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(); }

}  // namespace

HistoryMonitor::HistoryMonitor(const QpView& qp, const AccuracyScale& scale, long history_max, bool record,
                               std::vector<int> kept_rows)
    : m_qp(qp), m_scale(scale), m_kept_rows(std::move(kept_rows)), m_history_max(std::max(2L, history_max)),
      m_record(record)
{
    if (m_qp.x0.size() == m_qp.n()) m_g0 = m_qp.A * m_qp.x0 - m_qp.b;
}

std::vector<std::string> HistoryMonitor::columns()
{
    return {"iteration",       "time_s", "a_products", "step",      "stationarity",    "primal",     "dual",
            "complementarity", "gap",    "accuracy",   "objective", "native_residual", "active_set", "work",
            "solve_time_s"};
}

HistoryRow HistoryMonitor::measure(long call, long iteration, StepKind step, const Vec& x, const Vec* lambda,
                                   double time_s, double solve_time_s, long a_products, double native, long active,
                                   const Vec* lambda_t)
{
    HistoryRow row;
    row.call = call;
    row.iteration = iteration;
    row.time_s = time_s;
    row.solve_time_s = solve_time_s;
    row.a_products = a_products;
    row.step = step;
    row.native_residual = native;
    row.active_set = active;
    Vec g;
    if (m_g0.size() == x.size()) {
        // F(x) - F(x0) and g = g0 + A d from differences d = x - x0: no cancellation against
        // the absolute positions, and still one product per row.
        const Vec d = x - m_qp.x0;
        const Vec ad = m_qp.A * d;
        g = m_g0 + ad;
        row.objective_change = d.dot(m_g0) + 0.5 * d.dot(ad);
        row.objective_change_terms = d.cwiseProduct(m_g0).cwiseAbs().sum() + 0.5 * d.cwiseProduct(ad).cwiseAbs().sum();
    } else {
        g = m_qp.A * x - m_qp.b;
    }
    row.objective = 0.5 * x.dot(g) - 0.5 * m_qp.b.dot(x);
    if (m_g0.size() != x.size()) {
        row.objective_change = row.objective;
        row.objective_change_terms = std::abs(row.objective);
    }
    if (lambda && !m_kept_rows.empty() && lambda->size() == static_cast<Eigen::Index>(m_kept_rows.size())) {
        Vec padded = Vec::Zero(m_qp.m());
        for (size_t k = 0; k < m_kept_rows.size(); ++k)
            padded[m_kept_rows[k]] = (*lambda)[static_cast<Eigen::Index>(k)];
        row.accuracy = accuracy_from_gradient(m_qp, m_scale, x, g, padded);
    } else if (lambda && lambda->size() == m_qp.m()) {
        row.accuracy = accuracy_from_gradient(m_qp, m_scale, x, g, *lambda, lambda_t);
    } else {
        const Vec fitted = fit_multipliers(m_qp, m_scale, x, g);
        row.accuracy = accuracy_from_gradient(m_qp, m_scale, x, g, fitted);
    }
    return row;
}

void HistoryMonitor::push(HistoryRow row)
{
    if (!std::isfinite(row.objective) || !std::isfinite(row.accuracy.max())) m_nonfinite = true;
    // Monotonicity over the feasible recorded iterates only: an infeasible start may have a
    // lower objective than the solution.
    if (std::isfinite(row.objective_change) && row.accuracy.primal <= 1e-9) {
        const double slack = 1e-12 * std::max(std::abs(row.objective_change), std::abs(m_last_feasible_change)) +
                             1e-13 * (row.objective_change_terms + m_last_feasible_terms);
        if (m_have_feasible && row.objective_change > m_last_feasible_change + slack) m_monotone = false;
        m_have_feasible = true;
        m_last_feasible_change = row.objective_change;
        m_last_feasible_terms = row.objective_change_terms;
    }
    m_rows.push_back(row);
    m_last_recorded_call = row.call;
    // One slot stays free for the final row appended by finish().
    while (static_cast<long>(m_rows.size()) > m_history_max - 1) {
        m_stride *= 2;
        std::vector<HistoryRow> kept;
        for (const auto& r : m_rows)
            if (r.call % m_stride == 0) kept.push_back(r);
        m_rows.swap(kept);
    }
}

bool HistoryMonitor::on_iteration(const IterationInfo& info)
{
    const long call = m_calls++;
    if (info.x && !all_finite(*info.x)) m_nonfinite = true;
    if (info.lambda && !all_finite(*info.lambda)) m_nonfinite = true;
    if (!std::isfinite(info.native_residual)) m_nonfinite = true;
    if (!m_record || !info.x || call % m_stride != 0) return true;
    const long a_products = info.counters ? info.counters->a_products : 0;
    HistoryRow row =
        measure(call, info.iteration, info.step, *info.x, info.lambda, info.elapsed_s, info.elapsed_s - info.setup_s,
                a_products, info.native_residual, info.active_set_size, info.lambda_t);
    row.work = work_units(a_products, info.counters ? info.counters->work_flops : 0.0, m_qp.A);
    push(row);
    return true;
}

void HistoryMonitor::finish(const Vec& x, const Vec& lambda, long iterations, double setup_s, double solve_s,
                            long a_products, double native_residual, double work_flops, const Vec* lambda_t)
{
    if (!all_finite(x) || !all_finite(lambda)) m_nonfinite = true;
    if (!m_record || x.size() != m_qp.n()) return;
    const Vec* l = lambda.size() == m_qp.m() ? &lambda : nullptr;
    if (m_last_recorded_call == m_calls - 1 && !m_rows.empty() && m_rows.back().iteration == iterations) {
        // The solver's last call was the returned point: measure it with the multipliers the
        // harness settled on, so that the last row is the run's error.
        HistoryRow& last = m_rows.back();
        const HistoryRow again = measure(last.call, last.iteration, last.step, x, l, last.time_s, last.solve_time_s,
                                         last.a_products, last.native_residual, last.active_set, lambda_t);
        last.accuracy = again.accuracy;
        last.objective = again.objective;
        return;
    }
    HistoryRow row = measure(m_calls, iterations, StepKind::FINAL, x, l, setup_s + solve_s, solve_s, a_products,
                             native_residual, -1, lambda_t);
    row.work = work_units(a_products, work_flops, m_qp.A);
    if (!std::isfinite(row.objective) || !std::isfinite(row.accuracy.max())) m_nonfinite = true;
    m_rows.push_back(row);
}

nlohmann::json HistoryMonitor::to_json() const
{
    nlohmann::json rows = nlohmann::json::array();
    for (const auto& r : m_rows) {
        rows.push_back({r.iteration, number_or_null(r.time_s), r.a_products, to_string(r.step),
                        number_or_null(r.accuracy.stationarity), number_or_null(r.accuracy.primal),
                        number_or_null(r.accuracy.dual), number_or_null(r.accuracy.complementarity),
                        number_or_null(r.accuracy.gap), number_or_null(r.accuracy.max()), number_or_null(r.objective),
                        number_or_null(r.native_residual), r.active_set, number_or_null(r.work),
                        number_or_null(r.solve_time_s)});
    }
    // time_origin: time_s counts from the start of the solver's setup (older files: solve only).
    return {{"columns", columns()},
            {"rows", rows},
            {"stride", m_stride},
            {"monitor_calls", m_calls},
            {"time_origin", "setup_start"}};
}

}  // namespace cb
