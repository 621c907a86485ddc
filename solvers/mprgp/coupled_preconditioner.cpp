// The CG direction of `mprgp-coupled` for precond = ichol and deflation = rigid
// (docs/preconditioners.md, "mprgp-coupled").
// Ref: Saad, Yeung, Erhel, Guyomarc'h, SIAM J. Sci. Comput. 21(5), 2000 (deflated PCG, Galerkin start);
//      Tang, Nabben, Vuik, Erlangga, J. Sci. Comput. 39, 2009 (balanced preconditioner).
#include "solvers/mprgp/coupled_preconditioner.hpp"

#include "solvers/measure/accuracy.hpp"
#include "solvers/mprgp/mprgp_kernels.hpp"

#include <algorithm>
#include <cmath>

namespace cb {

CoupledPreconditioner::CoupledPreconditioner(const SpMat& A, const SpMat& J, const Vec& dinv, CoupledFaceOperators& ops,
                                             std::string precond)
    : m_A(A), m_J(J), m_dinv(dinv), m_ops(ops), m_precond(std::move(precond))
{
}

bool CoupledPreconditioner::setup(bool rigid, const Vec& x0, std::string& error, Counters& cnt)
{
    const Eigen::Index n = m_A.rows(), m = m_J.rows();
    for (Vec* v : {&m_jv, &m_nu, &m_jx}) v->setZero(m);
    for (Vec* v : {&m_r, &m_w, &m_d, &m_ad}) v->setZero(n);
    m_ichol = m_precond == "ichol";
    if (m_ichol) {
        // A's own pattern, once: Q M^-1 Q is valid for any SPD M, so no face needs its own factor
        // (a face matrix Q A Q would be dense over each component's DOFs).
        if (!m_ic.factor(m_A, error, &cnt.work_flops)) return false;
        ++cnt.precond_factorizations;
    }
    m_rigid_asked = rigid;
    if (rigid) {
        m_deflate = m_defl.build(m_A, m_J, x0, RigidDeflation::SLOW_RAYLEIGH);
        cnt.a_products += m_defl.build_products();
    }
    return true;
}

void CoupledPreconditioner::project(Vec& v, Counters& cnt)
{
    for (Eigen::Index i = 0; i < m_J.rows(); ++i) m_jv[i] = row_dot(m_J, i, v);
    m_ops.face_multipliers(m_jv, m_nu, cnt);
    for (Eigen::Index i = 0; i < m_J.rows(); ++i)
        if (m_nu[i] != 0.0) row_axpy(m_J, i, -m_nu[i], v);
}

void CoupledPreconditioner::face_direction(const Vec& r, Vec& out, Counters& cnt)
{
    if (m_ichol) {
        m_w = r;
        project(m_w, cnt);
        m_ic.apply(m_w, out);
        cnt.work_flops += m_ic.apply_flops();
        project(out, cnt);  // J_A z = 0 to rounding whatever the incomplete factor's error
    } else if (m_precond == "jacobi") {
        // The D-weighted projection of the built-in jacobi: z = D^-1 (r - J_A' eta).
        m_w = m_dinv.cwiseProduct(r);
        for (Eigen::Index i = 0; i < m_J.rows(); ++i) m_jv[i] = row_dot(m_J, i, m_w);
        m_ops.jacobi_multipliers(m_jv, m_nu, cnt);
        out = r;
        for (Eigen::Index i = 0; i < m_J.rows(); ++i)
            if (m_nu[i] != 0.0) row_axpy(m_J, i, -m_nu[i], out);
        out = m_dinv.cwiseProduct(out);
    } else {
        out = r;
        project(out, cnt);
    }
}

void CoupledPreconditioner::update_face(const std::vector<char>& active, Counters& cnt)
{
    if (!m_deflate || (m_have_defl_face && m_defl_face == active)) return;
    // The face changed: V = Q W by 6 projections (Q of coupled rows is no sum of row terms, so
    // mprgp's row-by-row formula for V does not apply); AV and E follow V on the DOFs where it
    // changed, or anew with 6 A-products when those are many.
    const auto project_face = [&](Vec& v) { project(v, cnt); };
    if (m_defl.set_face_projected(m_A, project_face, &cnt.work_flops)) {
        cnt.a_products += RigidDeflation::MODES;
        ++m_full_face_updates;
    }
    m_defl_face = active;
    m_have_defl_face = true;
    ++m_deflation_faces;
}

void CoupledPreconditioner::apply(const std::vector<char>& active, const Vec& g, const Vec& phi, Vec& z, Counters& cnt)
{
    if (!m_deflate) {
        // phi = Q g already: z = Q M^-1 Q g needs one projection after M^-1 (or, jacobi, its own).
        if (m_ichol) {
            m_ic.apply(phi, z);
            cnt.work_flops += m_ic.apply_flops();
            project(z, cnt);
        } else {
            face_direction(g, z, cnt);
        }
        return;
    }
    update_face(active, cnt);
    // z = P' M_f^-1 P g + V E^+ V'g with P g = g - A V E^+ V'phi (V'g = V'phi, V in null(J_A)).
    m_defl.coarse(phi, m_d, m_ad);
    m_r = g - m_ad;
    face_direction(m_r, z, cnt);
    m_defl.deflate(z);
    z += m_d;
    cnt.work_flops += 2.0 * m_defl.apply_flops();
}

void CoupledPreconditioner::galerkin_steps(Vec& x, Vec& g, const Vec& c, const Vec& s, Counters& cnt)
{
    if (!m_deflate) return;
    const Eigen::Index m = m_J.rows();
    m_galerkin_face.assign(static_cast<size_t>(m), 0);
    Eigen::Index blocking = -1;
    // Each clipped step adds a row to the face: at most m + 1 steps, a few in practice.
    for (Eigen::Index repeat = 0; repeat <= m; ++repeat) {
        for (Eigen::Index i = 0; i < m; ++i) {
            m_jx[i] = row_dot(m_J, i, x);
            m_galerkin_face[static_cast<size_t>(i)] =
                s[i] > 0.0 && (std::abs(m_jx[i] - c[i]) <= active_tolerance(c[i]) || i == blocking);
        }
        m_ops.set_face(m_galerkin_face, cnt);
        update_face(m_galerkin_face, cnt);
        m_w = g;
        project(m_w, cnt);  // phi
        m_defl.coarse(m_w, m_d, m_ad);
        cnt.work_flops += m_defl.apply_flops();
        const double dg = m_d.dot(m_w);
        if (!(dg > 0.0) || !std::isfinite(dg)) return;
        // F(x - a d) = F(x) - a d'g + a^2/2 d'Ad with d'Ad = d'g: it falls for a in (0, 2); a <= 1
        // is clipped at the first free row the step would cross (face rows: J_A d = 0).
        double step = 1.0;
        blocking = -1;
        for (Eigen::Index i = 0; i < m; ++i) {
            if (m_galerkin_face[static_cast<size_t>(i)] || !(s[i] > 0.0)) continue;
            const double jd = row_dot(m_J, i, m_d);
            if (jd > 0.0 && m_jx[i] - c[i] < step * jd) {
                step = std::max(0.0, (m_jx[i] - c[i]) / jd);
                blocking = i;
            }
        }
        if (step > 0.0) {
            x -= step * m_d;
            g -= step * m_ad;
            ++m_galerkin_steps;
        }
        if (blocking < 0) return;
    }
}

nlohmann::json CoupledPreconditioner::stats() const
{
    nlohmann::json j = {{"precond", m_precond}};
    if (m_ichol)
        j["ichol"] = {{"factor_nonzeros", m_ic.factor_nonzeros()}, {"a_nonzeros", static_cast<long>(m_A.nonZeros())}};
    if (m_rigid_asked)
        j["deflation"] = {{"active", m_deflate},
                          {"bodies", m_defl.components()},
                          {"modes", m_defl.kept_modes()},
                          {"rayleigh_min", m_defl.min_rayleigh_seen()},
                          {"rayleigh_max", m_defl.max_rayleigh_seen()},
                          {"galerkin_steps", m_galerkin_steps},
                          {"faces", m_deflation_faces},
                          {"full_face_updates", m_full_face_updates}};
    return j;
}

}  // namespace cb
