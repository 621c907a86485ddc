// `template`: projected gradient descent on bound rows, the model of a contactbench solver
// (solvers/methods/template_solver.hpp says what it shows; docs/STYLE.md §3 the rules it follows).
// An MPRGP variant is not a new solver but a part of the MPRGP engine (solvers/mprgp/mprgp_parts.hpp and
// one registration line; docs/DESIGN.md "Adding an MPRGP variant").
#include "solvers/methods/template_solver.hpp"
#include "solvers/linalg/a_product.hpp"

#include "solvers/core/solve_loop.hpp"
#include "solvers/measure/accuracy.hpp"
#include "solvers/mprgp/bounds.hpp"

#include <cmath>
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
    return read_settings(settings, "template", template_settings_table());
}

nlohmann::json TemplateSettings::to_json() const { return write_settings(*this, template_settings_table()); }

SolverResult TemplateSolver::solve(const QpView& qp, const SolveContext& context)
{
    SolverResult result;
    Counters& counters = result.counters;
    const CommonSettings& common = m_settings.common;
    // The solve-loop protocol (solvers/core/solve_loop.hpp): the clock starts here, with setup.
    SolveLoop loop("template", qp, common, context);

    // --- setup: bounds and step length (setup_s = the time until end_setup) ---
    const RowBounds bounds = bounds_from_rows(qp);  // solvers/mprgp/bounds.hpp: one policy for what it cannot take
    if (bounds.status != SolveStatus::NOT_RUN) return loop.finish(result, bounds.status, "template: " + bounds.why);
    double norm_inf = 0.0;  // max row sum of |A|, an upper bound of |A|_2
    for (Eigen::Index k = 0; k < qp.A.outerSize(); ++k) {
        double row = 0.0;
        for (SpMat::InnerIterator it(qp.A, k); it; ++it) row += std::abs(it.value());
        norm_inf = std::max(norm_inf, row);
    }
    const double step = norm_inf > 0 ? m_settings.step_scale / norm_inf : 1.0;
    loop.setup_phase("bounds_and_step");  // each part of the setup by name in info.setup_phases_s
    AOperator a_op(qp);  // the product with A: 3x3 blocks when A has them, built in the setup
    a_op.prepare(common.a_format, static_cast<int>(common.threads));
    result.info["a_format"] = to_string(a_op.format());  // the storage the products read
    loop.setup_phase("a_prepare");
    const AccuracyScale scale = accuracy_scale(qp);  // in the setup, as in every solver
    counters.a_products += scale.a_products;
    loop.setup_phase("measure_scale");
    // time_limit_s counts setup: a limit reached here ends the solve before any iteration.
    if (!loop.end_setup()) return loop.finish(result, SolveStatus::TIME_LIMIT);

    // --- solve ---
    Vec x = qp.x0.cwiseMax(bounds.lower).cwiseMin(bounds.upper);
    ++counters.projections;
    Vec g = a_product(a_op, x) - qp.b;
    ++counters.a_products;
    Vec lambda = bound_multipliers(qp, bounds, g);
    auto native = [&]() {  // |x - P(x - g)|_inf: zero exactly at a solution
        return (x - (x - g).cwiseMax(bounds.lower).cwiseMin(bounds.upper)).lpNorm<Eigen::Infinity>();
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
        // The loop owns the stop rule: non-finite, the rule (native or accuracy), the cap, the time.
        status = loop.check(counters.iterations, x.allFinite() && g.allFinite(), native,
                            [&] { return accuracy_from_gradient(qp, scale, x, g, lambda).max(); });
        if (status != SolveStatus::NOT_RUN) break;
        x = (x - step * g).cwiseMax(bounds.lower).cwiseMin(bounds.upper);
        ++counters.projections;
        g.noalias() = a_product(a_op, x) - qp.b;
        ++counters.a_products;
        lambda = bound_multipliers(qp, bounds, g);
        ++counters.iterations;
        if (!monitor(StepKind::OUTER)) status = SolveStatus::STOPPED_BY_MONITOR;
    }
    result.x = x;
    result.lambda = lambda;
    result.native_residual = native();
    std::ostringstream detail;  // the loop writes the reason; this adds what only the solver knows
    detail << counters.iterations << " projected-gradient steps of length " << step;
    return loop.finish(result, status, detail.str());
}

SolverEntry template_entry()
{
    return solver_entry<TemplateSolver>("template", template_settings_table(),
                                        "projected gradient on bound rows: the model solver to copy (not registered)",
                                        "bounds only (every row of J has at most one nonzero)");
}

}  // namespace cb
