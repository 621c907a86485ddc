// `mprgp-box`: Dostal's MPRGP for bounds (ALGORITHMS.md §5).
// Ref: Dostal 2009, Ch. 5: free/chopped gradients eq. (11)-(12) of Li et al. 2015, reduced
//      free gradient phitilde_i = min((x_i - l_i)/alpha_bar, phi_i) (and its upper-bound mirror),
//      feasible step length before the expansion step, Alg. 1-2.
#include "solvers/mprgp_box.hpp"
#include "solvers/solve_loop.hpp"

#include "solvers/a_product.hpp"
#include "solvers/accuracy.hpp"
#include "solvers/bounds.hpp"
#include "solvers/format_number.hpp"
#include "solvers/mprgp_kernels.hpp"

#include <cmath>
#include <limits>
#include <sstream>

namespace cb {

bool is_bound_rows(const SpMat& J)
{
    for (Eigen::Index i = 0; i < J.rows(); ++i) {
        int nonzeros = 0;
        for (SpMat::InnerIterator it(J, i); it; ++it) nonzeros += it.value() != 0.0;
        if (nonzeros > 1) return false;
    }
    return true;
}

namespace {

/// Every setting of `mprgp-box`, declared once (settings.hpp SettingsTable).
const SettingsTable<MprgpBoxSettings>& mprgp_box_settings_table()
{
    static const SettingsTable<MprgpBoxSettings> table =
        SettingsTable<MprgpBoxSettings>()
            .number("gamma", &MprgpBoxSettings::gamma, 0.0, 1e300, "proportioning constant Gamma > 0")
            .choice("precond", &MprgpBoxSettings::precond, {"none", "jacobi"},
                    "none | jacobi (diagonal of A on the free set)")
            .integer("power_max", &MprgpBoxSettings::power_max, 1, 1000000,
                     "max power-method products (alpha_bar = 2 / (1.01 ||A||))");
    return table;
}

}  // namespace

MprgpBoxSettings MprgpBoxSettings::from_json(const nlohmann::json& settings)
{
    return read_settings(settings, "mprgp-box", mprgp_box_settings_table());
}

nlohmann::json MprgpBoxSettings::to_json() const { return write_settings(*this, mprgp_box_settings_table()); }

SolverEntry mprgp_box_entry()
{
    return solver_entry<MprgpBoxSolver>(
        "mprgp-box", mprgp_box_settings_table(),
        "Dostal's MPRGP for bound rows (every row of J a signed unit vector), lower and upper bounds",
        "bounds only (every row of J has at most one nonzero)");
}

namespace {

}  // namespace

SolverResult MprgpBoxSolver::solve(const QpView& qp, const SolveContext& context)
{
    const CommonSettings& common = m_settings.common;
    const Eigen::Index n = qp.n(), m = qp.m();
    SolverResult result;
    SolveLoop loop("mprgp-box", qp, common, context);
    Counters cnt;
    result.x = qp.x0;
    result.lambda = Vec::Zero(m);
    // --- bounds from the rows (solvers/bounds.hpp: one policy for what a bounds solver cannot take) ---
    const RowBounds bounds = bounds_from_rows(qp);
    if (bounds.status != SolveStatus::NOT_RUN)
        return loop.finish(
            result, bounds.status,
            "mprgp-box: " + bounds.why +
                (bounds.status == SolveStatus::NOT_APPLICABLE ? "; use mprgp (decoupled J) or mprgp-coupled" : ""));
    const double inf = std::numeric_limits<double>::infinity();
    const Vec& lower = bounds.lower;
    const Vec& upper = bounds.upper;
    const Vec& row_coef = bounds.coef;
    const std::vector<Eigen::Index>& lower_row = bounds.lower_row;
    const std::vector<Eigen::Index>& upper_row = bounds.upper_row;
    Vec dinv = Vec::Ones(n);
    if (m_settings.precond == "jacobi") {
        const Vec diag = qp.A.diagonal();
        if (!(diag.minCoeff() > 0.0)) {
            result.status = SolveStatus::INVALID_INPUT;
            result.message = "mprgp-box: precond=jacobi needs a positive diagonal of A";
            return loop.finish(result, result.status);
        }
        dinv = diag.cwiseInverse();
    }
    // Tolerance for "at the bound", in x units: tau_i of the row divided by |a|.
    Vec tol_lower = Vec::Zero(n), tol_upper = Vec::Zero(n);
    for (Eigen::Index j = 0; j < n; ++j) {
        const int rl = lower_row[static_cast<size_t>(j)], ru = upper_row[static_cast<size_t>(j)];
        if (rl >= 0) tol_lower[j] = active_tolerance(qp.c[rl]) / std::abs(row_coef[rl]);
        if (ru >= 0) tol_upper[j] = active_tolerance(qp.c[ru]) / std::abs(row_coef[ru]);
    }
    AOperator a_op(qp.A);  // the product with A: 3x3 blocks when A has them, built in the setup
    a_op.prepare(AFormat::BSR, static_cast<int>(common.threads));
    Vec eigenvector;
    const bool warm = context.eigenvector && context.eigenvector->size() == n;
    if (warm) eigenvector = *context.eigenvector;
    const PowerResult power =
        power_method(a_op, eigenvector, PowerRule::POWER, m_settings.power_max, common.tol, warm, common.seed);
    if (context.eigenvector) *context.eigenvector = eigenvector;
    cnt.power_products = power.products;
    cnt.a_products += power.products;
    const double alpha_bar = power.estimate > 0.0 ? 2.0 / (1.01 * power.estimate) : 1.0;
    result.info["alpha_bar"] = alpha_bar;
    result.info["power"] = {{"products", power.products}, {"estimate", power.estimate}, {"warm_start", power.warm}};
    const AccuracyScale scale = accuracy_scale(qp);
    cnt.a_products += scale.a_products;
    if (!loop.end_setup()) return loop.finish(result, SolveStatus::TIME_LIMIT);

    // --- the MPRGP loop ---
    Vec x = qp.x0.cwiseMax(lower).cwiseMin(upper);
    ++cnt.projections;
    Vec g = a_product(a_op, x) - qp.b;
    ++cnt.a_products;
    Vec phi(n), beta(n), z(n), p(n), Ap(n), lambda = Vec::Zero(m);
    std::vector<char> at_lower(static_cast<size_t>(n)), at_upper(static_cast<size_t>(n));
    auto classify = [&]() {
        for (Eigen::Index j = 0; j < n; ++j) {
            at_lower[static_cast<size_t>(j)] = x[j] <= lower[j] + tol_lower[j];
            at_upper[static_cast<size_t>(j)] = !at_lower[static_cast<size_t>(j)] && x[j] >= upper[j] - tol_upper[j];
        }
    };
    auto gradients = [&]() {
        for (Eigen::Index j = 0; j < n; ++j) {
            const bool lo = at_lower[static_cast<size_t>(j)], up = at_upper[static_cast<size_t>(j)];
            phi[j] = (lo || up) ? 0.0 : g[j];
            beta[j] = lo ? std::min(g[j], 0.0) : (up ? std::max(g[j], 0.0) : 0.0);
            z[j] = dinv[j] * phi[j];
        }
        ++cnt.precond_applications;
    };
    auto phitilde_dot_phi = [&]() {
        double s = 0.0;
        for (Eigen::Index j = 0; j < n; ++j) {
            if (phi[j] > 0.0)
                s += std::min((x[j] - lower[j]) / alpha_bar, phi[j]) * phi[j];
            else if (phi[j] < 0.0)
                s += std::max((x[j] - upper[j]) / alpha_bar, phi[j]) * phi[j];
        }
        return s;
    };
    auto multipliers = [&]() {
        lambda.setZero();
        for (Eigen::Index j = 0; j < n; ++j) {
            const int rl = lower_row[static_cast<size_t>(j)], ru = upper_row[static_cast<size_t>(j)];
            if (at_lower[static_cast<size_t>(j)] && rl >= 0) lambda[rl] = std::max(0.0, g[j] / row_coef[rl]);
            if (at_upper[static_cast<size_t>(j)] && ru >= 0) lambda[ru] = std::max(0.0, g[j] / row_coef[ru]);
        }
    };
    classify();
    gradients();
    p = z;
    SolveStatus status = SolveStatus::NOT_RUN;
    std::string why;  // a breakdown's reason (the loop's own exits need none)
    StepKind last = StepKind::START;
    double native_residual = 0.0, error = 0.0;
    while (true) {
        multipliers();
        native_residual = (phi + beta).norm();
        error = accuracy_from_gradient(qp, scale, x, g, lambda).max();
        bool converged = loop.criterion_met(native_residual, error);
        if (converged) {  // confirm at an exact gradient
            g = a_product(a_op, x) - qp.b;
            ++cnt.a_products;
            gradients();
            multipliers();
            native_residual = (phi + beta).norm();
            converged = loop.criterion_met(native_residual,
                                           [&] { return accuracy_from_gradient(qp, scale, x, g, lambda).max(); });
            p = z;
        }
        IterationInfo info;
        info.iteration = cnt.iterations;
        info.step = last;
        info.x = &x;
        info.lambda = &lambda;
        info.native_residual = native_residual;
        info.counters = &cnt;
        if (!loop.notify(info)) {
            status = SolveStatus::STOPPED_BY_MONITOR;
            break;
        }
        // The exit checks in the loop's order (a non-finite residual never counts as converged).
        status = loop.check(cnt.iterations, std::isfinite(native_residual), converged);
        if (status != SolveStatus::NOT_RUN) break;
        ++cnt.iterations;
        if (beta.squaredNorm() <= m_settings.gamma * m_settings.gamma * phitilde_dot_phi()) {
            a_product(a_op, p, Ap);
            ++cnt.a_products;
            const double pap = p.dot(Ap);
            if (!(pap > 0.0)) {
                status = pap == 0.0 ? SolveStatus::STALLED : SolveStatus::DIVERGED;
                why = "p'Ap <= 0";
                break;
            }
            const double alpha_cg = z.dot(g) / pap;
            double alpha_f = inf;  // largest feasible step along -p
            for (Eigen::Index j = 0; j < n; ++j) {
                if (p[j] > 0.0 && std::isfinite(lower[j]))
                    alpha_f = std::min(alpha_f, (x[j] - lower[j]) / p[j]);
                else if (p[j] < 0.0 && std::isfinite(upper[j]))
                    alpha_f = std::min(alpha_f, (x[j] - upper[j]) / p[j]);
            }
            if (alpha_cg <= alpha_f) {
                x -= alpha_cg * p;
                g -= alpha_cg * Ap;
                const std::vector<char> lo_before = at_lower, up_before = at_upper;
                classify();
                gradients();
                if (lo_before == at_lower && up_before == at_upper) {
                    p = z - (z.dot(Ap) / pap) * p;
                } else {
                    p = z;  // the face changed: restart the conjugate directions
                }
                ++cnt.cg_steps;
                last = StepKind::CG;
            } else {
                // Feasible half step, then the expansion step with the fixed length alpha_bar.
                x -= alpha_f * p;
                g -= alpha_f * Ap;
                x = x.cwiseMax(lower).cwiseMin(upper);  // rounding at the bound hit
                classify();
                gradients();
                x = (x - alpha_bar * phi).cwiseMax(lower).cwiseMin(upper);
                ++cnt.projections;
                g = a_product(a_op, x) - qp.b;
                ++cnt.a_products;
                classify();
                gradients();
                p = z;
                ++cnt.expansion_steps;
                last = StepKind::EXPANSION;
            }
        } else {
            a_product(a_op, beta, Ap);
            ++cnt.a_products;
            const double dad = beta.dot(Ap);
            if (!(dad > 0.0)) {
                status = SolveStatus::STALLED;
                why = "beta'A beta <= 0";
                break;
            }
            const double alpha_p = g.dot(beta) / dad;
            x -= alpha_p * beta;
            g -= alpha_p * Ap;
            classify();
            gradients();
            p = z;
            ++cnt.proportioning_steps;
            last = StepKind::PROPORTIONING;
        }
    }
    g = a_product(a_op, x) - qp.b;
    ++cnt.a_products;
    classify();
    gradients();
    multipliers();
    native_residual = (phi + beta).norm();
    error = accuracy_from_gradient(qp, scale, x, g, lambda).max();
    result.x = x;
    result.lambda = lambda;
    result.counters = cnt;
    result.native_residual = native_residual;
    // The loop writes the reason of its own exits; a breakdown is the solver's word.
    const std::string figures = "accuracy error " + format_e(error, 3);
    return loop.finish(result, status,
                       !loop.owns(status) ? "mprgp-box: not converged: " + why + " (" + figures + ")" : figures);
}

}  // namespace cb
