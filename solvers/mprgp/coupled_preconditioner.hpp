#pragma once
/// The CG direction of `mprgp-coupled` for `precond = ichol` and `deflation = rigid`
/// (ALGORITHMS.md §4, docs/preconditioners.md). The face projector onto null(J_A),
///   Q v = v - J_A' (J_A J_A')^-1 J_A v,
/// is dense over each component's DOFs, so no face matrix is factored: M ~ A is the incomplete
/// Cholesky factor of A itself (solvers/linalg/ichol.hpp), formed once, and the direction is
///   z = Q M^-1 Q g,
/// with Q applied through the per-component face solves of solvers/mprgp/coupled_face_operators.hpp.
/// Q M^-1 Q is symmetric and positive definite on null(J_A) for any SPD M, and J_A z = 0 to
/// rounding. With `rigid`, the slow rigid modes W of each body (solvers/mprgp/mprgp_deflation.hpp) are
/// projected on each new face, V = Q W, E = V'AV per body, and the direction is balanced:
///   z = P' M_f^-1 P g + V E^+ V'g,   P = I - A V E^+ V',
/// M_f^-1 the face preconditioner (ichol: Q M^-1 Q; jacobi: D^-1 (I - J_A'(J_A D^-1 J_A')^-1 J_A D^-1);
/// none: Q), still SPD on the face. galerkin_steps() moves x to the minimiser of F over x + V y,
/// clipped to the feasible set, as `mprgp` does after a start, an expansion or a proportioning step.
/// Ref: Saad, Yeung, Erhel, Guyomarc'h, SIAM J. Sci. Comput. 21(5), 2000 (deflated PCG);
///      Tang, Nabben, Vuik, Erlangga, J. Sci. Comput. 39, 2009 (balanced preconditioner).
#include "solvers/core/solver.hpp"
#include "solvers/core/types.hpp"
#include "solvers/linalg/ichol.hpp"
#include "solvers/mprgp/coupled_face_operators.hpp"
#include "solvers/mprgp/mprgp_deflation.hpp"

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace cb {

class CoupledPreconditioner {
public:
    /// @param precond  "none" | "jacobi" | "ichol": the face preconditioner M_f
    /// @param dinv     1 / diag(A) (read with precond = jacobi; `ops` then keeps the J D^-1 J' factors)
    /// @param ops      the run's face operators; their face must be the one apply() is given
    CoupledPreconditioner(const SpMat& A, const SpMat& J, const Vec& dinv, CoupledFaceOperators& ops,
                          std::string precond);
    /// Setup: the IC factor of A (ichol) and the rigid modes from x0 (rigid: 6 A-products).
    /// @return false with `error` set when the incomplete factorisation fails
    bool setup(bool rigid, const Vec& x0, std::string& error, Counters& cnt);
    /// Whether the rigid modes are in use (rigid asked and some body has a slow mode).
    bool deflating() const { return m_deflate; }
    /// z from g and phi = Q g on the face `active` (the face of ops); V, AV and E follow a face change.
    void apply(const std::vector<char>& active, const Vec& g, const Vec& phi, Vec& z, Counters& cnt);
    /// deflation = rigid, at a feasible x: repeat x -= a d, d = V E^+ V'phi the Galerkin correction,
    /// a = 1 clipped at the first free row it would cross (that row then joins the face). F falls at
    /// every step and x stays feasible. Leaves ops on its last face (the caller sets its own next).
    /// @param s  ||J_i||^2 (zero rows are never active)
    void galerkin_steps(Vec& x, Vec& g, const Vec& c, const Vec& s, Counters& cnt);
    /// {precond, ichol: {factor_nonzeros, a_nonzeros}, deflation: {active, bodies, modes, rayleigh_*,
    ///  galerkin_steps, faces, full_face_updates (the ones with 6 A-products)}}
    nlohmann::json stats() const;

private:
    /// v = Q v on the face of ops (J v, the per-component face solves, v -= J_A' nu).
    void project(Vec& v, Counters& cnt);
    /// out = M_f^-1 r (z of the face problem without the coarse space).
    void face_direction(const Vec& r, Vec& out, Counters& cnt);
    /// V = Q W and E for `active` when it is not the face they were built for.
    void update_face(const std::vector<char>& active, Counters& cnt);

    const SpMat& m_A;
    const SpMat& m_J;
    const Vec& m_dinv;
    CoupledFaceOperators& m_ops;
    std::string m_precond;
    IncompleteCholeskyPreconditioner m_ic;
    bool m_ichol = false, m_deflate = false, m_rigid_asked = false;
    RigidDeflation m_defl;
    std::vector<char> m_defl_face, m_galerkin_face;
    bool m_have_defl_face = false;
    long m_galerkin_steps = 0, m_deflation_faces = 0, m_full_face_updates = 0;
    Vec m_jv, m_nu, m_jx;     // m-vectors of the projection and the Galerkin step
    Vec m_r, m_w, m_d, m_ad;  // n-vectors of the balanced direction and the Galerkin step
};

}  // namespace cb
