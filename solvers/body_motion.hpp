#pragma once
/// The rigid half of the accuracy measure's stationarity part (docs/accuracy.md, "Why these choices"):
/// how far a residual force r would move each body as a whole.
///
/// D^-1 r (one Jacobi step) is the displacement r causes on a DOF held by its neighbours. It
/// misreads forces that move a stiff body as a whole: in free fall at a small step the residual
/// of the start is h^2 M g on every DOF, D = M + h^2 diag(K) is ruled by the stiffness, so D^-1 r
/// is h^2 g M/D while the body really falls by h^2 g (K does not resist a rigid move). The
/// Galerkin displacement in the span of each body's rigid modes, u = V (V'AV)^+ V'r, is what the
/// residual does to the body as a whole; it is the A-orthogonal projection of the true error
/// A^-1 r onto those modes, so it never reads more than the error there and vanishes with r.
///
/// Bodies are the connected components of A's vertex graph (vertex = DOF / 3; stored zeros do not
/// join), their modes the 3 translations and the 3 rotations about the body's centroid in x0.
/// When n is not a multiple of 3 the nodes are the DOFs and each body has one mode, the constant.
/// Modes that a body cannot move (a single vertex's rotations, a point-like start) are dropped by
/// the pseudo-inverse.
#include "solvers/types.hpp"

#include <Eigen/Dense>
#include <vector>

namespace cb {

class BodyMotion {
public:
    static constexpr int kModes = 6;
    using Mat6 = Eigen::Matrix<double, kModes, kModes>;
    using Vec6 = Eigen::Matrix<double, kModes, 1>;

    BodyMotion() = default;
    /// O(nnz(A) + n); no A-product. `length` scales the rotation modes (any positive length).
    BodyMotion(const SpMat& A, const Vec& x0, double length);

    /// max over DOFs of |V (V'AV)^+ V'r| in the problem's length unit (0 for n = 0; infinity when r
    /// is not finite). O(n).
    double displacement(const Vec& r) const;

    int bodies() const { return static_cast<int>(m_pinv.size()); }

private:
    bool m_spatial = false;     ///< 3-D reading: nodes are vertices, 6 modes per body
    double m_inv_length = 1.0;  ///< rotation modes are (e_k x d) / l: the columns stay O(1)
    std::vector<int> m_body;    ///< body of each node
    Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> m_offset;  ///< vertex - its body's centroid
    std::vector<Mat6> m_pinv;  ///< (V'AV)^+ per body (1 x 1 in the top-left corner without 3-D)
};

}  // namespace cb
