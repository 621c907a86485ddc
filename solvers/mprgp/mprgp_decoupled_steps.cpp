// `mprgp` on decoupled rows: setup, the engine's steps (solvers/mprgp/mprgp_engine.hpp) and the
// returned point.
#include "solvers/mprgp/mprgp_decoupled.hpp"

#include "solvers/core/format_number.hpp"
#include "solvers/linalg/row_gather_prefetch.hpp"
#include "solvers/mprgp/decouple.hpp"

#include <algorithm>
#include <cmath>

namespace cb {

bool DecoupledMprgp::safeguard_steps(double f_before, double& f_now)
{
    return safeguard(f_before, f_now, m_st.safeguard_max, m_cnt, m_loop, [&] {
        m_x -= m_alpha_bar * m_g;
        project_x();
        refresh_gradient();
        return objective_from_gradient();
    });
}

void DecoupledMprgp::expansion_step()
{
    // m_tmp = d: the free gradient (Alg. 1) or the preconditioner's face direction, which on
    // stiff problems reaches the rows the CG chain was heading for where alpha_bar phi moves the
    // soft DOFs by almost nothing.
    switch (m_expansion.direction) {
    case ExpansionDirection::PRECONDITIONED:
        if (m_ichol && m_ic.ready())
            ichol_face_precondition(m_ic, m_J, m_rows, m_active, m_g, m_work, m_tmp, &m_cnt.work_flops);
        else
            jacobi_face_precondition(m_J, m_rows, m_active, m_dinv, m_g, m_tmp);
        ++m_cnt.precond_applications;
        break;
    case ExpansionDirection::PROJECTED_CG:  // without a rejected trial (expansion() takes it)
    case ExpansionDirection::FREE_GRADIENT:
        free_gradient(m_J, m_rows, m_active, m_g, m_tmp);  // phi(y)
        break;
    }
    double step = m_alpha_bar;
    if (m_expansion.length == StepLength::BARZILAI_BORWEIN) {
        step = m_bb_step.length(m_x, m_g, m_alpha_bar);
    } else if (m_expansion.length != StepLength::FIXED) {
        product(m_tmp, m_Ap);
        step = expansion_step_length(m_expansion.length, m_alpha_bar, m_tmp.dot(m_Ap), face_dot(m_tmp));
    }
    m_x -= step * m_tmp;
}

SolveStatus DecoupledMprgp::end_step(double f_before, double f_now, std::string& why)
{
    const bool ok = safeguard_steps(f_before, f_now);
    restart(true);
    if (m_bb) m_bb_step.record(m_x, m_g);
    if (!ok) {
        why = "in a safeguard loop";
        return SolveStatus::TIME_LIMIT;
    }
    if (m_recompute) m_f_proj_x = m_f_x;
    return SolveStatus::NOT_RUN;
}

SolveStatus DecoupledMprgp::expansion(std::string& why)
{
    const double f_before = m_f_x + m_corr_x;  // F(P(x))
    // expansion = projcg after a rejected trial: x = P(x - alpha_cg p), from the chain iterate.
    const double alpha_cg = m_expansion.direction == ExpansionDirection::PROJECTED_CG ? m_projcg.take() : 0.0;
    if (m_infeasible && alpha_cg == 0.0) {
        project_x();  // y = P(x)
        refresh_gradient();
    }
    active_rows(m_J, m_c, m_rows, m_x, m_active);
    if (alpha_cg > 0.0)
        m_x -= alpha_cg * m_p;
    else
        expansion_step();
    project_x();
    refresh_gradient();
    double f_now = objective_from_gradient();
    if (m_bb && alpha_cg == 0.0 && f_now > f_before) {
        // expansion = bb raised F: the fixed step from the same point (m_tmp still holds its phi).
        m_x = m_bb_step.start() - m_alpha_bar * m_tmp;
        project_x();
        refresh_gradient();
        f_now = objective_from_gradient();
        ++m_bb_fallbacks;
    }
    ++m_cnt.expansion_steps;
    return end_step(f_before, f_now, why);
}

SolveStatus DecoupledMprgp::proportioning(std::string& why)
{
    const double f_before = m_f_x;
    chopped_gradient(m_J, m_rows, m_active, m_g, m_tmp);  // d = beta
    product(m_tmp, m_Ap);
    const double dad = m_tmp.dot(m_Ap);
    const double gd = m_g.dot(m_tmp);
    if (!(dad > 0.0) || !std::isfinite(dad)) {
        why = "zero proportioning direction (beta'A beta = 0)";
        return SolveStatus::STALLED;
    }
    const double alpha_p = gd / dad;
    m_x -= alpha_p * m_tmp;
    // -beta keeps active rows feasible and free rows untouched (rows share no DOF), so the
    // projection is a no-op in exact arithmetic; refresh g only when it did move x.
    if (project_x() > 0)
        refresh_gradient();
    else
        m_g -= alpha_p * m_Ap;
    double f_now = objective_from_gradient();
    ++m_cnt.proportioning_steps;
    return end_step(f_before, f_now, why);
}

bool DecoupledMprgp::notify(StepKind step)
{
    IterationInfo info;
    info.iteration = m_cnt.iterations;
    info.step = step;
    info.x = &m_x;
    info.lambda = &m_lambda;
    info.native_residual = m_native;
    info.active_set_size = m_active_count;
    info.counters = &m_cnt;
    return m_loop.notify(info);
}

Evaluation DecoupledMprgp::evaluate(std::string& why)
{
    Evaluation e;
    if (m_face_factor_failed) {
        why = "precond=ichol: " + m_face_factor_error;
        e.broke = SolveStatus::DIVERGED;
        return e;
    }
    evaluate_rows();
    e.finite = std::isfinite(m_native);
    if (!e.finite) return e;
    // Converged means at a feasible x (an infeasible chain iterate ends in an expansion).
    e.converged = !m_infeasible && m_loop.criterion_met(m_native, [&] { return error_with_bodies(); });
    if (e.converged) {
        // Confirm at an exact gradient (the recursive g drifts along long chains); the
        // accuracy rule is confirmed by the common measure itself.
        refresh_gradient();
        restart();
        evaluate_rows();
        e.converged = m_loop.criterion_met(
            m_native, [&] { return accuracy_from_gradient(m_qp, m_scale, m_x, m_g, m_lambda).max(); });
    }
    return e;
}

bool DecoupledMprgp::proportional()
{
    // An infeasible chain iterate whose face problem is already solved cannot improve
    // along the frozen face: end the chain (the expansion step projects).
    const bool face_done = m_infeasible && m_loop.rule_holds(m_native, m_face_error);
    return !face_done && m_beta2 <= m_gamma2 * m_phitilde_phi;
}

double DecoupledMprgp::product_dot(const Vec& v, Vec& out, double& vg)
{
    double dot_g = 0.0;
    const char* in_row = m_rows.dof_in_row.data();
    // v is p: a pending p = z - beta p is formed inside the product's own pass
    const double vav = m_p_pending ? a_product_dots_next_direction(m_a_op, m_p, m_z, m_p_beta, out, m_g, in_row, dot_g)
                                   : a_product_dots(m_a_op, v, out, m_g, in_row, dot_g);
    m_p_pending = false;
    ++m_cnt.a_products;
    vg = dot_g + m_pg_rows;  // the row DOFs' part comes from evaluate_rows (face form, no cancellation)
    return vav;
}

Trial DecoupledMprgp::cg_trial(std::string& why)
{
    Trial t;
    double pg = 0.0;
    const double pap = product_dot(m_p, m_Ap, pg);
    if (!(pap > 0.0) || !std::isfinite(pap)) {
        if (m_native == 0.0 || pap == 0.0) {
            t.broke = SolveStatus::STALLED;
            why = "zero CG direction (p'Ap = 0) above tolerance";
        } else {
            t.broke = SolveStatus::DIVERGED;
            why = "p'Ap <= 0 or non-finite: A is not SPD?";
        }
        return t;
    }
    // Deflated directions: p'g = z'g only when V'g = 0 exactly; take the exact line minimiser.
    const double alpha = (m_deflate ? pg : m_rz) / pap;
    const double df = -alpha * pg + 0.5 * alpha * alpha * pap;  // F(x - alpha p) - F(x)
    // Both objectives decide on F(P(y)) - F(P(x)) formed from differences: its rounding
    // is relative to the decrease itself, not to |F| (docs/ALGORITHMS.md §3, setting `objective`).
    const double corr_y = projection_correction(alpha);
    const double delta = df + corr_y - m_corr_x;
    // An infeasible trial point must strictly decrease F(P(.)): otherwise a chain
    // converging to an infeasible face minimiser would never end.
    const bool accept = corr_y > 0.0 ? delta < 0.0 : delta <= 0.0;
    double f_proj_y = 0.0;
    if (m_recompute) f_proj_y = recompute_objective(alpha, delta, accept);
    // F(P(y)) went up: the chain ends with an (infeasible) trial point, an expansion follows.
    if (!accept) {
        m_projcg.rejected(alpha);
        return t;
    }
    cg_update(alpha, pap, df, corr_y, f_proj_y);
    t.accepted = true;
    return t;
}

void DecoupledMprgp::cg_update(double alpha, double pap, double df, double corr_y, double f_proj_y)
{
    // Fused update: x, g, z = D^-1 g and the dot products in one pass (DOFs in no
    // row; the rows' DOFs are summed below in face form, see face_dot).
    const CgUpdateSums sums =
        cg_update_pass(alpha, m_p, m_Ap, m_dinv, *m_stat_weight, m_rows.dof_in_row.data(), m_x, m_g, m_z);
    double zg = sums.zg, zap = sums.zap;
    const double gg = sums.gg, ginf = sums.ginf;
    if (m_ichol || m_deflate) {
        // The fused pass computed z = D^-1 g; replace it by the face direction (IC and/or balanced).
        face_precondition(m_z);
        zg = face_dot(m_z);
        zap = m_z.dot(m_Ap);
    } else {
        // Face correction of z on active rows (J_A z = 0) and the rows' part of the dots.
        const int* outer = m_J.outerIndexPtr();
        const int* inner = m_J.innerIndexPtr();
        const double* val = m_J.valuePtr();
        const bool prefetch = row_gather_prefetches(m_n);
        const std::array<const double*, 4> read = {m_z.data(), m_g.data(), m_Ap.data(), m_dinv.data()};
        for (Eigen::Index i = 0; i < m_m; ++i) {
            if (prefetch) prefetch_row_ahead(m_J, i, read);
            double t = 0.0;
            if (m_active[static_cast<size_t>(i)]) {
                double wg = 0.0, jg = 0.0;  // (W g)_i = J_i D^-1 g; J_i g
                for (int k = outer[i]; k < outer[i + 1]; ++k) {
                    wg += val[k] * m_z[inner[k]];
                    jg += val[k] * m_g[inner[k]];
                }
                const double mu = m_rows.r[i] * wg;
                t = jg * m_rows.inv_s[i];
                for (int k = outer[i]; k < outer[i + 1]; ++k) m_z[inner[k]] -= mu * val[k] * m_dinv[inner[k]];
            }
            for (int k = outer[i]; k < outer[i + 1]; ++k) {
                if (val[k] == 0.0) continue;
                const int j = inner[k];
                zg += m_z[j] * (m_g[j] - t * val[k]);
                zap += m_z[j] * m_Ap[j];
            }
        }
    }
    ++m_cnt.precond_applications;
    // p = z - beta p is left to the next trial's product, which forms it in its own pass
    // (evaluate_rows reads the rows' entries through p_at meanwhile).
    m_p_beta = zap / pap;
    m_p_pending = true;
    m_rz = zg;
    m_gg_out = gg;
    m_ginf_free = ginf;
    m_f_x += df;
    m_corr_x = corr_y;
    if (m_recompute) m_f_proj_x = f_proj_y;
    if (m_bb) m_bb_step.record(m_x, m_g);
    ++m_cnt.cg_steps;
}

SolverResult DecoupledMprgp::run()
{
    SolverResult result;
    const CommonSettings& common = m_st.common;
    result.info["precond"] = m_st.precond;
    result.info["objective"] = m_st.objective;
    if (!is_decoupled(m_J)) {
        result.status = SolveStatus::INVALID_INPUT;
        result.message = "mprgp: J is not decoupled (two rows touch the same vertex, vertex = column / 3); "
                         "decouple the problem first (decouple = authors | random | depth) or use mprgp-coupled";
        return m_loop.finish(result, result.status);
    }
    // --- setup: diagonal, row data, power method ---
    m_dinv = Vec::Ones(m_n);
    std::string refusal;
    if (m_st.precond == "jacobi" && !jacobi_inverse_diagonal(m_A, m_dinv, refusal))
        return m_loop.finish(result, SolveStatus::INVALID_INPUT, "mprgp: " + refusal);
    // Every string setting is read here, once: the steps read enums and flags.
    m_ichol = m_st.precond == "ichol";
    m_expansion = expansion_variant(m_st.expansion);
    m_bb = m_expansion.length == StepLength::BARZILAI_BORWEIN;
    m_recompute = m_st.objective == "recompute";
    m_gamma2 = m_st.gamma * m_st.gamma;
    if (m_st.deflation == "rigid") {
        m_loop.setup_phase("rows_and_diagonal");
        m_deflate = m_defl.build(m_A, m_J, m_qp.x0, RigidDeflation::SLOW_RAYLEIGH);
        m_cnt.a_products += m_defl.build_products();
        m_loop.setup_phase("deflation");  // the rigid modes and their products
    }
    m_rows = make_decoupled_rows(m_J, m_dinv);
    for (Eigen::Index i = 0; i < m_m; ++i) {
        if (m_rows.s[i] <= 0.0 && m_c[i] > active_tolerance(m_c[i])) {
            result.status = SolveStatus::INFEASIBLE;
            result.message = "mprgp: row " + std::to_string(i) + " of J is zero but c_i = " + std::to_string(m_c[i]) +
                             " > 0: the feasible set is empty";
            return m_loop.finish(result, result.status);
        }
    }
    m_loop.setup_phase("rows_and_diagonal");
    m_a_op.prepare(m_st.common.a_format, static_cast<int>(m_st.common.threads));
    m_loop.setup_phase("a_prepare");
    result.info["a_format"] = to_string(m_a_op.format());  // the storage the products read
    const PowerRule rule = m_st.alpha == "authors" ? PowerRule::AUTHORS : PowerRule::POWER;
    const long power_max = rule == PowerRule::AUTHORS ? 1001 : m_st.power_max;
    const PowerResult power = estimate_norm(m_a_op, m_ctx, rule, power_max, common, m_cnt, &m_loop);
    m_loop.setup_phase("power");
    // The power estimate approaches ||A|| from below; alpha_bar must stay <= 2 / ||A|| (Appendix B),
    // so our default rounds rho up by 1%. The authors' variant uses the estimate as is.
    const double rho = power.estimate * (rule == PowerRule::POWER ? 1.01 : 1.0);
    m_alpha_bar = rho > 0.0 ? 2.0 / rho : 1.0;
    result.info["power"] = {{"rule", m_st.alpha},
                            {"products", power.products},
                            {"estimate", power.estimate},
                            {"rho", rho},
                            {"warm_start", power.warm}};
    result.info["alpha_bar"] = m_alpha_bar;
    m_scale = accuracy_scale(m_qp);
    m_loop.setup_phase("measure_scale");
    m_stat_weight = m_dinv == m_scale.inv_diag ? &m_dinv : &m_scale.inv_diag;
    m_cnt.a_products += m_scale.a_products;
    const bool setup_in_time = m_loop.end_setup();
    result.info["power"]["seconds"] = m_loop.setup_phase_s("power");  // the power method's own time
    if (!setup_in_time) {
        result.counters = m_cnt;
        return m_loop.finish(result, SolveStatus::TIME_LIMIT);
    }

    // --- solve ---
    m_x = m_qp.x0;
    m_g.resize(m_n);
    m_z.resize(m_n);
    m_p.resize(m_n);
    m_Ap.resize(m_n);
    m_tmp.resize(m_n);
    m_work.resize(m_n);
    m_d = Vec::Zero(m_n);
    m_lambda = Vec::Zero(m_m);
    m_jx.resize(m_m);
    m_jg.resize(m_m);
    m_jp.resize(m_m);
    m_touched.reserve(static_cast<size_t>(m_J.nonZeros()));
    project_x();  // x = P(x0)
    refresh_gradient();
    restart(true);
    if (m_bb) m_bb_step.record(m_x, m_g);

    std::string why;  // a breakdown's reason (the loop's own exits need none)
    const SolveStatus status = run_mprgp(*this, m_loop, m_cnt, why);

    // --- final: x = P(x), lambda of Section 2 at the returned x (with an exact gradient) ---
    if (status != SolveStatus::CONVERGED) {
        project_x();
        refresh_gradient();
        restart();
    }
    evaluate_rows();
    result.native_residual = m_native;
    // The loop writes the reason of its own exits; a breakdown is the solver's word.
    // The whole measure at the returned point (m_error leaves out the bodies' rigid motion); a
    // converged run's message already states it.
    const std::string error =
        status == SolveStatus::CONVERGED
            ? std::string()
            : "accuracy error " + format_e(std::max(m_error, m_scale.body_motion(m_x, m_lambda)), 3) + ", ";
    const std::string figures = error + "||phi+beta|| " + format_e(m_native, 3) + "; " +
                                std::to_string(m_cnt.cg_steps) + " cg, " + std::to_string(m_cnt.expansion_steps) +
                                " expansion, " + std::to_string(m_cnt.proportioning_steps) + " proportioning steps";
    const std::string detail = !m_loop.owns(status) ? "mprgp: not converged: " + why + " (" + figures + ")"
                                                    : (why.empty() ? "" : why + "; ") + figures;
    result.x = m_x;
    result.lambda = m_lambda;
    result.lambda_fitted = false;
    result.counters = m_cnt;
    result.info["safeguard_firings"] = m_cnt.safeguard_steps;
    result.info["alpha_bar"] = m_alpha_bar;
    result.info["active_rows"] = m_active_count;
    if (m_bb) result.info["bb_fallbacks"] = m_bb_fallbacks;
    if (m_recompute)
        result.info["recompute"] = {{"trial_steps", m_trial_steps},
                                    {"direct_disagreements", m_direct_disagreements},
                                    {"direct_gap_max", m_direct_gap}};
    if (m_st.deflation != "none")
        result.info["deflation"] = {{"active", m_deflate},
                                    {"bodies", m_defl.components()},
                                    {"modes", m_defl.kept_modes()},
                                    {"rayleigh_min", m_defl.min_rayleigh_seen()},
                                    {"rayleigh_max", m_defl.max_rayleigh_seen()},
                                    {"galerkin_steps", m_galerkin_steps},
                                    {"faces", m_deflation_faces}};
    if (m_ichol)
        result.info["ichol"] = {{"factor_nonzeros", m_ic.factor_nonzeros()},
                                {"a_nonzeros", static_cast<long>(m_A.nonZeros())}};
    {
        IterationInfo info;
        info.iteration = m_cnt.iterations;
        info.step = StepKind::FINAL;
        info.x = &m_x;
        info.lambda = &m_lambda;
        info.native_residual = m_native;
        info.active_set_size = m_active_count;
        info.counters = &m_cnt;
        m_loop.notify(info);
    }
    return m_loop.finish(result, status, detail);
}
}  // namespace cb
