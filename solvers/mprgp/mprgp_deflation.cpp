#include "solvers/mprgp/mprgp_deflation.hpp"
#include "solvers/linalg/disjoint_sets.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <limits>
#include <numeric>

namespace cb {

bool RigidDeflation::build(const SpMat& A, const SpMat& J, const Vec& x0, double max_rayleigh)
{
    m_ready = false;
    m_build_products = 0;
    const Eigen::Index n = A.rows();
    if (n == 0 || n % 3 != 0 || x0.size() != n) return false;
    const int nv = static_cast<int>(n / 3);
    // Bodies = connected components of A's vertex graph (A couples no two bodies), joined by rows.
    DisjointSets sets(nv);
    const int* outer = A.outerIndexPtr();
    const int* inner = A.innerIndexPtr();
    for (Eigen::Index i = 0; i < n; ++i)
        for (int k = outer[i]; k < outer[i + 1]; ++k) sets.join(static_cast<int>(i / 3), inner[k] / 3);
    const int* j_outer = J.outerIndexPtr();
    const int* j_inner = J.innerIndexPtr();
    for (Eigen::Index i = 0; i < J.rows(); ++i)
        for (int k = j_outer[i] + 1; k < j_outer[i + 1]; ++k) sets.join(j_inner[j_outer[i]] / 3, j_inner[k] / 3);
    const std::vector<int> body = sets.labels(m_components);
    m_comp.assign(static_cast<size_t>(n), 0);
    for (size_t v = 0; v < static_cast<size_t>(nv); ++v)
        for (size_t d = 0; d < 3; ++d) m_comp[3 * v + d] = body[v];
    // Centroids, then translations e_d and rotations e_d x (p - centroid).
    Eigen::MatrixXd centroid = Eigen::MatrixXd::Zero(m_components, 3);
    Eigen::VectorXd count = Eigen::VectorXd::Zero(m_components);
    for (Eigen::Index v = 0; v < nv; ++v) {
        const int c = m_comp[static_cast<size_t>(3 * v)];
        centroid.row(c) += x0.segment<3>(3 * v).transpose();
        count[c] += 1.0;
    }
    for (int c = 0; c < m_components; ++c) centroid.row(c) /= count[c];
    m_W = Modes::Zero(n, MODES);
    for (Eigen::Index v = 0; v < nv; ++v) {
        const Eigen::Vector3d r = x0.segment<3>(3 * v) - centroid.row(m_comp[static_cast<size_t>(3 * v)]).transpose();
        for (int d = 0; d < 3; ++d) {
            m_W(3 * v + d, d) = 1.0;
            const Eigen::Vector3d rot = Eigen::Vector3d::Unit(d).cross(r);
            m_W.block<3, 1>(3 * v, 3 + d) = rot;
        }
    }
    // Keep the slow modes only: w'Aw against w'Dw per component and mode.
    const Modes AW = A * m_W;
    m_build_products = MODES;
    const Vec diag = A.diagonal();
    Eigen::MatrixXd w_a_w = Eigen::MatrixXd::Zero(m_components, MODES), w_d_w = w_a_w;
    for (Eigen::Index j = 0; j < n; ++j) {
        const int c = m_comp[static_cast<size_t>(j)];
        for (int k = 0; k < MODES; ++k) {
            w_a_w(c, k) += m_W(j, k) * AW(j, k);
            w_d_w(c, k) += m_W(j, k) * m_W(j, k) * diag[j];
        }
    }
    Eigen::MatrixXd keep = Eigen::MatrixXd::Zero(m_components, MODES);
    m_kept = 0;
    m_max_rayleigh_seen = 0.0;
    m_min_rayleigh_seen = std::numeric_limits<double>::infinity();
    for (int c = 0; c < m_components; ++c)
        for (int k = 0; k < MODES; ++k) {
            if (!(w_d_w(c, k) > 0.0)) continue;
            const double q = w_a_w(c, k) / w_d_w(c, k);
            m_max_rayleigh_seen = std::max(m_max_rayleigh_seen, q);
            m_min_rayleigh_seen = std::min(m_min_rayleigh_seen, q);
            if (q <= max_rayleigh) {
                keep(c, k) = 1.0;
                ++m_kept;
            }
        }
    for (Eigen::Index j = 0; j < n; ++j) m_W.row(j) = m_W.row(j).cwiseProduct(keep.row(m_comp[static_cast<size_t>(j)]));
    m_Einv.assign(static_cast<size_t>(m_components), Mat6::Zero());
    m_E = m_Einv;
    m_have_face = false;
    m_projected_ready = false;
    m_updates = 0;
    m_ready = m_kept > 0;
    return m_ready;
}

void RigidDeflation::reduce(const Modes& M, const Vec& v, Eigen::MatrixXd& R) const
{
    R.setZero(m_components, MODES);
    for (Eigen::Index j = 0; j < M.rows(); ++j) R.row(m_comp[static_cast<size_t>(j)]) += v[j] * M.row(j);
}

void RigidDeflation::expand(const Modes& M, const Eigen::MatrixXd& Y, Vec& out) const
{
    for (Eigen::Index j = 0; j < M.rows(); ++j) out[j] = M.row(j).dot(Y.row(m_comp[static_cast<size_t>(j)]));
}

RigidDeflation::ModeRow RigidDeflation::face_row(const SpMat& J, const DecoupledRows& rows, Eigen::Index i, int k,
                                                 bool is_active) const
{
    ModeRow v = m_W.row(J.innerIndexPtr()[k]);
    if (!is_active) return v;
    // Q W on row i: remove the normal component (rows share no DOF).
    const int* outer = J.outerIndexPtr();
    const int* inner = J.innerIndexPtr();
    const double* val = J.valuePtr();
    ModeRow t = ModeRow::Zero();
    for (int q = outer[i]; q < outer[i + 1]; ++q) t += val[q] * m_W.row(inner[q]);
    return v - val[k] * rows.inv_s[i] * t;
}

void RigidDeflation::invert(int c)
{
    Mat6 e = m_E[static_cast<size_t>(c)];
    e = 0.5 * (e + e.transpose()).eval();
    Eigen::SelfAdjointEigenSolver<Mat6> eig(e);
    const auto& ev = eig.eigenvalues();
    const double cut = 1e-10 * ev.cwiseAbs().maxCoeff();
    Eigen::Matrix<double, MODES, 1> inv = Eigen::Matrix<double, MODES, 1>::Zero();
    // Modes the face removes (or the dropped fast modes) have V'AV ~ 0: left out.
    for (int k = 0; k < MODES; ++k)
        if (ev[k] > cut && ev[k] > 0.0) inv[k] = 1.0 / ev[k];
    m_Einv[static_cast<size_t>(c)] = eig.eigenvectors() * inv.asDiagonal() * eig.eigenvectors().transpose();
}

void RigidDeflation::rebuild(const SpMat& A)
{
    m_AV = A * m_V;
    m_E.assign(static_cast<size_t>(m_components), Mat6::Zero());
    for (Eigen::Index j = 0; j < m_V.rows(); ++j)
        m_E[static_cast<size_t>(m_comp[static_cast<size_t>(j)])] += m_V.row(j).transpose() * m_AV.row(j);
    for (int c = 0; c < m_components; ++c) invert(c);
    m_updates = 0;
}

double RigidDeflation::update_row(const SpMat& A, int j, const ModeRow& delta, std::vector<int>& touched)
{
    // V_new'A V_new = E + Delta'(A V) + V_new'(A Delta), and A V += A Delta: both local to row j.
    const int* a_outer = A.outerIndexPtr();
    const int* a_inner = A.innerIndexPtr();
    const double* a_val = A.valuePtr();
    const int c = m_comp[static_cast<size_t>(j)];
    Mat6& e = m_E[static_cast<size_t>(c)];
    e += delta.transpose() * m_AV.row(j);
    m_V.row(j) += delta;
    for (int q = a_outer[j]; q < a_outer[j + 1]; ++q) {  // column j of A = row j (A symmetric)
        const ModeRow a_delta = a_val[q] * delta;
        m_AV.row(a_inner[q]) += a_delta;
        e += m_V.row(a_inner[q]).transpose() * a_delta;
    }
    touched.push_back(c);
    return 2.0 * MODES * (MODES + 2) * static_cast<double>(a_outer[j + 1] - a_outer[j] + 1);
}

void RigidDeflation::finish_updates(std::vector<int>& touched, double flops, double* work_flops)
{
    std::sort(touched.begin(), touched.end());
    touched.erase(std::unique(touched.begin(), touched.end()), touched.end());
    for (int c : touched) invert(c);
    if (work_flops) *work_flops += flops;
    ++m_updates;
}

bool RigidDeflation::set_face(const SpMat& A, const SpMat& J, const DecoupledRows& rows,
                              const std::vector<char>& active, double* work_flops)
{
    const int* outer = J.outerIndexPtr();
    const int* inner = J.innerIndexPtr();
    // Rows whose state changed since the last face, and their DOFs.
    long changed_dofs = 0;
    if (m_have_face)
        for (Eigen::Index i = 0; i < J.rows(); ++i)
            if (active[static_cast<size_t>(i)] != m_face[static_cast<size_t>(i)])
                changed_dofs += outer[i + 1] - outer[i];
    const bool full = !m_have_face || m_updates >= MAX_UPDATES || 20 * changed_dofs > m_W.rows();
    if (full) {
        m_V = m_W;
        for (Eigen::Index i = 0; i < J.rows(); ++i) {
            if (!active[static_cast<size_t>(i)]) continue;
            for (int k = outer[i]; k < outer[i + 1]; ++k) m_V.row(inner[k]) = face_row(J, rows, i, k, true);
        }
        rebuild(A);
    } else {
        // A few rows changed: V changes on their DOFs only (Delta), so
        // V_new'A V_new = E + Delta'(A V) + V_new'(A Delta), and A V += A Delta, both local.
        std::vector<int> touched_components;
        double flops = 0.0;
        for (Eigen::Index i = 0; i < J.rows(); ++i) {
            const bool now = active[static_cast<size_t>(i)] != 0;
            if (now == (m_face[static_cast<size_t>(i)] != 0)) continue;
            for (int k = outer[i]; k < outer[i + 1]; ++k) {
                const int j = inner[k];
                flops += update_row(A, j, face_row(J, rows, i, k, now) - m_V.row(j), touched_components);
            }
        }
        finish_updates(touched_components, flops, work_flops);
    }
    m_face = active;
    m_have_face = true;
    return full;
}

bool RigidDeflation::set_face_projected(const SpMat& A, const std::function<void(Vec&)>& project, double* work_flops)
{
    m_next.resize(m_W.rows(), MODES);
    Vec column(m_W.rows());
    for (int k = 0; k < MODES; ++k) {
        column = m_W.col(k);
        project(column);
        m_next.col(k) = column;
    }
    // DOFs whose row of V changed: those of the components whose face changed.
    m_changed.clear();
    if (m_projected_ready)
        for (Eigen::Index j = 0; j < m_next.rows(); ++j)
            if (m_next.row(j) != m_V.row(j)) m_changed.push_back(static_cast<int>(j));
    const bool full =
        !m_projected_ready || m_updates >= MAX_UPDATES || 20 * static_cast<Eigen::Index>(m_changed.size()) > m_W.rows();
    if (full) {
        m_V = m_next;
        rebuild(A);
    } else {
        // The row-by-row update of set_face() with Delta = V_new - V on the changed DOFs.
        std::vector<int> touched_components;
        double flops = 0.0;
        for (int j : m_changed) flops += update_row(A, j, m_next.row(j) - m_V.row(j), touched_components);
        finish_updates(touched_components, flops, work_flops);
    }
    m_projected_ready = true;
    m_have_face = false;  // set_face()'s row-by-row updates do not apply to this V
    return full;
}

void RigidDeflation::coarse(const Vec& g, Vec& d, Vec& ad) const
{
    Eigen::MatrixXd R;
    reduce(m_V, g, R);
    for (int c = 0; c < m_components; ++c)
        R.row(c) = (m_Einv[static_cast<size_t>(c)] * R.row(c).transpose()).transpose();
    d.resize(m_V.rows());
    ad.resize(m_V.rows());
    expand(m_V, R, d);
    expand(m_AV, R, ad);
}

void RigidDeflation::deflate(Vec& z) const
{
    Eigen::MatrixXd R;
    reduce(m_AV, z, R);
    for (int c = 0; c < m_components; ++c)
        R.row(c) = (m_Einv[static_cast<size_t>(c)] * R.row(c).transpose()).transpose();
    for (Eigen::Index j = 0; j < m_V.rows(); ++j) z[j] -= m_V.row(j).dot(R.row(m_comp[static_cast<size_t>(j)]));
}

}  // namespace cb
