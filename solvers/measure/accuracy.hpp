#pragma once
/// The one accuracy measure of contactbench (docs/accuracy.md): every part is a length divided by
/// the scene size l, so the error e is dimensionless and means the same whatever the units, the
/// start, a rigid translation, the objective's scale or a row's scale.
///
/// Notation: D = diag(A), n_i = |J_i|_2, k_i = sum_j (J_ij / n_i)^2 D_jj (the stiffness along row
/// i's unit normal), r = Ax - b - J'lambda. At (x, lambda):
///   stationarity     max(|D^-1 r|_inf, |V (V'AV)^+ V'r|_inf) / l  (displacement the residual force causes:
///                    on a DOF alone, and on each body as a whole, V its rigid modes: solvers/measure/body_motion.hpp)
///   primal           max_i max(0, c_i - J_i x) / n_i / l         (penetration)
///   dual             max_i max(0, -lambda_i) n_i / k_i / l       (displacement of a pulling force)
///   complementarity  max_i min(|lambda_i| n_i / k_i, |J_i x - c_i| / n_i) / l
///   gap              sum_i |lambda_i (J_i x - c_i)| / (d_ref l^2)  (the duality gap in units of the
///                    energy of moving a typical DOF, d_ref = mean of D, by the scene size)
///   e = max of the five.
/// A zero row (n_i = 0) is feasible iff c_i <= 0 (else the primal part is infinite); its
/// multiplier exerts no force, so it adds nothing to the dual, complementarity and gap parts.
///
/// Coulomb friction (qp.friction, issue 48; docs/accuracy.md "e for Coulomb friction"): with the
/// tangential multipliers lambda_T (2m), r = Ax - b - J'lambda - T'lambda_T, and each contact with
/// mu_i > 0 or lambda_T,i != 0 adds its natural map in lengths (accuracy_rows.hpp add_friction)
///   friction         max_i ||F_i||_2 / l
/// and its modified velocity's work to the gap; e = max of the six. A contact with mu_i = 0 and
/// lambda_T,i = 0 adds nothing, so on a frictionless problem e is today's bit for bit.
#include "solvers/core/qp.hpp"
#include "solvers/measure/body_motion.hpp"

#include <nlohmann/json.hpp>
#include <algorithm>
#include <cmath>
#include <string>

namespace cb {

/// The five parts of the accuracy error: four lengths as fractions of the scene size, and the
/// duality gap as a fraction of the energy scale d_ref l^2.
struct AccuracyParts {
    double stationarity = 0.0;
    double primal = 0.0;
    double dual = 0.0;
    double complementarity = 0.0;
    double gap = 0.0;
    double friction = 0.0;    ///< Coulomb's natural map (0 without friction)
    bool frictional = false;  ///< the problem has friction fields: to_json adds "friction"
    double max() const;       ///< the error e
    /// {stationarity, primal, dual, complementarity, gap, [friction,] max}; non-finite -> null
    nlohmann::json to_json() const;
};

/// What the measure needs from the problem alone, computed once per QP: O(nnz(A) + nnz(J)),
/// plus the A-products of the length-scale fallback for a point-like start (in a_products).
struct AccuracyScale {
    Vec inv_diag;               ///< 1 / D_jj (a non-positive D_jj uses the largest D)
    Vec inv_row_norm;           ///< 1 / n_i, or 0 for a zero row
    Vec length_per_multiplier;  ///< n_i / k_i: the displacement a unit multiplier causes along row i
    double length = 1.0;        ///< the scene size l, in the problem's length unit
    double inv_length = 1.0;
    std::string length_source;  ///< x0_extent | ... | unit, or a FixedLength's source (docs/accuracy.md)
    double stiffness = 1.0;     ///< d_ref = mean of D: the energy scale is d_ref * l^2
    double inv_energy = 1.0;    ///< 1 / (d_ref l^2)
    long a_products = 0;        ///< A-products spent computing this scale
    BodyMotion bodies;          ///< the rigid half of stationarity (built from the QP and l)
    /// The stationarity part at (x, lambda) whose residual force is r = Ax - b - J'lambda:
    /// max(|D^-1 r|_inf, the bodies' motion) / l (a lambda of another size than m counts as 0).
    double stationarity(const Vec& r, const Vec& x, const Vec& lambda) const;
    /// Same with tangential multipliers (2m; empty: none): r = Ax - b - J'lambda - T'lambda_T.
    double stationarity(const Vec& r, const Vec& x, const Vec& lambda, const Vec& lambda_t) const;
    /// Its rigid half alone, the bodies' motion / l (for solvers whose fused passes hold the rest).
    double body_motion(const Vec& x, const Vec& lambda, const Vec& lambda_t = Vec()) const;
    /// body_motion(u .* y, lambda) to the bit, without forming u .* y (BodyMotion::displacement_scaled).
    double body_motion_scaled(const Vec& u, const Vec& y, const Vec& lambda) const;
    nlohmann::json to_json() const;  ///< {length_scale, length_scale_source, stiffness_scale}
};

/// The scene size l (docs/accuracy.md "Length scale"): the largest axis extent of x0 read as 3-D
/// points when n is a multiple of 3, else the range of x0's entries; when that is 0 (or not
/// finite), the same extent of the unconstrained minimiser (Jacobi-PCG from x0 to a relative
/// residual of 1e-3, at most 200 iterations; its A-products are counted), then
/// max_i |c_i - J_i x0| / n_i, then 1.
/// A scene size fixed on the view (qp.length, docs/accuracy.md) is used as is, before all of these.
AccuracyScale accuracy_scale(const QpView& qp);

/// The scale of `qp` when it shares A, b and x0 with the QP `shared` was built for and differs in its
/// rows (a decoupled J, or none): equal to accuracy_scale(qp) to the last bit, without the passes
/// over A. Falls back on accuracy_scale(qp) when the scene size would differ or came from A-products
/// or the rows (the fallbacks after the start's extent), or when the sizes do not match.
AccuracyScale accuracy_scale_with_rows(const AccuracyScale& shared, const QpView& qp);

/// The largest axis extent of x read as 3-D points when its size is a multiple of 3 (source
/// "x0_extent"), else the range of its entries ("x0_range"); 0 for an empty x.
double point_extent(const Vec& x, std::string& source);

/// The measure at (x, lambda) with the gradient g = Ax - b already known (no A-product).
/// A lambda whose size is not m counts as lambda = 0 on stationarity and adds no dual or
/// complementarity part. NaN anywhere reads as an infinite part. On a problem with friction
/// fields, `lambda_t` (2m tangential multipliers; nullptr or another size: 0) enters stationarity
/// and the friction part (see above).
AccuracyParts accuracy_from_gradient(const QpView& qp, const AccuracyScale& scale, const Vec& x, const Vec& g,
                                     const Vec& lambda, const Vec* lambda_t = nullptr);
/// Same, one A-product.
AccuracyParts accuracy(const QpView& qp, const AccuracyScale& scale, const Vec& x, const Vec& lambda,
                       const Vec* lambda_t = nullptr);
/// Same, building the scale first (tests and one-off checks).
AccuracyParts accuracy(const QpView& qp, const Vec& x, const Vec& lambda, const Vec* lambda_t = nullptr);

/// The energy figure |F - F*| / (d_ref l^2): an objective gap in units of the energy of moving a
/// typical DOF by the scene size (dimensionless; NaN when F or F* is not finite).
double energy_gap(const AccuracyScale& scale, double objective, double objective_star);
/// The A-norm distance |x - x*|_A / (sqrt(d_ref) l) (one A-product).
double a_norm_distance(const QpView& qp, const AccuracyScale& scale, const Vec& x, const Vec& x_star);

/// Multipliers for a solver that has none: least-squares fit of J_A' lambda = g on the rows
/// near-active at x ((J_i x - c_i) / n_i <= 1e-6 l, violated rows included; zero rows never).
/// A negative fitted multiplier is kept (an honest dual infeasibility) unless its row is off
/// its face by more than 1e-9 l, which drops the row. Dependent rows are regularised.
/// Scale-free like the measure: the thresholds are lengths relative to the scene size.
Vec fit_multipliers(const QpView& qp, const AccuracyScale& scale, const Vec& x, const Vec& g);

/// Active-set tolerance tau_i = 1e-9 * max(1, |c_i|) (ALGORITHMS.md notation).
inline double active_tolerance(double c_i) { return 1e-9 * std::max(1.0, std::abs(c_i)); }

/// Largest constraint violation max_i max(0, c_i - J_i x) in the problem's length units.
double max_violation(const QpView& qp, const Vec& x);

}  // namespace cb
