#pragma once
/// Corotated linear elasticity on linear tets, lumped mass.
/// Ref: Li et al. 2015, Sec. 3.1 (eq. 3-7); Mueller & Gross 2004 (corotated FEM).
///
/// Per tet with rest shape matrix Dm and deformation gradient F = Ds Dm^-1 = U S V' (SVD),
/// R = U V' is the rotation of the polar decomposition. Inversion-safe: when det(U V') < 0 the
/// column of U of the smallest singular value is negated, so det R = +1 always and the stretch
/// S = R'F = V Sigma' V' carries a negative singular value for an inverted tet.
/// Energy  Psi = vol * (mu |S - I|_F^2 + lambda/2 tr(S - I)^2);  its gradient (dR drops out)
/// P = R (2 mu (S - I) + lambda tr(S - I) I) is the rotated linear stress, f_a = -vol P g_a.
/// The stiffness holds R fixed: K_e = R K0_e R' with K0_e the linear-elastic 12x12 matrix.
#include "sim/tet_mesh.hpp"
#include "solvers/core/types.hpp"

#include <Eigen/Core>
#include <array>
#include <vector>

namespace cb::sim {

/// Isotropic material in SI units.
struct Material {
    double youngs = 1e6;    ///< Pa
    double poisson = 0.4;   ///< -
    double density = 1000;  ///< kg/m^3
    double mu() const { return youngs / (2.0 * (1.0 + poisson)); }
    double lambda() const { return youngs * poisson / ((1.0 + poisson) * (1.0 - 2.0 * poisson)); }
};

/// The elastic model of all bodies of a scene (one global vertex numbering).
class CorotatedFem {
public:
    /// @param rest  #V by 3 rest positions; @param tets positively oriented; one material per tet.
    CorotatedFem(const Positions& rest, const Tets& tets, const std::vector<Material>& materials);

    long vertices() const { return m_vertices; }
    long tet_count() const { return static_cast<long>(m_tets.rows()); }
    /// Lumped mass per vertex: density * volume / 4 from every incident tet (kg).
    const Vec& vertex_mass() const { return m_vertex_mass; }
    /// Rest volume per tet (m^3).
    const std::vector<double>& rest_volume() const { return m_volume; }

    /// Corotated elastic energy at x (3#V, J).
    double energy(const Vec& x) const;
    /// Gradient of the energy (= minus the elastic force) at x; also stores the rotations of x.
    void update(const Vec& x);
    const Vec& gradient() const { return m_gradient; }  ///< of the last update()
    /// Rotation of tet t at the last update().
    const Eigen::Matrix3d& rotation(long t) const { return m_rotation[static_cast<size_t>(t)]; }

    /// The sparsity pattern of K and A (3x3 blocks for every vertex pair sharing a tet; the
    /// diagonal is always present), values zero.
    const SpMat& pattern() const { return m_pattern; }
    /// values(out) = stiff_coef * K(rotations of last update) + diag(mass_coef * mass), into a
    /// matrix with pattern(). Reuses out's storage when it already has the pattern.
    void assemble(double mass_coef, double stiff_coef, SpMat& out) const;

private:
    long m_vertices = 0;
    Tets m_tets;
    std::vector<Eigen::Matrix<double, 4, 3>> m_grad;  ///< shape-function gradients g_a (rows)
    std::vector<double> m_volume, m_mu, m_lambda;
    std::vector<Eigen::Matrix3d> m_dm_inv;
    Vec m_vertex_mass;
    std::vector<Eigen::Matrix3d> m_rotation;
    Vec m_gradient;
    SpMat m_pattern;
    std::vector<std::array<int, 16>> m_block_pos;  ///< per tet, per (a,b): 3*position of b in row 3a
    std::vector<int> m_diag_pos;                   ///< value index of (i,i) for every DOF i
};

/// Polar rotation of F, inversion-safe (det = +1), and the stretch S = R'F.
void polar_rotation(const Eigen::Matrix3d& F, Eigen::Matrix3d& R, Eigen::Matrix3d& S);

}  // namespace cb::sim
