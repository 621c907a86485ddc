#pragma once
/// The recording monitor: at each recorded solver iteration it measures the iterate with the
/// accuracy measure (docs/accuracy.md) on the ORIGINAL QP while the solver's stopwatch is paused
/// (a solver that saw fewer rows has its multipliers padded with 0 on the rows it did not see).
///
/// Stride: every k-th monitor call is recorded; k starts at 1 and doubles whenever the history
/// would exceed `history_max` rows (rows that are not on the new stride are dropped; the first
/// row is always kept, and finish() appends the returned point as the last row).
/// Monotone: the objective must be non-increasing over the recorded iterates that are feasible
/// to 1e-9 of the scene size (the measure's primal part <= 1e-9). It is compared as the change
/// from the start, F(x) - F(x0) = d'(g0 + 1/2 A d) with d = x - x0 and g0 = A x0 - b, not as
/// F(x) itself: F at absolute positions is dominated by 1/2 x'Ax (a body 100 m from the origin),
/// so its rounding and a slack relative to |F| hid or invented changes of the size of a
/// solver's last steps. The slack per comparison is 1e-12 of the larger |change| plus 1e-13 of
/// the sum of the absolute terms of the two dot products (their rounding bound).
/// Time: time_s is the solver's time since the start of its setup (monitor excluded), so the
/// first row of every history sits at the solver's setup time; solve_time_s is the same stamp
/// without the setup (the iterations only).
#include "solvers/core/solver.hpp"
#include "solvers/measure/accuracy.hpp"

#include <nlohmann/json.hpp>
#include <vector>

namespace cb {

/// One recorded row (the columns of the results file's "history").
struct HistoryRow {
    long call = 0;  ///< index of the monitor call (0-based); drives the stride
    long iteration = 0;
    double time_s = 0.0;        ///< since the start of the solver's setup (setup included)
    double solve_time_s = 0.0;  ///< time_s - setup_s: the iterations only
    long a_products = 0;
    StepKind step = StepKind::START;
    AccuracyParts accuracy;  ///< the measure's parts; accuracy.max() is the error e (column accuracy)
    double objective = 0.0;
    double objective_change = 0.0;        ///< F(x) - F(x0) in difference form (the monotonicity check)
    double objective_change_terms = 0.0;  ///< sum of |terms| of that difference (its rounding scale)
    double native_residual = 0.0;
    long active_set = -1;
    double work = 0.0;  ///< A-product equivalents so far (solvers/measure/work_units.hpp)
};

class HistoryMonitor : public Monitor {
public:
    /// @param qp         the original QP (what every row is measured on)
    /// @param kept_rows  rows of qp the solver saw, in its order (empty: all of them)
    /// @param record     false: only nonfinite detection on every call (no history rows)
    HistoryMonitor(const QpView& qp, const AccuracyScale& scale, long history_max, bool record = true,
                   std::vector<int> kept_rows = {});

    bool on_iteration(const IterationInfo& info) override;
    /// True when the next call is on the stride (and recording is on): the only calls it measures.
    bool wants_iterate() const override { return m_record && m_calls % m_stride == 0; }
    /// Appends the returned point (x, lambda) as the final row unless the last call was recorded;
    /// its time_s is setup_s + solve_s, its solve_time_s solve_s.
    void finish(const Vec& x, const Vec& lambda, long iterations, double setup_s, double solve_s, long a_products,
                double native_residual, double work_flops = 0.0, const Vec* lambda_t = nullptr);

    bool nonfinite() const { return m_nonfinite; }
    bool monotone() const { return m_monotone; }
    long stride() const { return m_stride; }
    long calls() const { return m_calls; }
    const std::vector<HistoryRow>& rows() const { return m_rows; }

    static std::vector<std::string> columns();
    /// {"columns": [...], "rows": [[...], ...]}; nonfinite numbers become null.
    nlohmann::json to_json() const;

private:
    HistoryRow measure(long call, long iteration, StepKind step, const Vec& x, const Vec* lambda, double time_s,
                       double solve_time_s, long a_products, double native, long active, const Vec* lambda_t = nullptr);
    void push(HistoryRow row);

    QpView m_qp;
    AccuracyScale m_scale;
    std::vector<int> m_kept_rows;
    long m_history_max;
    bool m_record;
    long m_stride = 1;
    long m_calls = 0;
    long m_last_recorded_call = -1;
    bool m_nonfinite = false;
    bool m_monotone = true;
    bool m_have_feasible = false;
    double m_last_feasible_change = 0.0;
    double m_last_feasible_terms = 0.0;
    Vec m_g0;  ///< A x0 - b of the original QP
    std::vector<HistoryRow> m_rows;
};

}  // namespace cb
