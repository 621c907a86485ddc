#pragma once
/// The rigid half of the accuracy measure's stationarity part (docs/accuracy.md, "Why these choices"):
/// how far the residual force r = Ax - b - J'lambda would move each body as a whole.
///
/// D^-1 r (one Jacobi step) is the displacement r causes on a DOF held by its neighbours. It
/// misreads forces that move a stiff body as a whole: in free fall at a small step the residual
/// of the start is h^2 M g on every DOF, D = M + h^2 diag(K) is ruled by the stiffness, so D^-1 r
/// is h^2 g M/D while the body really falls by h^2 g (K does not resist a rigid move). The
/// Galerkin displacement in the span of each body's rigid modes, u = V (V'AV)^+ V'r, is what the
/// residual does to the body as a whole; it is the A-orthogonal projection of the true error
/// A^-1 r onto those modes, so its A-norm never exceeds the error's, and it vanishes with r.
///
/// Bodies are the connected components of A's vertex graph (vertex = DOF / 3; stored zeros do not
/// join), their modes the 3 translations and the 3 rotations about the body's centroid in x0.
/// When n is not a multiple of 3 the nodes are the DOFs and each body has one mode, the constant.
/// Modes that a body cannot move (a single vertex's rotations, a point-like start) are dropped by
/// the pseudo-inverse.
///
/// V'r is formed as V'r0 + (AV)'(x - x0) - (JV)'lambda, r0 = A x0 - b and AV summed once in
/// extended precision, rather than summed from a computed r: each entry of fl(Ax - b) carries
/// rounding of the size eps |A||x| (the stiffness times the position), which a body's sum over
/// its mass would read as motion; this way only the step x - x0 meets the stiffness in double.
/// The QP's own floor remains: a backward-stable direct solve of a stiff body leaves a true
/// residual of that size (e = 1.6e-10 on the tipping column of tests/solvers/tipping_column.hpp).
#include "solvers/core/qp.hpp"

#include <Eigen/Dense>
#include <array>
#include <memory>
#include <vector>

namespace cb {

class BodyMotion {
public:
    static constexpr int MODES = 6;
    using Mat6 = Eigen::Matrix<double, MODES, MODES>;
    using Vec6 = Eigen::Matrix<double, MODES, 1>;

    BodyMotion() = default;
    /// O(nnz(A) + nnz(J) + n); no A-product. `length` scales the rotation modes (any positive length).
    BodyMotion(const QpView& qp, double length);

    /// max over DOFs of |V (V'AV)^+ V'(Ax - b - J'lambda - T'lambda_t)| in the problem's length
    /// unit; a lambda whose size is not m (lambda_t: 2m, T the friction's tangent rows) counts as 0.
    /// 0 for n = 0; infinity when x or lambda is not finite. O(n + nnz(J) + nnz(T)).
    double displacement(const Vec& x, const Vec& lambda, const Vec& lambda_t = Vec()) const;
    /// displacement(u .* y, lambda, lambda_t) to the bit, without forming u .* y (a run in scaled
    /// variables, x = D^-1/2 y, asks at every evaluation near convergence: one pass instead of three).
    double displacement_scaled(const Vec& u, const Vec& y, const Vec& lambda, const Vec& lambda_t = Vec()) const;

    int bodies() const { return m_bodies ? static_cast<int>(m_bodies->pinv.size()) : 0; }
    /// True when `other` holds the same body modes (a copy or a with_rows() of this one): shared,
    /// not duplicated.
    bool shares_modes_with(const BodyMotion& other) const { return m_bodies && m_bodies == other.m_bodies; }

    /// Body-mode blocks alive in the process now, and the most alive at once since the last
    /// reset_peak_live_modes() (each is n x 6 doubles of AV plus n-sized parts: what a run must
    /// not hold twice without need). Counters, for tests and reports; thread-safe.
    static long live_modes();
    static long peak_live_modes();
    static void reset_peak_live_modes();

    /// What BodyMotion(qp, length) gives for a QP that shares this one's A, b, x0 and length and has
    /// the rows J (and friction's T when it has 2 m rows): the bodies and AV carry over, only the
    /// rows' loads are formed again (the rest is shared, not copied). O(nnz(J) + nnz(T)).
    BodyMotion with_rows(const SpMat& J, const Friction* friction) const;

private:
    using LongVec6 = std::array<long double, MODES>;

    /// displacement's body at x = u .* y (x = y when u is null); the finiteness test rides in the
    /// pass over the nodes.
    double displacement_at(const double* u, const double* y, Eigen::Index n, const Vec& lambda,
                           const Vec& lambda_t) const;
    /// Row p of V: up to three (mode, value) pairs; returns how many.
    int mode_row(Eigen::Index p, int mode[3], double value[3]) const;
    /// (AV)_p in `av` and r0 + (A x0)_p, returned, summed in extended precision (3-D reading;
    /// `scaled_offset`: m_offset / length, row-major).
    long double spatial_row_sums(const SpMat& A, Eigen::Index p, const double* scaled_offset, long double r0,
                                 LongVec6& av) const;

    bool m_spatial = false;     ///< 3-D reading: nodes are vertices, 6 modes per body
    int m_per_node = 1;         ///< DOFs per node
    double m_inv_length = 1.0;  ///< rotation modes are (e_k x d) / l: the columns stay O(1)
    /// What depends on A, b and x0 alone, never changed after the constructor: held once and shared
    /// by copies and with_rows() (the harness's record and monitor, a decoupled view's scale), since
    /// AV alone is n x 6 doubles, 50 MB at a million DOFs.
    struct Bodies {
        /// Counts the block in live_modes() for its lifetime.
        struct Gauge {
            Gauge();
            ~Gauge();
            Gauge(const Gauge&) = delete;
            Gauge& operator=(const Gauge&) = delete;
        } gauge;
        std::vector<int> body;                                             ///< body of each node
        Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> offset;  ///< vertex - its body's centroid
        Vec x0;                                                            ///< the start the loads are taken from
        Eigen::Matrix<double, Eigen::Dynamic, MODES, Eigen::RowMajor> av;  ///< row p: (AV)_p on its body's modes
        std::vector<Vec6> load0;                                           ///< V'(A x0 - b) per body
        std::vector<Mat6> pinv;  ///< (V'AV)^+ per body (1 x 1 in the top-left corner without 3-D)
    };
    std::shared_ptr<const Bodies> m_bodies;  ///< null: the constructor stopped early (n = 0)
    /// Each row's load per body it touches (a contact row touches one or two bodies).
    struct RowLoads {
        std::vector<int> start;  ///< (JV) entries of row i: [start_i, start_i+1)
        std::vector<int> body;
        std::vector<Vec6> jv;
        Eigen::Index rows() const { return static_cast<Eigen::Index>(start.size()) - 1; }
    };
    RowLoads row_loads(const SpMat& rows) const;
    /// load -= (JV)' lambda over `rows`; false when lambda is not finite.
    static bool subtract(const RowLoads& rows, const Vec& lambda, std::vector<Vec6>& load);
    RowLoads m_rows;      ///< J's
    RowLoads m_tangents;  ///< the friction's T (no rows without friction)
};

}  // namespace cb
