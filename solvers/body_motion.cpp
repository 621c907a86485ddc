#include "solvers/body_motion.hpp"

#include <Eigen/Eigenvalues>
#include <cmath>
#include <limits>

namespace cb {

namespace {

int find_root(std::vector<int>& parent, int v)
{
    while (parent[static_cast<size_t>(v)] != v) {
        parent[static_cast<size_t>(v)] = parent[static_cast<size_t>(parent[static_cast<size_t>(v)])];
        v = parent[static_cast<size_t>(v)];
    }
    return v;
}

/// Eigenvalues below this fraction of a body's largest are modes the body cannot move.
constexpr double RANK_CUTOFF = 1e-12;

}  // namespace

BodyMotion::BodyMotion(const SpMat& A, const Vec& x0, double length)
{
    const Eigen::Index n = A.rows();
    if (n == 0) return;
    m_spatial = n % 3 == 0 && x0.size() == n;
    m_inv_length = length > 0.0 && std::isfinite(length) ? 1.0 / length : 1.0;
    const int dofs_per_node = m_spatial ? 3 : 1;
    const int nodes = static_cast<int>(n / dofs_per_node);

    std::vector<int> parent(static_cast<size_t>(nodes));
    for (int v = 0; v < nodes; ++v) parent[static_cast<size_t>(v)] = v;
    for (Eigen::Index r = 0; r < A.outerSize(); ++r)
        for (SpMat::InnerIterator it(A, r); it; ++it) {
            if (it.value() == 0.0) continue;  // a stored zero couples nothing
            const int a = find_root(parent, static_cast<int>(r) / dofs_per_node);
            const int b = find_root(parent, static_cast<int>(it.col()) / dofs_per_node);
            if (a != b) parent[static_cast<size_t>(a)] = b;
        }
    m_body.assign(static_cast<size_t>(nodes), -1);
    std::vector<int> id(static_cast<size_t>(nodes), -1);
    int bodies = 0;
    for (int v = 0; v < nodes; ++v) {
        const int root = find_root(parent, v);
        if (id[static_cast<size_t>(root)] < 0) id[static_cast<size_t>(root)] = bodies++;
        m_body[static_cast<size_t>(v)] = id[static_cast<size_t>(root)];
    }

    if (m_spatial) {
        std::vector<Eigen::Vector3d> centroid(static_cast<size_t>(bodies), Eigen::Vector3d::Zero());
        std::vector<double> count(static_cast<size_t>(bodies), 0.0);
        for (int v = 0; v < nodes; ++v) {
            const auto b = static_cast<size_t>(m_body[static_cast<size_t>(v)]);
            centroid[b] += x0.segment<3>(3 * v);
            count[b] += 1.0;
        }
        for (size_t b = 0; b < centroid.size(); ++b) centroid[b] /= count[b];
        m_offset.resize(nodes, 3);
        for (int v = 0; v < nodes; ++v)
            m_offset.row(v) =
                (x0.segment<3>(3 * v) - centroid[static_cast<size_t>(m_body[static_cast<size_t>(v)])]).transpose();
    }

    // E = V'AV per body, one pass over A. Row p of V (DOF p = 3v + a) has three nonzeros: the
    // translation a, and the rotations k != a, (e_k x d_v)_a / l.
    std::vector<Mat6> E(static_cast<size_t>(bodies), Mat6::Zero());
    auto mode_row = [&](Eigen::Index p, int idx[3], double val[3]) {
        if (!m_spatial) {
            idx[0] = 0;
            val[0] = 1.0;
            return 1;
        }
        const int a = static_cast<int>(p % 3);
        const auto d = m_offset.row(p / 3);
        idx[0] = a;
        val[0] = 1.0;
        // (e_k x d)_a for k = a+1 and a+2 (mod 3): +d_{a+2} and -d_{a+1}.
        const int k1 = (a + 1) % 3, k2 = (a + 2) % 3;
        idx[1] = 3 + k1;
        val[1] = d[k2] * m_inv_length;
        idx[2] = 3 + k2;
        val[2] = -d[k1] * m_inv_length;
        return 3;
    };
    for (Eigen::Index r = 0; r < A.outerSize(); ++r) {
        int ri[3], ci[3];
        double rv[3], cv[3];
        const int rn = mode_row(r, ri, rv);
        Mat6& Eb = E[static_cast<size_t>(m_body[static_cast<size_t>(r / dofs_per_node)])];
        for (SpMat::InnerIterator it(A, r); it; ++it) {
            if (it.value() == 0.0) continue;
            const int cn = mode_row(it.col(), ci, cv);
            for (int s = 0; s < rn; ++s)
                for (int t = 0; t < cn; ++t) Eb(ri[s], ci[t]) += rv[s] * it.value() * cv[t];
        }
    }

    m_pinv.assign(static_cast<size_t>(bodies), Mat6::Zero());
    for (size_t b = 0; b < E.size(); ++b) {
        if (!m_spatial) {
            if (E[b](0, 0) > 0.0 && std::isfinite(E[b](0, 0))) m_pinv[b](0, 0) = 1.0 / E[b](0, 0);
            continue;
        }
        if (!E[b].allFinite()) continue;  // not SPD: the Jacobi half of the measure still judges it
        const Eigen::SelfAdjointEigenSolver<Mat6> eig(0.5 * (E[b] + E[b].transpose()));
        const Vec6 lambda = eig.eigenvalues();
        const double cutoff = RANK_CUTOFF * lambda.maxCoeff();
        Vec6 inv = Vec6::Zero();
        for (int k = 0; k < kModes; ++k)
            if (lambda[k] > cutoff && lambda[k] > 0.0) inv[k] = 1.0 / lambda[k];
        m_pinv[b] = eig.eigenvectors() * inv.asDiagonal() * eig.eigenvectors().transpose();
    }
}

double BodyMotion::displacement(const Vec& r) const
{
    if (m_body.empty()) return 0.0;
    if (!r.allFinite()) return std::numeric_limits<double>::infinity();
    std::vector<Vec6> load(m_pinv.size(), Vec6::Zero());  // V'r per body
    const auto nodes = static_cast<Eigen::Index>(m_body.size());
    if (!m_spatial) {
        for (Eigen::Index v = 0; v < nodes; ++v) load[static_cast<size_t>(m_body[static_cast<size_t>(v)])][0] += r[v];
        double widest = 0.0;
        for (size_t b = 0; b < load.size(); ++b) widest = std::max(widest, std::abs(m_pinv[b](0, 0) * load[b][0]));
        return widest;
    }
    for (Eigen::Index v = 0; v < nodes; ++v) {
        Vec6& l = load[static_cast<size_t>(m_body[static_cast<size_t>(v)])];
        const Eigen::Vector3d f = r.segment<3>(3 * v);
        const Eigen::Vector3d d = m_offset.row(v).transpose();
        l.head<3>() += f;
        l.tail<3>() += d.cross(f) * m_inv_length;  // (e_k x d)'f / l = e_k'(d x f) / l
    }
    std::vector<Vec6> motion(load.size());
    for (size_t b = 0; b < load.size(); ++b) motion[b] = m_pinv[b] * load[b];
    double widest = 0.0;
    for (Eigen::Index v = 0; v < nodes; ++v) {
        const Vec6& y = motion[static_cast<size_t>(m_body[static_cast<size_t>(v)])];
        const Eigen::Vector3d d = m_offset.row(v).transpose();
        const Eigen::Vector3d u = y.head<3>() + y.tail<3>().cross(d) * m_inv_length;
        widest = std::max(widest, u.cwiseAbs().maxCoeff());
    }
    return widest;
}

}  // namespace cb
