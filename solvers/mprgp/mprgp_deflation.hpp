#pragma once
/// Rigid-mode deflation of MPRGP's CG chains (`mprgp` setting `deflation = rigid`,
/// docs/preconditioners.md). A nearly rigid body on a few contact points has its slowest modes
/// in the 6 rigid motions of each body: every new face restarts CG and pays again for them.
/// Here each face gets V = Q W (W: the rigid modes of each connected component of A, from the
/// positions x0; Q the face projector), a Galerkin step that minimises F over x + V y, and CG with
/// the balancing preconditioner z = P' M^-1 P g + V E^+ V'g (E = V'AV, P = I - A V E^+ V'), so
/// that no chain has to find those modes. After the Galerkin step (V'g = 0) its CG is deflated
/// PCG; unlike plain deflation it stays a PCG with an SPD preconditioner from any start.
/// Ref: Saad, Yeung, Erhel, Guyomarc'h, "A deflated version of the conjugate gradient
///      algorithm", SIAM J. Sci. Comput. 21(5), 2000 (deflated PCG, Galerkin start);
///      Tang, Nabben, Vuik, Erlangga, "Comparison of two-level preconditioners derived from
///      deflation, domain decomposition and multigrid methods", J. Sci. Comput. 39, 2009 (BNN).
#include "solvers/core/types.hpp"
#include "solvers/mprgp/mprgp_kernels.hpp"

#include <Eigen/Dense>
#include <functional>
#include <vector>

namespace cb {

class RigidDeflation {
public:
    static constexpr int MODES = 6;
    /// The slow-mode filter of build() that cg and mprgp use: a rigid mode w is kept when
    /// w'Aw <= 0.1 w'diag(A)w, only then a slow mode worth a coarse space (a stiff body's rigid
    /// modes see its mass only).
    static constexpr double SLOW_RAYLEIGH = 0.1;
    using Modes = Eigen::Matrix<double, Eigen::Dynamic, MODES>;

    /// Builds W from the connected components of the vertex graph (vertex = DOF / 3) of A and J
    /// (a row joins the bodies it touches, so that the face projector Q never mixes components)
    /// and the positions x0: 3 translations and 3 rotations about each component's centroid.
    /// A mode is kept only when it is a slow one: w'Aw <= max_rayleigh w'diag(A)w (a stiff
    /// body's rigid modes see only its mass; a random SPD matrix or a soft body has none).
    /// Returns false (deflation off) when n is not a multiple of 3 or no mode is kept.
    /// Costs MODES A-products.
    bool build(const SpMat& A, const SpMat& J, const Vec& x0, double max_rayleigh);
    /// Largest w'Aw / w'diag(A)w over the modes of build() (kept or not).
    double max_rayleigh_seen() const { return m_max_rayleigh_seen; }
    double min_rayleigh_seen() const { return m_min_rayleigh_seen; }
    int kept_modes() const { return m_kept; }
    /// A-products the last build() spent (MODES, or 0 when it returned before the slow-mode test).
    long build_products() const { return m_build_products; }
    /// V = Q W on the face `active`, AV = A V and the pseudo-inverse of each component's V'AV
    /// (modes that the face removes are dropped). When few rows changed since the last face, V, AV
    /// and V'AV are updated on those rows' DOFs only (flops added to *work_flops); otherwise they
    /// are formed anew with MODES A-products, and the call returns true.
    bool set_face(const SpMat& A, const SpMat& J, const DecoupledRows& rows, const std::vector<char>& active,
                  double* work_flops = nullptr);
    /// V = project(W) mode by mode, AV = A V and each component's (V'AV)^+. For a general J (`mprgp-coupled`), whose
    /// face projector is not row by row: `project` maps an n-vector onto the face in place and must keep each
    /// component's DOFs in that component (true of Q = I - J_A'(J_A J_A')^-1 J_A, since rows join the bodies they
    /// touch). As set_face(): when the new V differs from the last one on few DOFs (under n/20),
    /// AV and V'AV are updated on those DOFs only (flops added to *work_flops), else formed anew
    /// with MODES A-products, and the call returns true. Not to be mixed with set_face().
    bool set_face_projected(const SpMat& A, const std::function<void(Vec&)>& project, double* work_flops = nullptr);
    /// Coarse correction d = V y, y = (V'AV)^+ V'g, and Ad = AV y: F(x - d) = min over x + V y
    /// (the Galerkin step). `g` should be in face form (the free gradient).
    void coarse(const Vec& g, Vec& d, Vec& ad) const;
    /// z -= V (V'AV)^+ (AV)'z: z becomes A-conjugate to V (stays in the face).
    void deflate(Vec& z) const;
    bool ready() const { return m_ready; }
    int components() const { return m_components; }
    /// Flops of one deflate() or coarse(): two passes over the n x 6 modes.
    double apply_flops() const { return 4.0 * MODES * static_cast<double>(m_W.rows()); }

private:
    using ModeRow = Eigen::Matrix<double, 1, MODES>;
    using Mat6 = Eigen::Matrix<double, MODES, MODES>;
    /// Incremental face updates between two full ones (bounds the drift of V'AV).
    static constexpr int MAX_UPDATES = 50;
    /// Row of V at DOF inner[k] of row i: W's row, projected when the row is active.
    ModeRow face_row(const SpMat& J, const DecoupledRows& rows, Eigen::Index i, int k, bool is_active) const;
    /// m_Einv[c] = pseudo-inverse of m_E[c].
    void invert(int c);
    /// AV = A V, E = V'AV per component and their pseudo-inverses, from scratch (MODES A-products).
    void rebuild(const SpMat& A);
    /// V's row j += delta with AV and E updated locally; records j's component; returns the flops.
    double update_row(const SpMat& A, int j, const ModeRow& delta, std::vector<int>& touched);
    /// Re-inverts the touched components and counts one incremental update.
    void finish_updates(std::vector<int>& touched, double flops, double* work_flops);
    /// Per component: R(c, :) = sum over its DOFs of M(j, :) v_j.
    void reduce(const Modes& M, const Vec& v, Eigen::MatrixXd& R) const;
    /// out_j = M(j, :) Y(comp(j), :)'.
    void expand(const Modes& M, const Eigen::MatrixXd& Y, Vec& out) const;

    Modes m_W, m_V, m_AV;
    Modes m_next;                // set_face_projected(): the new V
    std::vector<int> m_changed;  // set_face_projected(): DOFs whose row of V changed
    bool m_projected_ready = false;
    std::vector<int> m_comp;  // #DOF: component of the DOF's vertex
    std::vector<Mat6> m_E, m_Einv;
    std::vector<char> m_face;  // the face V was built for
    bool m_have_face = false;
    int m_updates = 0;
    int m_components = 0;
    int m_kept = 0;
    long m_build_products = 0;
    double m_max_rayleigh_seen = 0.0, m_min_rayleigh_seen = 0.0;
    bool m_ready = false;
};

}  // namespace cb
