// `active-set`: Goldfarb-Idnani dual active-set method on a CHOLMOD factor of A (ALGORITHMS.md §8).
// Ref: Goldfarb & Idnani, Math. Programming 27 (1983), Sec. 3 (the dual algorithm: step
// directions z = H n+, r = N* n+, partial and full steps t1, t2); here written in the
// "range-space" form of Nocedal-Wright Sec. 16.5: with K = J A^-1 J' (columns computed on
// demand, one CHOLMOD solve per row), S_W = K_WW, r = S_W^-1 K_Wp, n_p'z = K_pp - K_pW r, and
// the slacks s = J x - c = s_unc + K lambda are tracked in the m-dimensional dual space; x is
// only formed (one solve) when it is needed: monitor calls and the final polish.
#include "solvers/methods/active_set.hpp"
#include "solvers/core/solve_loop.hpp"

#include "solvers/linalg/a_product.hpp"
#include "solvers/measure/work_units.hpp"

#include <Eigen/CholmodSupport>
#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

namespace cb {

namespace {

/// Every setting of `active-set`, declared once (settings.hpp SettingsTable).
const SettingsTable<ActiveSetSettings>& active_set_settings_table()
{
    static const SettingsTable<ActiveSetSettings> table =
        SettingsTable<ActiveSetSettings>()
            .integer("monitor_every", &ActiveSetSettings::monitor_every, 0, LONG_MAX,
                     "monitor call every k-th pivot (each forms x with one untimed solve); 0 = start and end only")
            .integer("polish_rounds", &ActiveSetSettings::polish_rounds, 0, 100,
                     "iterative-refinement rounds of the equality QP on the final working set")
            .number("dependency_tol", &ActiveSetSettings::dependency_tol, 0.0, 1e-2,
                    "row p depends on the working set when K_pp - K_pW S_W^-1 K_Wp <= dependency_tol * K_pp");
    return table;
}

}  // namespace

ActiveSetSettings ActiveSetSettings::from_json(const nlohmann::json& settings)
{
    return read_settings(settings, "active-set", active_set_settings_table());
}

nlohmann::json ActiveSetSettings::to_json() const { return write_settings(*this, active_set_settings_table()); }

// ---------------------------------------------------------------------------------------------
// GrowingCholesky

Vec GrowingCholesky::forward(const Vec& d) const
{
    if (m_size == 0) return Vec(0);
    return m_buffer.topLeftCorner(m_size, m_size).triangularView<Eigen::Lower>().solve(d);
}

Vec GrowingCholesky::backward(const Vec& y) const
{
    if (m_size == 0) return Vec(0);
    return m_buffer.topLeftCorner(m_size, m_size).transpose().triangularView<Eigen::Upper>().solve(y);
}

void GrowingCholesky::append(const Vec& l, double pivot_squared)
{
    const int q = m_size;
    if (q + 1 > m_buffer.rows()) {
        // Geometric growth: resizing a q x q factor at every append would cost O(q^3) in copies.
        const Eigen::Index capacity = std::max<Eigen::Index>(16, 2 * m_buffer.rows());
        Eigen::MatrixXd grown = Eigen::MatrixXd::Zero(capacity, capacity);
        grown.topLeftCorner(q, q) = m_buffer.topLeftCorner(q, q);
        m_buffer.swap(grown);
    }
    m_buffer.row(q).head(q) = l.transpose();
    m_buffer.col(q).head(q).setZero();
    m_buffer(q, q) = std::sqrt(pivot_squared);
    m_size = q + 1;
}

void GrowingCholesky::remove(int k)
{
    const int q = m_size;
    assert(k >= 0 && k < q && "GrowingCholesky::remove: index out of range");
    // Delete row k of L: rows below it keep one entry right of the diagonal, which a Givens
    // rotation of columns (j, j+1) removes (L G G' L' = L L'). Done in place: shift rows up.
    Eigen::MatrixXd& M = m_buffer;
    for (int i = k; i < q - 1; ++i) M.row(i).head(q) = M.row(i + 1).head(q);
    for (int j = k; j < q - 1; ++j) {
        const double a = M(j, j), b = M(j, j + 1);
        const double rho = std::hypot(a, b);
        if (rho == 0.0) continue;
        const double cs = a / rho, sn = b / rho;
        for (int i = j; i < q - 1; ++i) {
            const double u = M(i, j), v = M(i, j + 1);
            M(i, j) = cs * u + sn * v;
            M(i, j + 1) = -sn * u + cs * v;
        }
        M(j, j + 1) = 0.0;
    }
    m_size = q - 1;
    // Keep the unused part of the buffer clean for the next append's row.
    M.row(m_size).head(q).setZero();
    M.col(m_size).head(q).setZero();
}

// ---------------------------------------------------------------------------------------------
// The solver

namespace {

constexpr double INF = std::numeric_limits<double>::infinity();
/// Rows violated by less than this (relative to |c_i| + |J_i|_1 |x|_inf, i.e. a few hundred
/// roundings of J_i x - c_i) count as satisfied: chasing them would only add noise pivots.
constexpr double FEASIBILITY_EPS = 1e-12;
/// Initial batch of K columns (one multi-RHS CHOLMOD solve is much cheaper per column).
constexpr int INITIAL_BATCH_MAX = 1024;
constexpr int SOLVE_BLOCK = 32;

}  // namespace

SolverResult ActiveSetSolver::solve(const QpView& qp, const SolveContext& context)
{
    SolverResult result;
    Counters& counters = result.counters;
    const CommonSettings& common = m_settings.common;
    const Eigen::Index n = qp.n();
    const Eigen::Index m = qp.m();
    result.info["method"] = "goldfarb-idnani";

    SolveLoop loop("active-set", qp, common, context);
    auto invalid = [&](const std::string& message) {
        result.x = qp.x0.size() == n ? qp.x0 : Vec::Zero(n);
        result.lambda = Vec::Zero(m);
        return loop.finish(result, SolveStatus::INVALID_INPUT, "active-set: " + message);
    };
    if (qp.A.cols() != n || qp.b.size() != n || qp.x0.size() != n || qp.c.size() != m || (m > 0 && qp.J.cols() != n)) {
        std::ostringstream msg;
        msg << "sizes disagree: A " << qp.A.rows() << "x" << qp.A.cols() << ", b " << qp.b.size() << ", x0 "
            << qp.x0.size() << ", J " << qp.J.rows() << "x" << qp.J.cols() << ", c " << qp.c.size();
        return invalid(msg.str());
    }

    // Row norms; zero rows are decided once: feasible iff 0 >= c_i.
    Vec row_norm(m), row_norm1(m);
    std::vector<char> zero_row(m, 0);
    long zero_rows = 0;
    Eigen::Index infeasible_zero_row = -1;
    for (Eigen::Index i = 0; i < m; ++i) {
        double s2 = 0.0, s1 = 0.0;
        for (SpMat::InnerIterator it(qp.J, i); it; ++it) {
            s2 += it.value() * it.value();
            s1 += std::abs(it.value());
        }
        row_norm[i] = std::sqrt(s2);
        row_norm1[i] = s1;
        if (s2 == 0.0) {
            zero_row[i] = 1;
            ++zero_rows;
            if (qp.c[i] > 0.0 && infeasible_zero_row < 0) infeasible_zero_row = i;
        }
    }

    // Factor A once.
    const SpMatCol A_col = qp.A;
    Eigen::CholmodSupernodalLLT<SpMatCol, Eigen::Lower> chol;
    chol.cholmod().print = 0;  // failures are reported through the status, not on stderr
    chol.analyzePattern(A_col);
    ++counters.cholmod_analyses;
    chol.factorize(A_col);
    ++counters.cholmod_factorizations;
    counters.work_flops += cholmod_factor_flops(chol.cholmod());
    if (chol.info() != Eigen::Success)
        return invalid("A is not positive definite (CHOLMOD Cholesky factorization failed)");
    auto apply_a_inverse = [&](const Vec& rhs) -> Vec {
        ++counters.cholmod_solves;
        counters.work_flops += cholmod_solve_flops(chol.cholmod());
        return chol.solve(rhs);
    };
    // CSR: a few products (the stop test's gradients) would not repay a block copy of A.
    loop.setup_phase("factorization");  // the row norms and A's Cholesky factor
    AOperator a_op(qp);
    a_op.prepare(AFormat::CSR, static_cast<int>(common.threads));
    const AccuracyScale scale = accuracy_scale(qp);  // setup, as in every solver
    counters.a_products += scale.a_products;
    loop.setup_phase("measure_scale");
    if (!loop.end_setup()) {
        result.x = qp.x0;
        result.lambda = Vec::Zero(m);
        return loop.finish(result, SolveStatus::TIME_LIMIT);
    }

    const Vec x_unc = apply_a_inverse(qp.b);
    // A non-finite b (or A) leaves nothing to pivot on: the loop's finiteness check ends the solve.
    if (!x_unc.allFinite()) return loop.finish(result, loop.check(counters.iterations, false, false));
    Vec s_base = m > 0 ? Vec(qp.J * x_unc - qp.c) : Vec(0);
    const double x_scale = std::max(x_unc.size() ? x_unc.lpNorm<Eigen::Infinity>() : 0.0,
                                    qp.x0.size() ? qp.x0.lpNorm<Eigen::Infinity>() : 0.0);
    Vec tau(m);
    for (Eigen::Index i = 0; i < m; ++i) tau[i] = FEASIBILITY_EPS * (std::abs(qp.c[i]) + row_norm1[i] * x_scale);

    // Columns of K = J A^-1 J', computed on first use.
    std::vector<int> slot(m, -1);
    std::vector<Vec> kcol;
    auto cache_rows = [&](const std::vector<int>& rows) {
        for (size_t start = 0; start < rows.size(); start += SOLVE_BLOCK) {
            const int k = static_cast<int>(std::min<size_t>(SOLVE_BLOCK, rows.size() - start));
            Eigen::MatrixXd R = Eigen::MatrixXd::Zero(n, k);
            for (int j = 0; j < k; ++j)
                for (SpMat::InnerIterator it(qp.J, rows[start + j]); it; ++it) R(it.col(), j) = it.value();
            const Eigen::MatrixXd U = chol.solve(R);
            counters.cholmod_solves += k;
            counters.work_flops +=
                cholmod_solve_flops(chol.cholmod(), k) + sparse_product_flops(static_cast<double>(qp.J.nonZeros()), k);
            const Eigen::MatrixXd KU = qp.J * U;
            for (int j = 0; j < k; ++j) {
                slot[rows[start + j]] = static_cast<int>(kcol.size());
                kcol.emplace_back(KU.col(j));
            }
        }
    };
    auto ensure_cached = [&](int row) {
        if (slot[row] < 0) cache_rows({row});
    };

    // Warm the cache with the rows violated at the unconstrained minimiser (most violated first).
    {
        std::vector<std::pair<double, int>> violated;
        for (Eigen::Index i = 0; i < m; ++i)
            if (!zero_row[i] && s_base[i] < -tau[i])
                violated.emplace_back(s_base[i] / row_norm[i], static_cast<int>(i));
        std::sort(violated.begin(), violated.end());
        std::vector<int> rows;
        for (size_t k = 0; k < violated.size() && k < static_cast<size_t>(INITIAL_BATCH_MAX); ++k)
            rows.push_back(violated[k].second);
        cache_rows(rows);
    }

    std::vector<int> W;  // working set, in the order of the Cholesky factor
    std::vector<char> in_working_set(m, 0);
    GrowingCholesky schur;  // S_W = L L'
    Vec lambda = Vec::Zero(m);
    Vec s(m);
    long added = 0, dropped = 0, dependent_steps = 0, gi_restarts = 0, polish_done = 0;
    double clipped = 0.0;

    auto recompute_slack = [&](int pending) {
        s = s_base;
        for (int row : W)
            if (lambda[row] != 0.0) s.noalias() += lambda[row] * kcol[slot[row]];
        if (pending >= 0 && lambda[pending] != 0.0) s.noalias() += lambda[pending] * kcol[slot[pending]];
        counters.work_flops += dense_matvec_flops(m, static_cast<double>(W.size()) + (pending >= 0 ? 1.0 : 0.0));
    };
    auto drop = [&](int k) {
        lambda[W[k]] = 0.0;
        in_working_set[W[k]] = 0;
        W.erase(W.begin() + k);
        schur.remove(k);  // Givens rotations of the trailing columns: about 6 q (q - k) flops
        counters.work_flops +=
            6.0 * static_cast<double>(W.size() + 1) * static_cast<double>(static_cast<int>(W.size()) + 1 - k);
        ++dropped;
        ++counters.pivots;
    };
    // J' v, also when J has no rows (then possibly 0 x 0).
    auto Jt = [&](const Vec& v) -> Vec { return m > 0 ? Vec(qp.J.transpose() * v) : Vec(Vec::Zero(n)); };
    auto max_violation_of = [&](const Vec& slack) {
        double v = 0.0;
        for (Eigen::Index i = 0; i < m; ++i)
            if (!zero_row[i]) v = std::max(v, -slack[i]);
        return v;
    };
    Vec x_monitor;
    // `returned`: the final call passes the returned (polished) point, so that the history's
    // last row is what the solver returns.
    auto monitor = [&](StepKind step, const Vec* returned = nullptr, double returned_native = 0.0) {
        if (!context.monitor) return true;
        const bool every = m_settings.monitor_every > 0 && counters.iterations % m_settings.monitor_every == 0;
        if (step == StepKind::PIVOT && !every) return true;
        IterationInfo info;
        info.iteration = counters.iterations;
        info.step = step;
        info.x = returned ? returned : &x_monitor;
        info.lambda = &lambda;
        info.native_residual = returned ? returned_native : 0.0;
        info.active_set_size = static_cast<long>(W.size());
        info.counters = &counters;
        // Forming x and the violation it shows are monitor work, not solver work: done inside the pause.
        return loop.notify(info, [&](IterationInfo& shown) {
            if (returned) return;
            x_monitor = chol.solve(Vec(qp.b + Jt(lambda)));
            shown.native_residual = m > 0 ? max_violation_of(s) : 0.0;
        });
    };

    recompute_slack(-1);
    if (infeasible_zero_row >= 0) {
        std::ostringstream msg;
        msg << "active-set: infeasible: row " << infeasible_zero_row
            << " of J is zero and c = " << qp.c[infeasible_zero_row] << " > 0";
        result.status = SolveStatus::INFEASIBLE;
        result.message = msg.str();
    } else if (!monitor(StepKind::START)) {
        result.status = SolveStatus::STOPPED_BY_MONITOR;
    }

    Vec x;
    bool x_polished = false;
    while (result.status == SolveStatus::NOT_RUN) {
        // ---- Goldfarb-Idnani phase: add the most violated row until none is left ----
        while (result.status == SolveStatus::NOT_RUN) {
            int p = -1;
            double best = 0.0;
            for (Eigen::Index i = 0; i < m; ++i) {
                if (zero_row[i] || s[i] >= -tau[i]) continue;
                if (in_working_set[i]) continue;
                const double score = s[i] / row_norm[i];  // signed distance to the row's plane
                if (p < 0 || score < best) {
                    best = score;
                    p = static_cast<int>(i);
                }
            }
            if (p < 0) break;
            ensure_cached(p);
            // Step 2: move until p is satisfied (full step) or a working row must leave.
            bool p_added = false;
            while (!p_added) {
                result.status = loop.limit_status(counters.iterations);
                if (result.status != SolveStatus::NOT_RUN) break;
                ++counters.iterations;
                const Vec& kp = kcol[slot[p]];
                const int q = static_cast<int>(W.size());
                Vec d(q);
                for (int a = 0; a < q; ++a) d[a] = kp[W[a]];
                const Vec l = schur.forward(d);
                const Vec r = schur.backward(l);
                counters.work_flops += 2.0 * dense_triangular_solve_flops(q);
                const double kpp = kp[p];
                const double pivot = kpp - l.squaredNorm();  // n_p' z: zero when p is in span(W)
                const bool dependent = !(pivot > m_settings.dependency_tol * kpp);
                double t1 = INF;
                int k = -1;
                for (int a = 0; a < q; ++a) {
                    // r_a counts as positive only above rounding (rows compared at equal norm).
                    if (r[a] * row_norm[W[a]] > 1e-12 * row_norm[p]) {
                        const double ratio = lambda[W[a]] / r[a];
                        if (ratio < t1) {
                            t1 = ratio;
                            k = a;
                        }
                    }
                }
                const double t2 = dependent ? INF : -s[p] / pivot;
                if (t1 == INF && t2 == INF) {
                    std::ostringstream msg;
                    msg << "active-set: infeasible: row " << p << " (violated by " << -s[p]
                        << ") is a nonpositive combination of the " << q
                        << " working rows, so no x satisfies them together";
                    result.status = SolveStatus::INFEASIBLE;
                    result.message = msg.str();
                    break;
                }
                const double t = std::min(t1, t2);
                for (int a = 0; a < q; ++a) lambda[W[a]] = std::max(0.0, lambda[W[a]] - t * r[a]);
                lambda[p] += t;
                if (t2 <= t1) {  // full step: p joins the working set
                    schur.append(l, pivot);
                    W.push_back(p);
                    in_working_set[p] = 1;
                    ++added;
                    ++counters.pivots;
                    p_added = true;
                } else {  // partial (or, when dependent, pure dual) step: k leaves
                    if (dependent) ++dependent_steps;
                    drop(k);
                }
                recompute_slack(p_added ? -1 : p);
                if (!monitor(StepKind::PIVOT)) {
                    result.status = SolveStatus::STOPPED_BY_MONITOR;
                    break;
                }
            }
        }
        if (result.status != SolveStatus::NOT_RUN) break;

        // ---- Polish: iterative refinement of the equality QP on W ----
        //   A x - J_W' lambda_W = b,  J_W x = c_W
        const int q = static_cast<int>(W.size());
        x = apply_a_inverse(qp.b + Jt(lambda));
        double best_error = INF;
        Vec best_x = x, best_lambda = lambda;
        for (long round = 0; round <= m_settings.polish_rounds; ++round) {
            const Vec g = a_product(a_op, x) - qp.b;
            ++counters.a_products;
            const double error = accuracy_from_gradient(qp, scale, x, g, lambda).max();
            if (error < best_error) {
                best_error = error;
                best_x = x;
                best_lambda = lambda;
            } else {
                break;  // refinement stopped helping
            }
            if (round == m_settings.polish_rounds || error <= 1e-15) break;
            const Vec r1 = Jt(lambda) - g;
            const Vec v = apply_a_inverse(r1);
            Vec rhs(q);
            for (int a = 0; a < q; ++a) rhs[a] = qp.c[W[a]] - qp.J.row(W[a]).dot(x) - qp.J.row(W[a]).dot(v);
            const Vec dlam = schur.solve(rhs);
            counters.work_flops += 2.0 * dense_triangular_solve_flops(q);
            Vec dlam_full = Vec::Zero(m);
            for (int a = 0; a < q; ++a) dlam_full[W[a]] = dlam[a];
            x += apply_a_inverse(r1 + Jt(dlam_full));
            lambda += dlam_full;
            ++polish_done;
        }
        x = best_x;
        lambda = best_lambda;
        for (int row : W)
            if (lambda[row] < 0.0) {
                clipped = std::min(clipped, lambda[row]);
                lambda[row] = 0.0;
            }
        x_polished = true;

        // The polished x is exact to rounding: if it reveals violated rows the GI phase missed
        // (slacks tracked in K carried solve errors), resume from it.
        const Vec s_exact = m > 0 ? Vec(qp.J * x - qp.c) : Vec(0);
        bool violated = false;
        for (Eigen::Index i = 0; i < m && !violated; ++i)
            violated = !zero_row[i] && !in_working_set[i] && s_exact[i] < -tau[i];
        if (!violated || gi_restarts >= 3) break;
        ++gi_restarts;
        s_base = s_exact;
        for (int row : W)
            if (lambda[row] != 0.0) s_base.noalias() -= lambda[row] * kcol[slot[row]];
        recompute_slack(-1);
        x_polished = false;
    }

    if (!x_polished) x = apply_a_inverse(qp.b + Jt(lambda));
    const Vec g = a_product(a_op, x) - qp.b;
    ++counters.a_products;
    const double rel = accuracy_from_gradient(qp, scale, x, g, lambda).max();
    const double stationarity_abs = (g - Jt(lambda)).lpNorm<Eigen::Infinity>();
    result.native_residual = std::max(stationarity_abs, max_violation(qp, x));

    std::ostringstream detail;  // the loop writes the reason; INFEASIBLE keeps its own message
    if (result.status == SolveStatus::NOT_RUN) {
        // A finite method: the loop's verdict on the polished point.
        result.status = loop.verdict(x.allFinite() && lambda.allFinite(), result.native_residual, rel);
        detail << (result.status == SolveStatus::STALLED ? "working set of " : "optimal working set of ") << W.size()
               << " rows after " << counters.iterations << " steps"
               << (result.status == SolveStatus::STALLED ? " (ill-conditioned A or dependent rows)" : "");
    }
    if (detail.tellp() == 0)
        detail << counters.iterations << " steps; working set " << W.size() << " rows; accuracy error " << rel;
    result.x = x;
    result.lambda = lambda;
    result.iterations = counters.iterations;
    result.info["rows_added"] = added;
    result.info["rows_dropped"] = dropped;
    result.info["dependent_steps"] = dependent_steps;
    result.info["working_set"] = static_cast<long>(W.size());
    result.info["rows_cached"] = static_cast<long>(kcol.size());
    result.info["polish_rounds"] = polish_done;
    result.info["gi_restarts"] = gi_restarts;
    result.info["zero_rows"] = zero_rows;
    result.info["clipped_negative_lambda"] = clipped;
    result.info["accuracy_error"] = rel;
    monitor(StepKind::FINAL, &x, result.native_residual);
    return loop.finish(result, result.status, result.message.empty() ? detail.str() : result.message);
}

SolverEntry active_set_entry()
{
    return solver_entry<ActiveSetSolver>(
        "active-set", active_set_settings_table(),
        "Goldfarb-Idnani dual active-set QP on a CHOLMOD factor of A (the reference; detects infeasibility)",
        "any J (dense Schur complement of the working set)");
}

}  // namespace cb
