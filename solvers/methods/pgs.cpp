// Ref: Li et al., CGF 2015, eq. (2) (the dual LCP of the contact QP); ALGORITHMS.md §7.
#include "solvers/methods/pgs.hpp"
#include "solvers/core/solve_loop.hpp"
#include "solvers/linalg/a_product.hpp"
#include "solvers/linalg/delassus.hpp"
#include "solvers/measure/accuracy_rows.hpp"
#include "solvers/measure/work_units.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

namespace cb {

namespace {

/// Every setting of `pgs`, declared once (settings.hpp SettingsTable).
const SettingsTable<PgsSettings>& pgs_settings_table()
{
    static const SettingsTable<PgsSettings> table =
        SettingsTable<PgsSettings>()
            .integer("max_rows", &PgsSettings::max_rows, 0, LONG_MAX,
                     "refuse (not_applicable) problems with more rows of J (S is dense m x m)")
            .integer("block", &PgsSettings::block, 1, 4096, "right-hand sides per CHOLMOD solve when forming S");
    return table;
}

}  // namespace

PgsSettings PgsSettings::from_json(const nlohmann::json& settings)
{
    return read_settings(settings, "pgs", pgs_settings_table());
}

nlohmann::json PgsSettings::to_json() const { return write_settings(*this, pgs_settings_table()); }

namespace {

/// Y = A^-1 J' is kept (x = x_u + Y lambda without a solve) when it fits in this many doubles.
constexpr double MAX_STORED_ENTRIES = 16e6;

}  // namespace

SolverResult PgsSolver::solve(const QpView& qp, const SolveContext& context)
{
    const PgsSettings& s = m_settings;
    const Eigen::Index n = qp.n(), m = qp.m();
    SolverResult result;
    Counters& counters = result.counters;
    result.x = qp.x0;
    result.lambda = Vec::Zero(m);
    result.info["native_residual_definition"] = "||min(lambda, S lambda - q)||_inf (LCP natural residual, absolute)";

    SolveLoop loop("pgs", qp, s.common, context);
    if (m > s.max_rows) {
        return loop.finish(result, SolveStatus::NOT_APPLICABLE,
                           "pgs: m = " + std::to_string(m) + " rows exceeds max_rows = " + std::to_string(s.max_rows) +
                               " (S = J A^-1 J' is a dense m x m matrix formed with m CHOLMOD solves); "
                               "raise the max_rows setting to allow it");
    }

    // Zero rows of J: S_ii = 0. Row i reads 0 >= c_i, so c_i > 0 means an empty feasible set.
    std::vector<char> zero_row(static_cast<size_t>(m), 1);
    for (Eigen::Index i = 0; i < m; ++i)
        for (SpMat::InnerIterator it(qp.J, i); it; ++it)
            if (it.value() != 0.0) zero_row[static_cast<size_t>(i)] = 0;
    long zero_rows = 0;
    for (Eigen::Index i = 0; i < m; ++i) {
        if (!zero_row[static_cast<size_t>(i)]) continue;
        ++zero_rows;
        if (qp.c[i] > 0.0) {
            std::ostringstream msg;
            msg << "pgs: row " << i << " of J is zero but c_" << i << " = " << qp.c[i]
                << " > 0: the constraint 0 >= c_i cannot hold";
            return loop.finish(result, SolveStatus::INFEASIBLE, msg.str());
        }
    }
    result.info["zero_rows"] = zero_rows;

    Delassus delassus;
    if (!delassus.factor(SpMatCol(qp.A), counters))
        return loop.finish(result, SolveStatus::INVALID_INPUT,
                           "pgs: CHOLMOD could not factor A (not positive definite to working precision)");
    const Vec x_u = delassus.solve(qp.b, counters);
    const Vec q = qp.c - qp.J * x_u;
    // A non-finite b or c would sit in q, where the clamp max(0, .) hides it from the sweeps.
    if (!x_u.allFinite() || !q.allFinite()) return loop.finish(result, loop.check(counters.iterations, false, false));

    // S = J A^-1 J', with Y = A^-1 J' kept when it fits.
    const bool keep_y = static_cast<double>(n) * static_cast<double>(m) <= MAX_STORED_ENTRIES;
    Eigen::MatrixXd Y, S;
    if (!delassus.form_dense(qp.J, S, counters, {s.block, keep_y ? &Y : nullptr, [&] { return loop.time_up(); }}))
        return loop.finish(result, SolveStatus::TIME_LIMIT, "while forming S = J A^-1 J'");
    const Vec S_diag = S.diagonal();
    result.info["y_stored"] = keep_y;
    // CSR: a few products (the stop test's gradients) would not repay a block copy of A.
    loop.setup_phase("delassus");  // A's factor, S = J A^-1 J'
    AOperator a_op(qp);
    a_op.prepare(AFormat::CSR, static_cast<int>(s.common.threads));
    const AccuracyScale scale = accuracy_scale(qp);  // setup, as in every solver
    counters.a_products += scale.a_products;
    loop.setup_phase("measure_scale");
    if (!loop.end_setup()) return loop.finish(result, SolveStatus::TIME_LIMIT);

    Vec lambda = Vec::Zero(m);
    if (context.lambda0 && context.lambda0->size() == m) lambda = context.lambda0->cwiseMax(0.0);
    for (Eigen::Index i = 0; i < m; ++i)
        if (zero_row[static_cast<size_t>(i)]) lambda[i] = 0.0;
    Vec w = S * lambda - q;  // = J x(lambda) - c, the slack of the primal point
    counters.work_flops += dense_matvec_flops(m, m);

    Vec x = x_u;
    auto primal_point = [&](bool exact) {
        if (m == 0) {
            x = x_u;
        } else if (keep_y && !exact) {
            x = x_u + Y * lambda;
        } else {
            x = delassus.solve(Vec(qp.b + qp.J.transpose() * lambda), counters);
        }
    };
    auto natural_residual = [&]() {
        double r = 0.0;
        for (Eigen::Index i = 0; i < m; ++i) r = std::max(r, std::abs(std::min(lambda[i], w[i])));
        return r;
    };
    // The accuracy measure in dual space: stationarity is 0 at x(lambda), dual feasibility holds
    // (lambda >= 0); the row parts as in solvers/measure/accuracy.cpp.
    auto dual_space_error = [&]() {
        RowParts rows;
        for (Eigen::Index i = 0; i < m; ++i) {
            const double inv_norm = scale.inv_row_norm[i];
            if (inv_norm == 0.0) continue;  // zero rows: checked at the exact primal point
            rows.add_primal(w[i], inv_norm);
            rows.add_multiplier(w[i], lambda[i], inv_norm, scale.length_per_multiplier[i]);
        }
        const RowParts e = rows.scaled(scale.inv_length, scale.inv_energy);
        return std::max(std::max(e.primal, std::max(e.dual, e.complementarity)), e.gap);
    };

    double native = natural_residual();
    double dual_threshold = s.common.tol;
    auto finish = [&](SolveStatus status) {
        primal_point(true);
        result.x = x;
        result.lambda = lambda;
        result.native_residual = native;
        std::ostringstream detail;  // the loop writes the reason
        detail << "LCP natural residual " << native << " after " << counters.iterations << " sweeps";
        return loop.finish(result, status, detail.str());
    };
    // x(lambda) for the monitor only: formed inside the monitor's pause (loop.notify's prepare).
    auto monitor = [&](long iteration, StepKind step) {
        return loop.notify({iteration, step, &x, &lambda, native, -1, &counters, 0.0}, [&] { primal_point(false); });
    };
    // The accuracy error for the loop's stop rule: screened in dual space first, then measured at
    // the exact primal point; +inf when the screen already says "not met".
    auto accuracy_error = [&]() -> double {
        if (dual_space_error() > dual_threshold) return std::numeric_limits<double>::infinity();
        primal_point(true);
        const Vec g = a_product(a_op, x) - qp.b;
        ++counters.a_products;
        const double e = accuracy_from_gradient(qp, scale, x, g, lambda).max();
        if (!(e <= s.common.tol)) dual_threshold *= 0.5;  // the solve's error showed up: ask more of the dual estimate
        return e;
    };

    SolveStatus status = monitor(0, StepKind::START) ? SolveStatus::NOT_RUN : SolveStatus::STOPPED_BY_MONITOR;
    while (status == SolveStatus::NOT_RUN) {
        status = loop.check(counters.iterations, lambda.allFinite() && std::isfinite(native), native, accuracy_error);
        if (status != SolveStatus::NOT_RUN) break;

        // One ascending sweep; w = S lambda - q is kept current by rank-one updates.
        long updates = 0;  // columns of S added to w (2m flops each; docs/work.md)
        for (Eigen::Index i = 0; i < m; ++i) {
            if (!(S_diag[i] > 0.0)) continue;  // zero row: lambda_i stays 0
            const double li = std::max(0.0, lambda[i] - w[i] / S_diag[i]);
            const double delta = li - lambda[i];
            if (delta != 0.0) {
                w.noalias() += delta * S.col(i);
                lambda[i] = li;
                ++updates;
            }
        }
        ++counters.iterations;
        ++counters.pgs_sweeps;
        ++counters.lcp_iterations;
        counters.work_flops += dense_matvec_flops(static_cast<double>(updates), m);
        if (counters.iterations % 64 == 0) {
            w = S * lambda - q;  // limit the drift of the updates
            counters.work_flops += dense_matvec_flops(m, m);
        }
        native = natural_residual();
        if (!monitor(counters.iterations, StepKind::PGS_SWEEP)) status = SolveStatus::STOPPED_BY_MONITOR;
    }
    return finish(status);
}

SolverEntry pgs_entry()
{
    return solver_entry<PgsSolver>("pgs", pgs_settings_table(),
                                   "projected Gauss-Seidel on the exact dual S = J A^-1 J' (CHOLMOD; small m only)",
                                   "any J with at most max_rows rows (2000; the dual matrix is dense)");
}

}  // namespace cb
