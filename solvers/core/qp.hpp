#pragma once
/// The QP every solver sees:  minimize 1/2 x'Ax - b'x  subject to  Jx >= c.
/// Ref: Li et al., "Deformable Objects Collision Handling with Fast Convergence", CGF 2015, eq. (9).
#include "solvers/core/types.hpp"

#include <nlohmann/json.hpp>
#include <cstdint>
#include <string>
#include <vector>

namespace cb {

/// What produced each row of J (kept so that decoupling can order rows as the authors did).
enum class ContactKind : std::int64_t { PLANE = 0, OBSTACLE = 1, INTER_BODY = 2, SELF = 3, OTHER = 4 };

/// Optional per-row contact metadata (all empty, or all of size m).
struct ContactRows {
    std::vector<std::int64_t> kind;    ///< ContactKind per row
    std::vector<double> depth;         ///< penetration depth at detection (length units), >= 0
    std::vector<std::int64_t> vertex;  ///< m x 4 row-major, vertex ids touched by the row, -1 padded
    bool empty() const { return kind.empty() && depth.empty() && vertex.empty(); }
};

/// A scene size l fixed for the problem before any solver runs (docs/accuracy.md "Length scale"),
/// so that every solver's stop test and the harness's measure use the same one. value 0: none
/// fixed, accuracy_scale derives l from x0 (and its fallbacks).
struct FixedLength {
    double value = 0.0;
    std::string source;  ///< length_scale_source: given | suite | snapshot | reference_extent | load_displacement
};

/// Optional Coulomb friction of the contact rows (issue 48; snapshot version 2, docs/INTERFACES.md).
/// Contact i is J's row i (its normal) with the two tangent rows T(2i, :), T(2i + 1, :): FCLIB's
/// local frame, normal first. At a solution of the frictional problem, with the contact's
/// displacement u_i = (J_i x - c_i, T_i x - cT_i) and its force r_i = (lambda_N,i, lambda_T,i):
///   A x - b = J' lambda_N + T' lambda_T,   K*_mu_i ∋ u_i + mu_i ||u_iT|| e_n  ⊥  r_i ∈ K_mu_i.
/// All empty (mu.size() == 0): frictionless, exactly the QP above.
struct Friction {
    Vec mu;          ///< m coefficients, finite, >= 0; empty: frictionless
    SpMat T;         ///< 2m x n tangent rows (row-major); 0 x 0 exactly when mu is empty
    Vec cT;          ///< 2m tangential offsets (cT = T x at the step's start: slip measured from there); empty: 0
    double h = 0.0;  ///< time step of a velocity-level method (time units); 0: not given
    Vec v0;          ///< n start velocities (length / time units); empty: not given (needs h)
    /// True when some contact has mu > 0; mu = 0 everywhere is the frictionless QP.
    bool frictional() const { return mu.size() > 0 && mu.maxCoeff() > 0.0; }
    /// No friction field at all (then the snapshot is written as version 1).
    bool empty() const { return mu.size() == 0 && T.size() == 0 && cT.size() == 0 && h == 0.0 && v0.size() == 0; }
};

/// Const views of a QP; no ownership. A: n x n SPD (full, both triangles), J: m x n.
struct QpView {
    const SpMat& A;
    const Vec& b;
    const SpMat& J;
    const Vec& c;
    const Vec& x0;                        ///< start point (may be infeasible)
    const FixedLength* length = nullptr;  ///< the problem's fixed scene size, if any
    const Friction* friction = nullptr;   ///< the rows' Coulomb friction, if any
    /// A equals A' to the bit (Qp::a_symmetric); false unless the view was made from a Qp that says so.
    bool a_symmetric = false;
    Eigen::Index n() const { return A.rows(); }
    bool frictional() const { return friction && friction->frictional(); }
    Eigen::Index m() const { return J.rows(); }
};

/// An owned QP (what the snapshot reader and the synthetic generators return).
struct Qp {
    SpMat A;
    Vec b;
    SpMat J;
    Vec c;
    Vec x0;
    ContactRows contacts;
    nlohmann::json meta = nlohmann::json::object();
    FixedLength length;  ///< set by the harness (harness/length_scale.hpp) before any solver runs
    Friction friction;   ///< empty: frictionless
    /// A equals A' to the bit, established by the code that made it so: set only by the readers
    /// (problems/: validate_qp and read_qpsnap, right after their exact symmetrisation), copied with
    /// A (select_rows). Whoever writes A afterwards must set it to false. The block products trust
    /// it instead of checking A's mirror again (AOperator::prepare, SBSR); a wrong true would make
    /// them use A's upper triangle for an A that is not symmetric.
    bool a_symmetric = false;

    QpView view() const { return QpView{A, b, J, c, x0, &length, &friction, a_symmetric}; }
    Eigen::Index n() const { return A.rows(); }
    bool frictional() const { return friction.frictional(); }
    Eigen::Index m() const { return J.rows(); }
};

/// F(x) = 1/2 x'Ax - b'x.
inline double objective(const QpView& qp, const Vec& x) { return 0.5 * x.dot(qp.A * x) - qp.b.dot(x); }

}  // namespace cb
