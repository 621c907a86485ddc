#pragma once
/// The QP every solver sees:  minimize 1/2 x'Ax - b'x  subject to  Jx >= c.
/// Ref: Li et al., "Deformable Objects Collision Handling with Fast Convergence", CGF 2015, eq. (9).
#include "solvers/types.hpp"

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

/// Const views of a QP; no ownership. A: n x n SPD (full, both triangles), J: m x n.
struct QpView {
    const SpMat& A;
    const Vec& b;
    const SpMat& J;
    const Vec& c;
    const Vec& x0;  ///< start point (may be infeasible)
    const FixedLength* length = nullptr;  ///< the problem's fixed scene size, if any
    Eigen::Index n() const { return A.rows(); }
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

    QpView view() const { return QpView{A, b, J, c, x0, &length}; }
    Eigen::Index n() const { return A.rows(); }
    Eigen::Index m() const { return J.rows(); }
};

/// F(x) = 1/2 x'Ax - b'x.
inline double objective(const QpView& qp, const Vec& x) { return 0.5 * x.dot(qp.A * x) - qp.b.dot(x); }

}  // namespace cb
