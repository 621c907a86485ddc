// `mprgp` on decoupled rows: the row pass (residuals, multipliers, the measure), the face, its
// preconditioners (jacobi, ichol, rigid-mode deflation) and the projected objective's correction.
#include "solvers/linalg/row_gather_prefetch.hpp"
#include "solvers/mprgp/mprgp_decoupled.hpp"

#include "solvers/measure/accuracy_rows.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace cb {

double DecoupledMprgp::face_dot(const Vec& a) const
{
    double sum = 0.0;
    for (Eigen::Index j = 0; j < m_n; ++j)
        if (!m_rows.dof_in_row[static_cast<size_t>(j)]) sum += a[j] * m_g[j];
    const int* outer = m_J.outerIndexPtr();
    const int* inner = m_J.innerIndexPtr();
    const double* val = m_J.valuePtr();
    for (Eigen::Index i = 0; i < m_m; ++i) {
        const double t = m_active[static_cast<size_t>(i)] ? row_dot(m_J, i, m_g) * m_rows.inv_s[i] : 0.0;
        for (int k = outer[i]; k < outer[i + 1]; ++k)
            if (val[k] != 0.0) sum += a[inner[k]] * (m_g[inner[k]] - t * val[k]);
    }
    return sum;
}

void DecoupledMprgp::update_deflation_face()
{
    if (!m_defl_face.empty() && m_defl_face == m_active) return;
    if (m_defl.set_face(m_A, m_J, m_rows, m_active, &m_cnt.work_flops)) m_cnt.a_products += RigidDeflation::MODES;
    ++m_deflation_faces;
    m_defl_face = m_active;
}

void DecoupledMprgp::galerkin_steps()
{
    const int* outer = m_J.outerIndexPtr();
    const int* inner = m_J.innerIndexPtr();
    const double* val = m_J.valuePtr();
    // Each clipped step adds a row to the face: at most m repeats; a few suffice in practice.
    for (long repeat = 0; repeat <= m_m; ++repeat) {
        update_deflation_face();
        free_gradient(m_J, m_rows, m_active, m_g, m_tmp);  // phi: V'g in face form
        m_defl.coarse(m_tmp, m_gd, m_gad);
        m_cnt.work_flops += m_defl.apply_flops();
        const double dg = m_gd.dot(m_tmp);
        if (!(dg > 0.0) || !std::isfinite(dg)) return;
        // F(x - a d) decreases for a in (0, 2) (d'Ad = d'g): clip a <= 1 to the feasible set.
        double step = 1.0;
        long blocking = -1;
        for (Eigen::Index i = 0; i < m_m; ++i) {
            if (m_active[static_cast<size_t>(i)] || m_rows.s[i] <= 0.0) continue;
            double jd = 0.0, jx = 0.0;
            for (int k = outer[i]; k < outer[i + 1]; ++k) {
                jd += val[k] * m_gd[inner[k]];
                jx += val[k] * m_x[inner[k]];
            }
            if (jd > 0.0 && (jx - m_c[i]) < step * jd) {
                step = std::max(0.0, (jx - m_c[i]) / jd);
                blocking = i;
            }
        }
        if (step > 0.0) {
            m_x -= step * m_gd;
            m_g -= step * m_gad;
            ++m_galerkin_steps;
        }
        if (blocking < 0) return;
        active_rows(m_J, m_c, m_rows, m_x, m_active);
        m_active[static_cast<size_t>(blocking)] = 1;  // the row the step stopped at
        if (over_time()) return;
    }
}

void DecoupledMprgp::face_precondition(Vec& z)
{
    const Vec* g = &m_g;
    if (m_deflate) {
        // P g = g - A V y1 with y1 = E^+ V'g (V'g in face form); the coarse part V y1 is added back.
        free_gradient(m_J, m_rows, m_active, m_g, m_tmp);
        m_defl.coarse(m_tmp, m_gd, m_gad);
        m_tmp = m_g - m_gad;
        g = &m_tmp;
        m_cnt.work_flops += m_defl.apply_flops();
    }
    if (m_ichol) {
        if (m_ic.ready())
            ichol_face_precondition(m_ic, m_J, m_rows, m_active, *g, m_work, z, &m_cnt.work_flops);
        else
            z.setZero(m_n);
    } else {
        jacobi_face_precondition(m_J, m_rows, m_active, m_dinv, *g, z);
    }
    if (m_deflate) {
        m_defl.deflate(z);  // P' M^-1 P g
        z += m_gd;
        m_cnt.work_flops += m_defl.apply_flops();
    }
}

void DecoupledMprgp::restart(bool galerkin)
{
    m_p_pending = false;  // p = z below
    active_rows(m_J, m_c, m_rows, m_x, m_active);
    if (m_deflate) {
        if (galerkin) {
            galerkin_steps();
            active_rows(m_J, m_c, m_rows, m_x, m_active);
        }
        update_deflation_face();
    }
    if (m_ichol) {
        // The factor belongs to one face: rebuild it only when the face changed.
        // Q M^-1 Q is a valid (SPD on the face) preconditioner for any SPD M, so a factor of an
        // older face only costs quality: rebuild it when the face drifted by more than
        // ichol_refactor of the rows.
        long changed = 0;
        if (m_ic.ready())
            for (size_t i = 0; i < m_active.size(); ++i) changed += m_active[i] != m_face_factored[i];
        if (!m_ic.ready() || static_cast<double>(changed) > m_st.ichol_refactor * static_cast<double>(m_m)) {
            if (!m_ic.factor(face_matrix(m_A, m_J, m_rows, m_active, &m_cnt.work_flops), m_face_factor_error,
                             &m_cnt.work_flops))
                m_face_factor_failed = true;
            m_face_factored = m_active;
            ++m_cnt.precond_factorizations;
        }
    }
    face_precondition(m_z);
    ++m_cnt.precond_applications;
    m_p = m_z;
    m_rz = face_dot(m_z);
    m_gg_out = 0.0;
    m_ginf_free = 0.0;
    for (Eigen::Index j = 0; j < m_n; ++j)
        if (!m_rows.dof_in_row[static_cast<size_t>(j)]) {
            m_ginf_free = std::max(m_ginf_free, std::abs(m_g[j]) * m_scale.inv_diag[j]);
            m_gg_out += m_g[j] * m_g[j];
        }
    m_f_x = objective_from_gradient();
    m_corr_x = 0.0;
    m_f_proj_x = m_f_x;
}

double DecoupledMprgp::error_with_bodies()
{
    // m_error holds every part but the bodies' rigid motion (solvers/measure/body_motion.hpp): added only
    // when the rest already meets the rule, the one time it can change the decision.
    if (!m_loop.rule_holds(m_native, m_error)) return m_error;
    return std::max(m_error, m_scale.body_motion(m_x, m_lambda));
}

void DecoupledMprgp::evaluate_rows()
{
    const int* outer = m_J.outerIndexPtr();
    const int* inner = m_J.innerIndexPtr();
    const double* val = m_J.valuePtr();
    // Norms are summed part by part (DOFs outside every row, then each row's DOFs; rows share
    // no DOF), never as ||g||^2 minus the active part: that difference cancels catastrophically
    // when the active rows carry almost all of g near the solution.
    double beta2 = 0.0, pb2 = m_gg_out, phi2 = m_gg_out, ptp_corr = 0.0;
    double stat = m_ginf_free, pg_rows = 0.0;
    RowParts rows;  // the accuracy measure's row parts
    bool infeasible = false;
    long active_count = 0;
    const bool prefetch = row_gather_prefetches(m_n);
    const std::array<const double*, 5> read = {m_x.data(), m_g.data(), m_p.data(), m_z.data(), m_scale.inv_diag.data()};
    for (Eigen::Index i = 0; i < m_m; ++i) {
        if (prefetch) prefetch_row_ahead(m_J, i, read);
        double jx = 0.0, jg = 0.0, jp = 0.0;
        for (int k = outer[i]; k < outer[i + 1]; ++k) {
            const int j = inner[k];
            jx += val[k] * m_x[j];
            jg += val[k] * m_g[j];
            jp += val[k] * p_at(j);
        }
        m_jx[i] = jx;
        m_jg[i] = jg;
        m_jp[i] = jp;
        double lambda = 0.0, t = 0.0;
        if (m_active[static_cast<size_t>(i)]) {
            ++active_count;
            t = jg * m_rows.inv_s[i];
            lambda = std::max(0.0, t);
            beta2 += std::min(0.0, t) * std::min(0.0, t) * m_rows.s[i];
        } else if (m_rows.s[i] > 0.0) {
            if (jx < m_c[i] - active_tolerance(m_c[i])) infeasible = true;
            // Projection of x - alpha_bar phi on a free row (J_i phi = J_i g there).
            const double l = (m_c[i] - jx + m_alpha_bar * jg) * m_rows.inv_s[i];
            if (l > 0.0) ptp_corr += l * jg;
        }
        m_lambda[i] = lambda;
        for (int k = outer[i]; k < outer[i + 1]; ++k) {
            if (val[k] == 0.0) continue;
            const double gk = m_g[inner[k]];
            const double r_pb = gk - val[k] * lambda;  // (phi + beta)_k
            const double r_phi = gk - val[k] * t;      // phi_k
            pb2 += r_pb * r_pb;
            phi2 += r_phi * r_phi;
            pg_rows += p_at(inner[k]) * r_phi;
            stat = std::max(stat, std::abs(r_pb) * m_scale.inv_diag[inner[k]]);
        }
        rows.add_row(m_c[i], jx - m_c[i], lambda, m_scale.inv_row_norm[i], m_scale.length_per_multiplier[i]);
    }
    m_beta2 = beta2;
    m_pg_rows = pg_rows;
    // phitilde = phi - J' l / alpha_bar (eq. 13 through one projection).
    m_phitilde_phi = phi2 - ptp_corr / m_alpha_bar;
    m_native = std::sqrt(pb2);
    m_infeasible = infeasible;
    m_active_count = active_count;
    const RowParts parts = rows.scaled(m_scale.inv_length, m_scale.inv_energy);
    const double face =
        std::max(std::max(stat * m_scale.inv_length, std::max(parts.dual, parts.complementarity)), parts.gap);
    const double error = std::max(face, parts.primal);
    m_error = std::isfinite(error) ? error : std::numeric_limits<double>::infinity();
    m_face_error = std::isfinite(face) ? face : std::numeric_limits<double>::infinity();
}

double DecoupledMprgp::projection_correction(double alpha)
{
    // F(y + d) = F(y) + d'(Ay - b) + 1/2 d'Ad with d = J' lambda, lambda_i = max(0, (c_i - J_i y)/s_i).
    const int* outer = m_J.outerIndexPtr();
    const int* inner = m_J.innerIndexPtr();
    const double* val = m_J.valuePtr();
    double dg = 0.0;
    m_touched.clear();
    for (Eigen::Index i = 0; i < m_m; ++i) {
        // Active rows stay on their face (J_A p = 0 in exact arithmetic): their rounding-level
        // drift must not count as a violation, or it would swamp the tiny F decreases near
        // the solution.
        if (m_rows.s[i] <= 0.0 || m_active[static_cast<size_t>(i)]) continue;
        const double l = (m_c[i] - (m_jx[i] - alpha * m_jp[i])) * m_rows.inv_s[i];
        if (l <= 0.0) continue;
        double jgy = 0.0;
        for (int k = outer[i]; k < outer[i + 1]; ++k) {
            const int j = inner[k];
            jgy += val[k] * (m_g[j] - alpha * m_Ap[j]);
            m_d[j] += l * val[k];
            m_touched.push_back(j);
        }
        dg += l * jgy;
    }
    if (m_touched.empty()) return 0.0;
    ++m_cnt.projections;
    // d'Ad over the touched rows of A only (A symmetric, d sparse).
    const int* a_outer = m_A.outerIndexPtr();
    const int* a_inner = m_A.innerIndexPtr();
    const double* a_val = m_A.valuePtr();
    double dad = 0.0;
    for (int j : m_touched) {
        const double dj = m_d[j];
        if (dj == 0.0) continue;
        double s = 0.0;
        for (int k = a_outer[j]; k < a_outer[j + 1]; ++k) s += a_val[k] * m_d[a_inner[k]];
        dad += dj * s;
    }
    // Touched DOFs may repeat (explicit zeros, shared columns): clear after the sum.
    for (int j : m_touched) m_d[j] = 0.0;
    return dg + 0.5 * dad;
}

double DecoupledMprgp::recompute_objective(double alpha, double delta, bool accept)
{
    m_tmp = m_x - alpha * m_p;
    const long moved = project_decoupled(m_J, m_c, m_rows, m_tmp, m_tmp);
    ++m_cnt.projections;
    product(m_tmp, m_a_proj_y);
    const double f_proj_y = 0.5 * m_tmp.dot(m_a_proj_y) - m_b.dot(m_tmp);
    ++m_trial_steps;
    // The authors' rule compares the two F values: both round at about eps |F|, which exceeds
    // the decrease of a CG step near the solution, so it rejects steps that decrease F.
    const double direct = f_proj_y - m_f_proj_x;
    const bool direct_accept = moved > 0 ? direct < 0.0 : direct <= 0.0;
    if (direct_accept != accept) ++m_direct_disagreements;
    m_direct_gap = std::max(m_direct_gap, std::abs(direct - delta));
    return f_proj_y;
}

}  // namespace cb
