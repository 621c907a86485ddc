// `mprgp-coupled`: setup, the engine's steps (solvers/mprgp/mprgp_engine.hpp) and the returned point.
#include "solvers/mprgp/mprgp_coupled_run.hpp"

#include "solvers/core/format_number.hpp"
#include "solvers/measure/work_units.hpp"

namespace cb {

bool CoupledRun::safeguard_steps(double f_before, double& f_now)
{
    return safeguard(f_before, f_now, m_st.safeguard_max, m_cnt, m_loop, [&] {
        m_x -= m_alpha_bar * m_g;
        project_x(false);
        exact_gradient();
        return objective_from_gradient();
    });
}

bool CoupledRun::expand()
{
    const double f_before = m_f_x + m_corr_x;  // F(P(x))
    // y = P(x) of the infeasible chain iterate, g(y) = g + A J'lam; with `face` the chain's frozen
    // face stays active here too (the safeguard below keeps F(P(x)) as the bound).
    if (!m_x_feasible) project_x(false, m_keep_face);
    const std::vector<char> face_before = m_active;
    restart(false, false);  // the face of P(x) and phi(P(x)); z is not needed to step along phi
    m_x -= m_alpha_bar * m_phi;
    project_x(false, m_keep_face);
    exact_gradient();
    double f_now = objective_from_gradient();
    ++m_cnt.expansion_steps;
    const bool ok = safeguard_steps(f_before, f_now);
    restart(true);
    if (m_active == face_before) ++m_stats.chain.expansions_same_face;
    return ok;
}

int CoupledRun::proportion()
{
    const double f_before = m_f_x;
    // beta = J_A'(nu - mu) (chopped_gradient's multipliers) is 0 off the face rows' DOFs: A beta
    // over its columns, as the projections' corrections, not a full A-product.
    for (Eigen::Index i = 0; i < m_m; ++i) m_q[i] = m_nu[i] - m_mu[i];
    build_d(m_q);
    const double dad = d_a_d();
    double gb = 0.0;
    for (int j : m_touched) gb += m_g[j] * m_d[j];
    m_cnt.work_flops += 2.0 * sparse_product_flops(touched_nonzeros());
    if (!(dad > 0.0) || !std::isfinite(dad)) {
        clear_d();
        return 0;
    }
    const double alpha_p = gb / dad;
    for (int j : m_touched) {
        m_d[j] *= -alpha_p;
        m_x[j] += m_d[j];
    }
    add_a_d(m_g);  // g -= alpha_p A beta
    clear_d();
    project_x(false);  // -beta may leave the set when rows are coupled (Sec. 4.4)
    double f_now = objective_from_gradient();
    ++m_cnt.proportioning_steps;
    const bool ok = safeguard_steps(f_before, f_now);
    restart(true);
    return ok ? 1 : -1;
}

bool CoupledRun::criterion()
{
    // m_error holds every part but the bodies' rigid motion (solvers/measure/body_motion.hpp): added only
    // when the rest already meets the rule, the one time it can change the decision.
    auto error_with_bodies = [&]() {
        if (!m_loop.rule_holds(m_native, m_error)) return m_error;
        return std::max(m_error, bodies_motion());
    };
    return m_x_feasible && m_loop.criterion_met(m_native, error_with_bodies);
}

Evaluation CoupledRun::evaluate(std::string&)
{
    Evaluation e;
    evaluate();
    e.converged = criterion();
    if (e.converged) {
        // Confirm at the exact gradient: the recurrence g -= alpha Ap drifts, and on
        // ill-conditioned problems the drift alone can fake convergence.
        exact_gradient();
        restart();
        evaluate();
        e.converged = criterion();
        // The returned point is P(x) with the rows met exactly: judge that one, and go on
        // from it when the small move of the projection undid the rule.
        // project_x updates g by A J'lam over the moved DOFs, exactly: no second full product.
        if (e.converged && project_x(true)) {
            restart();
            evaluate(true);
            e.converged = criterion();
        }
    }
    e.finite = std::isfinite(m_native);
    return e;
}

bool CoupledRun::notify(StepKind last)
{
    IterationInfo info;
    info.iteration = m_cnt.iterations;
    info.step = last;
    info.x = &m_x;
    info.lambda = m_chopped_exact ? &m_mu : nullptr;
    info.native_residual = m_native;
    info.active_set_size = static_cast<long>(std::count(m_active.begin(), m_active.end(), 1));
    info.counters = &m_cnt;
    return m_loop.notify(info, [this](IterationInfo& shown) { monitor_view(shown); });
}

bool CoupledRun::proportional()
{
    // An infeasible chain iterate whose face problem is solved cannot improve along the face.
    if (!m_x_feasible && m_loop.rule_holds([&] { return std::sqrt(m_phi2); }, m_face_error)) {
        ++m_stats.chain.face_done_expansions;
        return false;
    }
    const bool proportional = proportional_test(m_gamma2);
    if (!proportional && !m_x_feasible) ++m_stats.chain.infeasible_not_proportional;
    return proportional;
}

SolveStatus CoupledRun::expansion(std::string& why)
{
    if (expand()) return SolveStatus::NOT_RUN;
    why = "time limit reached in a safeguard loop";
    return SolveStatus::TIME_LIMIT;
}

SolveStatus CoupledRun::proportioning(std::string& why)
{
    const int done = proportion();
    if (done > 0) return SolveStatus::NOT_RUN;
    if (done == 0) {
        why = "beta'A beta <= 0";
        return SolveStatus::STALLED;
    }
    why = "time limit reached in a safeguard loop";
    return SolveStatus::TIME_LIMIT;
}

Trial CoupledRun::cg_trial(std::string& why)
{
    // F(P(y)) - F(P(x)) in difference form
    Trial t;
    double pg = 0.0;  // p'phi = p'g on the chain's face, summed in the product's pass
    const double pap = m_p_pending
                           ? a_product_dots_next_direction(m_a_op, m_p, direction(), m_p_beta, m_Ap, m_phi, nullptr, pg)
                           : a_product_dots(m_a_op, m_p, m_Ap, m_phi, pg);
    m_p_pending = false;
    ++m_cnt.a_products;
    if (!(pap > 0.0) || !std::isfinite(pap)) {
        t.broke = pap == 0.0 ? SolveStatus::STALLED : SolveStatus::DIVERGED;
        why = "p'Ap <= 0";
        return t;
    }
    const double alpha = m_zphi / pap;                          // z'g = z'phi (z in null(J_A)), without cancellation
    const double df = -alpha * pg + 0.5 * alpha * alpha * pap;  // F(x - alpha p) - F(x)
    rows_times(m_p, m_jp);
    for (Eigen::Index i = 0; i < m_m; ++i) m_q[i] = m_c[i] - m_jx[i] + alpha * m_jp[i];
    ++m_cnt.projections;
    const long violated_rows = flag_violated(m_q, false);
    bool moved = violated_rows > 0;
    if (!moved && m_last_drift > 0) ++m_stats.chain.drift_only_trials;
    double corr_y = 0.0;
    if (moved) {
        const long pivots_before = m_cnt.lcp_iterations;
        moved = m_ops->projection_multipliers(m_q, m_violated, m_lam, m_cnt, nullptr, ProjectionUse::TRIAL) > 0;
        m_stats.lcp_by_use.trial += m_cnt.lcp_iterations - pivots_before;
    }
    if (moved) {
        // F(y + d) - F(y) = d'(g - alpha Ap) + 1/2 d'Ad, d = J' lam sparse.
        build_d(m_lam);
        double dg = 0.0;
        for (int j : m_touched) dg += m_d[j] * (m_g[j] - alpha * m_Ap[j]);
        corr_y = dg + 0.5 * d_a_d();
    }
    const double delta = df + corr_y - m_corr_x;
    const bool accept = moved ? delta < 0.0 : delta <= 0.0;
    clear_d();
    if (accept) {
        face_gradient(true, &m_Ap, alpha);  // x -= alpha p, g -= alpha Ap, then phi and z
        // p = z - beta p is left to the next trial's product, which forms it in its own pass
        m_p_beta = m_zap / pap;
        m_p_pending = true;
        m_f_x += df;
        m_corr_x = corr_y;
        m_x_feasible = !moved;
        if (moved) {
            ++m_stats.chain.accepted_infeasible_trials;
            m_stats.chain.violated_rows_accepted += violated_rows;
        }
        ++m_cnt.cg_steps;
        t.accepted = true;
        return t;
    }
    ++(moved ? m_stats.chain.rejected_infeasible_trials : m_stats.chain.rejected_feasible_trials);
    if (moved) {
        m_stats.chain.violated_rows_rejected += violated_rows;
        m_stats.chain.rejected_gain -= df;
        m_stats.chain.rejected_cost += corr_y;
    }
    return t;
}

SolverResult CoupledRun::run()
{
    const CommonSettings& common = m_st.common;
    SolverResult result;
    result.x = m_original.x0;
    result.lambda = Vec::Zero(m_m);
    if (m_choice.name == "scaled" && !m_scaled) {
        result.status = SolveStatus::INVALID_INPUT;
        result.message = m_st.deflation != "none"
                             ? "mprgp-coupled: precond=scaled takes deflation=none (rigid modes are of x, not of y)"
                             : "mprgp-coupled: precond=scaled needs a positive diagonal of A";
        if (!m_choice.rule.empty()) result.message += " (" + m_choice.rule + ")";
        return m_loop.finish(result, result.status);
    }
    m_loop.setup_phase("precond_and_scaling");  // the constructor's choice and scaled variables
    // Every string setting is read here, once: the steps read flags.
    m_jacobi = m_choice.name == "jacobi";
    m_keep_face = m_st.expansion_projection == "face";
    m_gamma2 = m_st.gamma * m_st.gamma;
    m_dinv = Vec::Ones(m_n);
    std::string refusal;
    if (m_jacobi && !jacobi_inverse_diagonal(m_A, m_dinv, refusal))
        return m_loop.finish(result, SolveStatus::INVALID_INPUT, "mprgp-coupled: " + refusal);
    CoupledOperatorOptions opt;
    opt.global = m_st.operators == "global";
    opt.jacobi = m_jacobi;
    opt.dense_max_rows = m_st.dense_max_rows;
    opt.sparse_max_updates = m_st.sparse_max_updates;
    opt.lcp_max_pivots = m_st.lcp_max_pivots;
    opt.pgs_max_sweeps = m_st.pgs_max_sweeps;
    m_ops = m_choice.components
                ? std::make_unique<CoupledFaceOperators>(m_J, m_dinv, opt, std::move(*m_choice.components))
                : std::make_unique<CoupledFaceOperators>(m_J, m_dinv, opt);
    m_gram = SpMat(m_J * m_J.transpose());
    m_loop.setup_phase("face_operators");
    if (m_choice.name == "ichol" || m_st.deflation == "rigid") {
        m_precond = std::make_unique<CoupledPreconditioner>(m_A, m_J, m_dinv, *m_ops, m_choice.name);
        std::string error;
        if (!m_precond->setup(m_st.deflation == "rigid", m_qp.x0, error, m_cnt)) {
            result.status = SolveStatus::DIVERGED;
            result.message = "mprgp-coupled: precond=ichol: " + error;
            return m_loop.finish(result, result.status);
        }
        m_loop.setup_phase("preconditioner");  // ichol's factor, the rigid modes
    }
    m_s = m_ops->row_norm2();
    for (Eigen::Index i = 0; i < m_m; ++i)
        if (!(m_s[i] > 0.0) && m_c[i] > active_tolerance(m_c[i])) {
            result.status = SolveStatus::INFEASIBLE;
            result.message = "mprgp-coupled: row " + std::to_string(i) + " is zero but c > 0: empty feasible set";
            return m_loop.finish(result, result.status);
        }
    m_loop.setup_phase("face_operators");  // the row norms: added to the part above
    m_a_op.prepare(m_st.common.a_format, static_cast<int>(m_st.common.threads));
    m_rows_of_a = std::make_unique<TouchedRowsOfA>(m_a_op, m_unscale, &m_J);
    m_loop.setup_phase("a_prepare");
    const PowerResult power = estimate_norm(m_a_op, m_ctx, PowerRule::POWER, m_st.power_max, common, m_cnt);
    m_loop.setup_phase("power");
    m_alpha_bar = fixed_step_length(power);
    m_scale = accuracy_scale(m_original);
    m_loop.setup_phase("measure_scale");
    m_cnt.a_products += m_scale.a_products;
    // precond = scaled: the residual in y is D^-1/2 that in x, so the measure's D^-1 weights act
    // on it as D^-1/2 = unscale; lengths, rows and multipliers are the same in both variables.
    if (m_unscale != nullptr) m_scale.inv_diag = m_scale.inv_diag.cwiseQuotient(*m_unscale);
    m_free_weight = m_scale.inv_diag;
    if (!m_loop.end_setup()) return m_loop.finish(result, SolveStatus::TIME_LIMIT);

    for (Vec* v : {&m_g, &m_phi, &m_z, &m_p, &m_Ap, &m_beta, &m_tmp, &m_x_ref, &m_g_ref}) v->setZero(m_n);
    m_d = Vec::Zero(m_n);
    for (Vec* v : {&m_jx, &m_jg, &m_jp, &m_jphi, &m_jdg, &m_q, &m_nu, &m_eta, &m_mu, &m_lam}) v->setZero(m_m);
    m_active.assign(static_cast<size_t>(m_m), 0);
    m_violated.assign(static_cast<size_t>(m_m), 0);
    m_mark.assign(static_cast<size_t>(m_n), 0);
    m_face_dof.assign(static_cast<size_t>(m_n), 0);
    m_face_dofs.reserve(static_cast<size_t>(m_J.nonZeros()));
    m_mu_bound.setZero(m_m);
    m_w_bound.setZero(m_m);
    m_touched.reserve(static_cast<size_t>(m_J.nonZeros()));

    // Translation invariance: positions enter only as differences from x_ref = P(x0), whose
    // gradient g_ref = A x_ref - b is formed once; F(v) - F(x_ref) and g(v) then round relative
    // to |A||v - x_ref|, not |A||v| (a scene 100 m from the origin gives the same decisions).
    m_x = m_qp.x0;
    project_x(true);
    m_x_ref = m_x;
    a_product(m_a_op, m_x, m_g_ref);
    ++m_cnt.a_products;
    m_g_ref -= m_qp.b;
    m_g = m_g_ref;
    restart(true);

    std::string why;  // a breakdown's reason (the loop's own exits need none)
    SolveStatus status = run_mprgp(*this, m_loop, m_cnt, why);

    // The returned point: P(x) with rows feasible exactly (no face tolerance), at an exact gradient.
    if (project_x(true) || status != SolveStatus::CONVERGED) {
        exact_gradient();
        restart();
        evaluate(true);
    }
    if (status == SolveStatus::CONVERGED && !criterion()) {
        status = SolveStatus::STALLED;
        why = "the criterion held before the final projection but not after it";
    }
    result.x = original_x(m_x);
    result.lambda = m_mu;
    result.counters = m_cnt;
    result.native_residual = m_native;
    result.info = {{"alpha_bar", m_alpha_bar},
                   {"power", {{"products", power.products}, {"estimate", power.estimate}, {"warm_start", power.warm}}},
                   {"precond", m_choice.name},
                   {"preconditioner", m_precond ? m_precond->stats() : nlohmann::json{{"precond", m_choice.name}}},
                   {"components", m_ops->stats()},
                   {"lcp_failures", m_ops->lcp_failures()},
                   {"safeguard_firings", m_cnt.safeguard_steps},
                   {"dependent_rows", "handled by a shift 1e-12 of the unit-diagonal-scaled Gram matrices"}};
    m_stats.fill(result.info);
    if (!m_choice.rule.empty()) result.info["precond_rule"] = m_choice.rule;
    result.info["a_format"] = to_string(m_a_op.format());  // the storage the products read
    // The loop writes the reason of its own exits; a breakdown is the solver's word.
    // The whole measure at the returned point (m_error leaves out the bodies' rigid motion); a
    // converged run's message already states it.
    std::string detail = "safeguard firings " + std::to_string(m_cnt.safeguard_steps);
    if (status != SolveStatus::CONVERGED)
        detail = "accuracy error " + format_e(std::max(m_error, bodies_motion()), 3) + ", " + detail;
    if (!m_loop.owns(status)) detail = "mprgp-coupled: not converged: " + why + " (" + detail + ")";
    if (m_ops->lcp_failures() > 0)
        detail += "; " + std::to_string(m_ops->lcp_failures()) + " LCP solves missed their tolerance";
    return m_loop.finish(result, status, detail);
}

}  // namespace cb
