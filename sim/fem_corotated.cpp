#include "sim/fem_corotated.hpp"

#include <Eigen/LU>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>

namespace cb::sim {

void polar_rotation(const Eigen::Matrix3d& F, Eigen::Matrix3d& R, Eigen::Matrix3d& S)
{
    // Fast path: scaled Newton iteration X <- (g X + X^-T / g) / 2 (Higham 1986), which converges
    // quadratically to the polar rotation of a well-conditioned F with det F > 0, about 20x
    // cheaper than a 3x3 SVD. Inverted, flat or badly conditioned tets take the SVD path.
    const double det = F.determinant();
    const double fnorm = F.norm();
    if (det > 1e-6 * fnorm * fnorm * fnorm) {
        Eigen::Matrix3d X = F;
        bool converged = false;
        for (int k = 0; k < 20; ++k) {
            const Eigen::Matrix3d Xinv = X.inverse();
            const double g = std::sqrt(Xinv.norm() / X.norm());
            const Eigen::Matrix3d next = 0.5 * (g * X + Xinv.transpose() / g);
            const double change = (next - X).norm();
            X = next;
            if (change <= 1e-13) {
                converged = true;
                break;
            }
        }
        if (converged) {
            R = X;
            S = R.transpose() * F;
            return;
        }
    }
    Eigen::JacobiSVD<Eigen::Matrix3d, Eigen::NoQRPreconditioner> svd(F, Eigen::ComputeFullU | Eigen::ComputeFullV);
    Eigen::Matrix3d U = svd.matrixU();
    const Eigen::Matrix3d& V = svd.matrixV();
    R = U * V.transpose();
    if (R.determinant() < 0) {
        // Reflection: negate the direction of the smallest singular value (Eigen sorts them
        // descending), the smallest change that makes R a rotation (inverted tets push back).
        U.col(2) = -U.col(2);
        R = U * V.transpose();
    }
    S = R.transpose() * F;
}

CorotatedFem::CorotatedFem(const Positions& rest, const Tets& tets, const std::vector<Material>& materials)
    : m_vertices(static_cast<long>(rest.rows())), m_tets(tets)
{
    const size_t nt = static_cast<size_t>(tets.rows());
    m_grad.resize(nt);
    m_volume.resize(nt);
    m_mu.resize(nt);
    m_lambda.resize(nt);
    m_dm_inv.resize(nt);
    m_rotation.assign(nt, Eigen::Matrix3d::Identity());
    m_vertex_mass = Vec::Zero(m_vertices);
    for (size_t t = 0; t < nt; ++t) {
        const auto T = static_cast<Eigen::Index>(t);
        Eigen::Matrix3d Dm;
        for (int k = 0; k < 3; ++k) Dm.col(k) = (rest.row(tets(T, k + 1)) - rest.row(tets(T, 0))).transpose();
        m_volume[t] = Dm.determinant() / 6.0;
        m_dm_inv[t] = Dm.inverse();
        // F = sum_a x_a g_a'  with g_a = row a-1 of Dm^-1 (a = 1..3) and g_0 = -(g_1 + g_2 + g_3).
        for (int a = 1; a < 4; ++a) m_grad[t].row(a) = m_dm_inv[t].row(a - 1);
        m_grad[t].row(0) = -(m_grad[t].row(1) + m_grad[t].row(2) + m_grad[t].row(3));
        const Material& mat = materials[materials.size() == 1 ? 0 : t];
        m_mu[t] = mat.mu();
        m_lambda[t] = mat.lambda();
        for (int a = 0; a < 4; ++a) m_vertex_mass[tets(T, a)] += mat.density * m_volume[t] / 4.0;
    }
    m_gradient = Vec::Zero(3 * m_vertices);

    // Sparsity: vertex adjacency through tets, 3x3 blocks.
    std::vector<std::vector<int>> nbr(static_cast<size_t>(m_vertices));
    for (long i = 0; i < m_vertices; ++i) nbr[static_cast<size_t>(i)].push_back(static_cast<int>(i));
    for (size_t t = 0; t < nt; ++t)
        for (int a = 0; a < 4; ++a)
            for (int b = 0; b < 4; ++b)
                nbr[static_cast<size_t>(tets(static_cast<Eigen::Index>(t), a))].push_back(
                    tets(static_cast<Eigen::Index>(t), b));
    long nnz = 0;
    for (auto& list : nbr) {
        std::sort(list.begin(), list.end());
        list.erase(std::unique(list.begin(), list.end()), list.end());
        nnz += 9 * static_cast<long>(list.size());
    }
    const Eigen::Index n = 3 * m_vertices;
    m_pattern.resize(n, n);
    m_pattern.resizeNonZeros(nnz);
    int* outer = m_pattern.outerIndexPtr();
    int* inner = m_pattern.innerIndexPtr();
    double* values = m_pattern.valuePtr();
    long pos = 0;
    m_diag_pos.resize(static_cast<size_t>(n));
    for (long i = 0; i < m_vertices; ++i) {
        const auto& list = nbr[static_cast<size_t>(i)];
        for (int r = 0; r < 3; ++r) {
            outer[3 * i + r] = static_cast<int>(pos);
            for (int j : list)
                for (int s = 0; s < 3; ++s) {
                    if (j == i && s == r) m_diag_pos[static_cast<size_t>(3 * i + r)] = static_cast<int>(pos);
                    inner[pos] = 3 * j + s;
                    values[pos++] = 0.0;
                }
        }
    }
    outer[n] = static_cast<int>(pos);
    m_block_pos.resize(nt);
    for (size_t t = 0; t < nt; ++t)
        for (int a = 0; a < 4; ++a) {
            const auto& list = nbr[static_cast<size_t>(tets(static_cast<Eigen::Index>(t), a))];
            for (int b = 0; b < 4; ++b) {
                const int j = tets(static_cast<Eigen::Index>(t), b);
                m_block_pos[t][4 * static_cast<size_t>(a) + static_cast<size_t>(b)] =
                    3 * static_cast<int>(std::lower_bound(list.begin(), list.end(), j) - list.begin());
            }
        }
}

namespace {
Eigen::Matrix3d deformation_gradient(const Vec& x, const Tets& tets, Eigen::Index t, const Eigen::Matrix3d& dm_inv)
{
    Eigen::Matrix3d Ds;
    const Eigen::Vector3d x0 = x.segment<3>(3 * static_cast<Eigen::Index>(tets(t, 0)));
    for (int k = 0; k < 3; ++k) Ds.col(k) = x.segment<3>(3 * static_cast<Eigen::Index>(tets(t, k + 1))) - x0;
    return Ds * dm_inv;
}
}  // namespace

double CorotatedFem::energy(const Vec& x) const
{
    double e = 0.0;
    for (Eigen::Index t = 0; t < m_tets.rows(); ++t) {
        const size_t T = static_cast<size_t>(t);
        Eigen::Matrix3d R, S;
        polar_rotation(deformation_gradient(x, m_tets, t, m_dm_inv[T]), R, S);
        const Eigen::Matrix3d E = S - Eigen::Matrix3d::Identity();
        const double tr = E.trace();
        e += m_volume[T] * (m_mu[T] * E.squaredNorm() + 0.5 * m_lambda[T] * tr * tr);
    }
    return e;
}

void CorotatedFem::update(const Vec& x)
{
    m_gradient.setZero(3 * m_vertices);
    for (Eigen::Index t = 0; t < m_tets.rows(); ++t) {
        const size_t T = static_cast<size_t>(t);
        Eigen::Matrix3d R, S;
        polar_rotation(deformation_gradient(x, m_tets, t, m_dm_inv[T]), R, S);
        m_rotation[T] = R;
        // Linear stress of the unrotated strain; S is symmetric, so sym(S) - I = S - I.
        Eigen::Matrix3d E = S - Eigen::Matrix3d::Identity();
        E = 0.5 * (E + E.transpose());  // exact symmetry against round-off
        const Eigen::Matrix3d P = R * (2.0 * m_mu[T] * E + m_lambda[T] * E.trace() * Eigen::Matrix3d::Identity());
        for (int a = 0; a < 4; ++a)
            m_gradient.segment<3>(3 * static_cast<Eigen::Index>(m_tets(t, a))) +=
                m_volume[T] * (P * m_grad[T].row(a).transpose());
    }
}

void CorotatedFem::assemble(double mass_coef, double stiff_coef, SpMat& out) const
{
    if (out.rows() != m_pattern.rows() || out.nonZeros() != m_pattern.nonZeros()) out = m_pattern;
    double* v = out.valuePtr();
    std::fill(v, v + out.nonZeros(), 0.0);
    const int* outer = out.outerIndexPtr();
    for (Eigen::Index t = 0; t < m_tets.rows(); ++t) {
        const size_t T = static_cast<size_t>(t);
        const Eigen::Matrix3d& R = m_rotation[T];
        const Eigen::Matrix<double, 4, 3>& g = m_grad[T];
        Eigen::Matrix<double, 3, 4> rg = R * g.transpose();  // R g_a as columns
        const double cv = stiff_coef * m_volume[T];
        const double mu = cv * m_mu[T], la = cv * m_lambda[T];
        // R K0_ab R' = vol [mu (g_a.g_b) I + mu (R g_b)(R g_a)' + lambda (R g_a)(R g_b)'].
        for (int a = 0; a < 4; ++a) {
            const int i = m_tets(t, a);
            for (int b = 0; b < 4; ++b) {
                const double gg = mu * g.row(a).dot(g.row(b));
                const int off = m_block_pos[T][4 * static_cast<size_t>(a) + static_cast<size_t>(b)];
                for (int r = 0; r < 3; ++r) {
                    double* dst = v + outer[3 * i + r] + off;
                    for (int s = 0; s < 3; ++s)
                        dst[s] += mu * rg(r, b) * rg(s, a) + la * rg(r, a) * rg(s, b) + (r == s ? gg : 0.0);
                }
            }
        }
    }
    for (long i = 0; i < m_vertices; ++i)
        for (int r = 0; r < 3; ++r) v[m_diag_pos[static_cast<size_t>(3 * i + r)]] += mass_coef * m_vertex_mass[i];
}

}  // namespace cb::sim
