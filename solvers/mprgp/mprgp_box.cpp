// `mprgp-box`: Dostal's MPRGP for bounds (ALGORITHMS.md §5).
// Ref: Dostal 2009, Ch. 5: free/chopped gradients eq. (11)-(12) of Li et al. 2015, reduced
//      free gradient phitilde_i = min((x_i - l_i)/alpha_bar, phi_i) (and its upper-bound mirror),
//      feasible step length before the expansion step, Alg. 1-2.
#include "solvers/mprgp/mprgp_box.hpp"
#include "solvers/core/solve_loop.hpp"

#include "solvers/core/format_number.hpp"
#include "solvers/linalg/a_product.hpp"
#include "solvers/measure/accuracy.hpp"
#include "solvers/mprgp/bound_set.hpp"
#include "solvers/mprgp/bounds.hpp"
#include "solvers/mprgp/mprgp_feasible.hpp"
#include "solvers/mprgp/mprgp_kernels.hpp"
#include "solvers/mprgp/mprgp_parts.hpp"

#include <cmath>

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

SolverResult MprgpBoxSolver::solve(const QpView& qp, const SolveContext& context)
{
    return mprgp_box_solve(qp, m_settings, context);
}

SolverResult mprgp_box_solve(const QpView& qp, const MprgpBoxSettings& settings, const SolveContext& context)
{
    const CommonSettings& common = settings.common;
    const Eigen::Index n = qp.n(), m = qp.m();
    SolverResult result;
    SolveLoop loop("mprgp-box", qp, common, context);
    Counters cnt;
    result.x = qp.x0;
    result.lambda = Vec::Zero(m);
    // --- bounds from the rows (solvers/mprgp/bounds.hpp: one policy for what a bounds solver cannot take) ---
    const RowBounds bounds = bounds_from_rows(qp);
    if (bounds.status != SolveStatus::NOT_RUN)
        return loop.finish(
            result, bounds.status,
            "mprgp-box: " + bounds.why +
                (bounds.status == SolveStatus::NOT_APPLICABLE ? "; use mprgp (decoupled J) or mprgp-coupled" : ""));
    Vec dinv = Vec::Ones(n);
    std::string error;
    if (settings.precond == "jacobi" && !jacobi_inverse_diagonal(qp.A, dinv, error))
        return loop.finish(result, SolveStatus::INVALID_INPUT, "mprgp-box: " + error);
    loop.setup_phase("bounds_and_diagonal");
    AOperator a_op(qp);  // the product with A: 3x3 blocks when A has them, built in the setup
    a_op.prepare(common.a_format, static_cast<int>(common.threads));
    loop.setup_phase("a_prepare");
    result.info["a_format"] = to_string(a_op.format());  // the storage the products read
    const PowerResult power = estimate_norm(a_op, context, PowerRule::POWER, settings.power_max, common, cnt);
    loop.setup_phase("power");
    const double alpha_bar = fixed_step_length(power);
    result.info["alpha_bar"] = alpha_bar;
    result.info["power"] = {{"products", power.products}, {"estimate", power.estimate}, {"warm_start", power.warm}};
    const AccuracyScale scale = accuracy_scale(qp);
    loop.setup_phase("measure_scale");
    cnt.a_products += scale.a_products;
    if (!loop.end_setup()) return loop.finish(result, SolveStatus::TIME_LIMIT);

    // --- the MPRGP iteration (solvers/mprgp/mprgp_engine.hpp) over the bounds ---
    BoundSet set(qp, bounds, scale);
    FeasibleMprgpSteps<BoundSet> steps(set, a_op, qp.b, dinv, alpha_bar, settings.gamma, loop, cnt);
    steps.start(qp.x0);
    std::string why;  // a breakdown's reason (the loop's own exits need none)
    const SolveStatus status = run_mprgp(steps, loop, cnt, why);
    steps.final_evaluation();
    result.x = steps.x();
    result.lambda = *set.multipliers();
    result.counters = cnt;
    result.native_residual = steps.native_residual();
    // The loop writes the reason of its own exits; a breakdown is the solver's word.
    const std::string figures = "accuracy error " + format_e(steps.error(), 3);
    return loop.finish(result, status,
                       !loop.owns(status) ? "mprgp-box: not converged: " + why + " (" + figures + ")" : figures);
}

}  // namespace cb
