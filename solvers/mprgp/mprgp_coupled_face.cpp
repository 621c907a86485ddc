// `mprgp-coupled`: the evaluation of an iterate (phi, the chopped LCP deferred while bounds decide)
// and the proportioning test with its bounds.
#include "solvers/mprgp/mprgp_coupled_run.hpp"

#include "solvers/measure/accuracy_rows.hpp"

#include <limits>

namespace cb {

/// Projected coordinate-descent sweeps tried on the chopped problem's upper bound before its LCP.
constexpr int BOUND_SWEEPS = 8;

void CoupledRun::evaluate(bool exact)
{
    // J x comes from the last restart, moved by each accepted CG step (J x - alpha J p, the trial's
    // J p): every evaluate follows one of the two. (J phi as J g - G nu, also without a gather, took
    // the components' iterates 10x further from the global operators' on 251-step chains: the
    // difference cancels on the face rows.)
    rows_times(m_phi, m_jphi);
    // The parts of the accuracy error that do not depend on mu: the feasibility, and the
    // stationarity at DOFs no face row touches (there g - J_A'mu = g = phi for every mu): over every
    // DOF with the face DOFs weighted 0, in face_gradient's pass (m_stat_free), then the face DOFs alone.
    const double stat_free = m_stat_free;
    double stat_phi = stat_free;
    for (int j : m_face_dofs) stat_phi = std::max(stat_phi, std::abs(m_phi[j]) * m_scale.inv_diag[j]);
    m_face_error = stat_phi * m_scale.inv_length;
    RowParts feasibility;
    for (Eigen::Index i = 0; i < m_m; ++i) {
        const double inv_norm = m_scale.inv_row_norm[i];
        if (inv_norm == 0.0)
            feasibility.add_zero_row(m_c[i]);
        else
            feasibility.add_primal(m_jx[i] - m_c[i], inv_norm);
    }
    m_primal = feasibility.primal;
    // beta'beta = min over mu >= 0 of ||J_A'(nu - mu)||^2 <= its value at mu = max(nu, 0).
    for (Eigen::Index i = 0; i < m_m; ++i) m_q[i] = std::min(m_nu[i], 0.0);
    build_d(m_q);
    m_beta2_upper = 0.0;
    for (int j : m_touched) m_beta2_upper += m_d[j] * m_d[j];
    clear_d();
    m_chopped_exact = false;
    m_chopped_by_monitor = false;
    const double error_lower = std::max(stat_free, m_primal) * m_scale.inv_length;
    // ||phi + beta||^2 = ||phi||^2 + ||beta||^2 (beta in range(J_A'), phi in its complement):
    // both are lower bounds, so the rule can hold only when it holds on them.
    const bool may_converge = m_x_feasible && m_loop.rule_holds(std::sqrt(m_phi2), error_lower);
    if (exact || may_converge) {
        chopped_gradient(m_cnt, true);
        return;
    }
    // Bounds until the chopped LCP is needed: the criterion cannot hold, the monitor gets the exact
    // values from chopped_gradient in notify's prepare, the proportioning test tries the upper bound.
    m_beta2 = m_beta2_upper;
    m_native = std::sqrt(m_phi2 + m_beta2_upper);
    m_error = std::isfinite(error_lower) ? error_lower : std::numeric_limits<double>::infinity();
    ++m_stats.chopped.deferred;
}

void CoupledRun::chopped_gradient(Counters& cnt, bool solver_work)
{
    if (m_chopped_exact) {
        if (solver_work && m_chopped_by_monitor) {
            // The solver needs the solve the monitor had done: its work counts now, as without a monitor.
            m_cnt.lcp_iterations += m_monitor_chopped.lcp_iterations;
            m_cnt.pgs_sweeps += m_monitor_chopped.pgs_sweeps;
            m_cnt.cholmod_factorizations += m_monitor_chopped.cholmod_factorizations;
            m_cnt.cholmod_solves += m_monitor_chopped.cholmod_solves;
            m_cnt.work_flops += m_monitor_chopped.work_flops;
            m_stats.lcp_by_use.chopped += m_monitor_chopped.lcp_iterations;
            ++m_stats.chopped.solved;
            m_chopped_by_monitor = false;
        }
        return;
    }
    // q_A = J_A (g - phi) on the face rows for the chopped LCP; beta = J_A'(nu - mu).
    for (Eigen::Index i = 0; i < m_m; ++i) m_q[i] = m_active[static_cast<size_t>(i)] ? m_jg[i] - m_jphi[i] : 0.0;
    const long pivots_before = cnt.lcp_iterations;
    m_ops->chopped_multipliers(m_q, m_nu, m_mu, cnt);
    if (solver_work) {
        m_stats.lcp_by_use.chopped += cnt.lcp_iterations - pivots_before;
        ++m_stats.chopped.solved;
    }
    // beta = J_A'(nu - mu) lives on the face rows' DOFs (nu and mu are 0 off the face), so phi + beta =
    // g - J'mu differs from phi only there: ||phi + beta||^2 = phi'phi + sum beta_j (2 phi_j + beta_j)
    // (no cancellation: phi'beta = 0 to rounding) and the free DOFs' stationarity is evaluate's.
    for (Eigen::Index i = 0; i < m_m; ++i)
        if (m_nu[i] != m_mu[i]) row_axpy(m_J, i, m_nu[i] - m_mu[i], m_beta);
    // phi + beta = g - J'mu: the native residual and the measure's stationarity part together.
    double pb2 = m_phi2, stat = m_stat_free;
    m_beta2 = 0.0;
    for (int j : m_face_dofs) {
        const double r = m_phi[j] + m_beta[j];
        m_beta2 += m_beta[j] * m_beta[j];
        pb2 += m_beta[j] * (2.0 * m_phi[j] + m_beta[j]);
        stat = std::max(stat, std::abs(r) * m_scale.inv_diag[j]);
        m_beta[j] = 0.0;  // all of m_beta is 0 again
    }
    RowParts rows;  // the multiplier's parts; the primal part is evaluate's (m_primal)
    for (Eigen::Index i = 0; i < m_m; ++i) {
        const double inv_norm = m_scale.inv_row_norm[i];
        if (inv_norm != 0.0) rows.add_multiplier(m_jx[i] - m_c[i], m_mu[i], inv_norm, m_scale.length_per_multiplier[i]);
    }
    m_native = std::sqrt(pb2);
    const RowParts parts = rows.scaled(m_scale.inv_length, m_scale.inv_energy);
    const double error =
        std::max(std::max(std::max(stat, m_primal) * m_scale.inv_length, std::max(parts.dual, parts.complementarity)),
                 parts.gap);
    m_error = std::isfinite(error) ? error : std::numeric_limits<double>::infinity();
    m_chopped_exact = true;
}

bool CoupledRun::proportional_test(double gamma2)
{
    // No face multiplier negative: beta = 0, and at a feasible x phitilde'phi >= ||phitilde||^2 >= 0
    // (P is a projection onto a convex set), so the test holds without the projection of eq. (13).
    if (m_beta2_upper == 0.0 && m_x_feasible) {
        ++m_stats.chopped.proportional_without_beta;
        return true;
    }
    const double reduced = reduced_free_gradient_dot();
    const double bound = gamma2 * reduced;
    // beta'beta <= any ||J_A'(nu - mu)||^2 with mu >= 0 decides without the chopped LCP when the
    // bound passes. Tried first even when a monitor had mu computed: a monitor changes no decision.
    if (m_beta2_upper <= bound) {
        ++m_stats.chopped.proportional_by_bound;
        return true;
    }
    if (projected_sweeps_bound(bound)) {
        ++m_stats.chopped.proportional_by_sweeps;
        return true;
    }
    chopped_gradient(m_cnt, true);
    return m_beta2 <= bound;
}

bool CoupledRun::projected_sweeps_bound(double bound)
{
    // Coordinate descent on 1/2 ||r||^2, r = J_A'(nu - mu), mu >= 0, from mu = max(nu, 0): each
    // row step is exact and keeps mu feasible, so ||r||^2 only falls and bounds beta'beta at
    // every point. Done in the rows' space: w = J_A r = G (nu - mu) (G = J J', nu and mu zero off
    // the face), a row step reads w_i and moves w by a column of G, and ||r||^2 = (nu - mu)'w; the
    // m-vectors stay in cache where r's DOFs were gathered and scattered (flank_press frame 0:
    // 1052 face rows, 12 DOFs each). Row work, not counted in `work` (solvers/measure/work_units.hpp).
    const int* outer = m_gram.outerIndexPtr();
    const int* inner = m_gram.innerIndexPtr();
    const double* val = m_gram.valuePtr();
    m_w_bound.setZero();
    for (Eigen::Index i = 0; i < m_m; ++i) {
        m_mu_bound[i] = std::max(m_nu[i], 0.0);
        const double delta = m_nu[i] - m_mu_bound[i];
        if (delta == 0.0) continue;
        for (int k = outer[i]; k < outer[i + 1]; ++k) m_w_bound[inner[k]] += val[k] * delta;
    }
    bool decided = false;
    for (int sweep = 0; sweep < BOUND_SWEEPS && !decided; ++sweep) {
        for (Eigen::Index i = 0; i < m_m; ++i) {
            if (!m_active[static_cast<size_t>(i)]) continue;
            const double next = std::max(0.0, m_mu_bound[i] + m_w_bound[i] / m_s[i]);
            const double step = next - m_mu_bound[i];
            if (step == 0.0) continue;
            m_mu_bound[i] = next;
            for (int k = outer[i]; k < outer[i + 1]; ++k) m_w_bound[inner[k]] -= val[k] * step;
        }
        double r2 = 0.0;
        for (Eigen::Index i = 0; i < m_m; ++i)
            if (m_active[static_cast<size_t>(i)]) r2 += (m_nu[i] - m_mu_bound[i]) * m_w_bound[i];
        ++m_stats.chopped.bound_sweeps;
        decided = r2 <= bound;
    }
    return decided;
}

double CoupledRun::reduced_free_gradient_dot()
{
    ++m_cnt.projections;
    for (Eigen::Index i = 0; i < m_m; ++i) m_q[i] = m_c[i] - m_jx[i] + m_alpha_bar * m_jphi[i];
    if (flag_violated(m_q, false) == 0) return m_phi2;
    const long pivots_before = m_cnt.lcp_iterations;
    const long solved =
        m_ops->projection_multipliers(m_q, m_violated, m_lam, m_cnt, nullptr, ProjectionUse::REDUCED_GRADIENT);
    m_stats.lcp_by_use.reduced_gradient += m_cnt.lcp_iterations - pivots_before;
    if (solved == 0) return m_phi2;
    double lj = 0.0;
    for (Eigen::Index i = 0; i < m_m; ++i) lj += m_lam[i] * m_jphi[i];
    return m_phi2 - lj / m_alpha_bar;
}

}  // namespace cb
