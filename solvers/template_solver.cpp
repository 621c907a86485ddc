// `template`: projected gradient descent on bound rows, the model of a contactbench solver
// (solvers/template_solver.hpp says what it shows; docs/STYLE.md §3 the rules it follows).
#include "solvers/template_solver.hpp"
#include "solvers/a_product.hpp"

#include "solvers/accuracy.hpp"
#include "solvers/solve_loop.hpp"

#include <cmath>
#include <limits>
#include <sstream>

namespace cb {

namespace {

/// Every setting of `template`, declared once (settings.hpp SettingsTable).
const SettingsTable<TemplateSettings>& template_settings_table()
{
    static const SettingsTable<TemplateSettings> table = SettingsTable<TemplateSettings>().number(
        "step_scale", &TemplateSettings::step_scale, 0.0, 1.999, "step t = step_scale / |A|_inf, in (0, 2)");
    return table;
}

}  // namespace

TemplateSettings TemplateSettings::from_json(const nlohmann::json& settings)
{
    SettingsReader reader(settings, "template");
    TemplateSettings s;
    s.common = reader.common();
    template_settings_table().read(reader, s);
    reader.finish();
    return s;
}

nlohmann::json TemplateSettings::to_json() const
{
    nlohmann::json j = common.to_json();
    template_settings_table().write(*this, j);
    return j;
}

std::vector<SettingDoc> template_setting_docs() { return template_settings_table().docs(); }

namespace {

/// Bounds lo <= x <= hi from bound rows; row_col[i] is the column of row i (-1 for a zero row).
struct Bounds {
    Vec lo, hi;
    std::vector<Eigen::Index> row_col;
    std::vector<double> row_coef;
};

/// The bounds of J, or an empty optional-like flag `ok = false` with the offending row in `why`.
bool bounds_from_rows(const QpView& qp, Bounds& out, std::string& why)
{
    const double inf = std::numeric_limits<double>::infinity();
    out.lo = Vec::Constant(qp.n(), -inf);
    out.hi = Vec::Constant(qp.n(), inf);
    out.row_col.assign(static_cast<size_t>(qp.m()), -1);
    out.row_coef.assign(static_cast<size_t>(qp.m()), 0.0);
    for (Eigen::Index i = 0; i < qp.m(); ++i) {
        for (SpMat::InnerIterator it(qp.J, i); it; ++it) {
            if (it.value() == 0.0) continue;
            if (out.row_col[static_cast<size_t>(i)] >= 0) {
                why = "row " + std::to_string(i) + " has more than one nonzero (bound rows only)";
                return false;
            }
            out.row_col[static_cast<size_t>(i)] = it.col();
            out.row_coef[static_cast<size_t>(i)] = it.value();
            const double bound = qp.c[i] / it.value();
            if (it.value() > 0)
                out.lo[it.col()] = std::max(out.lo[it.col()], bound);
            else
                out.hi[it.col()] = std::min(out.hi[it.col()], bound);
        }
        if (out.row_col[static_cast<size_t>(i)] < 0 && qp.c[i] > 0) {
            why = "row " + std::to_string(i) + " is zero but c > 0: no feasible point";
            return false;
        }
    }
    for (Eigen::Index j = 0; j < qp.n(); ++j)
        if (out.lo[j] > out.hi[j]) {
            why = "x_" + std::to_string(j) + " has lower bound above upper bound";
            return false;
        }
    return true;
}

/// Multipliers of the active rows: J_i' lambda_i carries g on its column (g_j = a lambda_i).
Vec bound_multipliers(const QpView& qp, const Bounds& bounds, const Vec& x, const Vec& g)
{
    Vec lambda = Vec::Zero(qp.m());
    std::vector<char> taken(static_cast<size_t>(qp.n()), 0);
    for (Eigen::Index i = 0; i < qp.m(); ++i) {
        const Eigen::Index j = bounds.row_col[static_cast<size_t>(i)];
        if (j < 0 || taken[static_cast<size_t>(j)]) continue;  // one row per column carries g_j
        const double a = bounds.row_coef[static_cast<size_t>(i)];
        if (std::abs(a * x[j] - qp.c[i]) <= active_tolerance(qp.c[i])) {
            lambda[i] = g[j] / a;
            taken[static_cast<size_t>(j)] = 1;
        }
    }
    return lambda;
}

}  // namespace

SolverResult TemplateSolver::solve(const QpView& qp, const SolveContext& context)
{
    SolverResult result;
    Counters& counters = result.counters;
    const CommonSettings& common = m_settings.common;
    // The solve-loop protocol (solvers/solve_loop.hpp): the clock starts here, with setup.
    SolveLoop loop("template", qp, common, context);

    // --- setup: bounds and step length (setup_s = the time until end_setup) ---
    Bounds bounds;
    std::string why;
    if (!bounds_from_rows(qp, bounds, why)) {
        const bool infeasible = why.find("feasible") != std::string::npos || why.find("above") != std::string::npos;
        return loop.finish(result, infeasible ? SolveStatus::INFEASIBLE : SolveStatus::INVALID_INPUT, "",
                           "template: " + why);
    }
    double norm_inf = 0.0;  // max row sum of |A|, an upper bound of |A|_2
    for (Eigen::Index k = 0; k < qp.A.outerSize(); ++k) {
        double row = 0.0;
        for (SpMat::InnerIterator it(qp.A, k); it; ++it) row += std::abs(it.value());
        norm_inf = std::max(norm_inf, row);
    }
    const double step = norm_inf > 0 ? m_settings.step_scale / norm_inf : 1.0;
    const AccuracyScale scale = accuracy_scale(qp);
    counters.a_products += scale.a_products;
    // time_limit_s counts setup: a limit reached here ends the solve before any iteration.
    if (!loop.end_setup()) return loop.finish(result, SolveStatus::TIME_LIMIT, "", loop.time_limit_message());

    // --- solve ---
    Vec x = qp.x0.cwiseMax(bounds.lo).cwiseMin(bounds.hi);
    ++counters.projections;
    Vec g = a_product(qp.A, x) - qp.b;
    ++counters.a_products;
    Vec lambda = bound_multipliers(qp, bounds, x, g);
    auto native = [&]() {  // |x - P(x - g)|_inf: zero exactly at a solution
        return (x - (x - g).cwiseMax(bounds.lo).cwiseMin(bounds.hi)).lpNorm<Eigen::Infinity>();
    };
    auto monitor = [&](StepKind kind) {  // the clock is paused inside loop.notify
        IterationInfo info;
        info.iteration = counters.iterations;
        info.step = kind;
        info.x = &x;
        info.lambda = &lambda;
        info.native_residual = native();
        info.counters = &counters;
        return loop.notify(info);
    };
    SolveStatus status = monitor(StepKind::START) ? SolveStatus::NOT_RUN : SolveStatus::STOPPED_BY_MONITOR;
    while (status == SolveStatus::NOT_RUN) {
        // The exit checks in the protocol's order: non-finite, converged, iteration cap, time.
        status = loop.exit_status(
            x.allFinite() && g.allFinite(),
            [&] {
                return common.stop == StopRule::NATIVE ? native() <= common.tol
                                                       : accuracy_converged(qp, scale, x, g, lambda, common.tol);
            },
            counters.iterations);
        if (status != SolveStatus::NOT_RUN) break;
        x = (x - step * g).cwiseMax(bounds.lo).cwiseMin(bounds.hi);
        ++counters.projections;
        g.noalias() = a_product(qp.A, x) - qp.b;
        ++counters.a_products;
        lambda = bound_multipliers(qp, bounds, x, g);
        ++counters.iterations;
        if (!monitor(StepKind::OUTER)) status = SolveStatus::STOPPED_BY_MONITOR;
    }
    result.x = x;
    result.lambda = lambda;
    result.native_residual = native();
    std::ostringstream msg;
    if (status == SolveStatus::DIVERGED)
        msg << "template: non-finite iterate";
    else if (status == SolveStatus::TIME_LIMIT)
        msg << loop.time_limit_message();
    else
        msg << "template: " << to_string(status) << " after " << counters.iterations
            << " projected-gradient steps of length " << step;
    const std::string criterion =
        status != SolveStatus::CONVERGED ? "" : (common.stop == StopRule::NATIVE ? "native" : "kkt");
    return loop.finish(result, status, criterion, msg.str());
}

SolverEntry template_entry()
{
    SolverEntry entry;
    entry.make = [](const nlohmann::json& settings) -> std::unique_ptr<Solver> {
        return std::make_unique<TemplateSolver>(TemplateSettings::from_json(settings));
    };
    entry.description = "projected gradient on bound rows: the model solver to copy (not registered)";
    entry.settings = template_setting_docs();
    entry.applies_to = "bounds only (every row of J has at most one nonzero)";
    return entry;
}

}  // namespace cb
