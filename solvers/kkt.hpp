#pragma once
/// The one KKT metric for every solver (DESIGN.md "Metrics").
/// With g = Ax - b, s = max(1, |b|_inf), s_c = max(1, |c|_inf):
///   stationarity     |g - J'lambda|_inf / s
///   primal           |max(0, c - Jx)|_inf / s_c
///   dual             |max(0, -lambda)|_inf / max(1, |lambda|_inf)
///   complementarity  max_i |lambda_i (Jx - c)_i| / s
/// The relative error divides each part by the max of the parts at (x0, lambda = 0), so it is
/// the same reference for every solver whatever its own first iterate.
#include "solvers/qp.hpp"

#include <nlohmann/json.hpp>

namespace cb {

struct KktResiduals {
    double stationarity = 0.0;
    double primal = 0.0;
    double dual = 0.0;
    double complementarity = 0.0;
    double max() const;
    KktResiduals scaled(double factor) const;  ///< every part multiplied by factor
    nlohmann::json to_json() const;            ///< {stationarity, primal, dual, complementarity, max}
};

/// Reference of the relative error: 1 / (KKT max at (x0, 0)), or 1 when that is 0.
struct KktScale {
    double inverse_reference = 1.0;
    double reference = 1.0;
};
KktScale kkt_scale(const QpView& qp);

/// Scaled KKT residuals (one A-product).
KktResiduals kkt_residuals(const QpView& qp, const Vec& x, const Vec& lambda);
/// Same with the gradient g = Ax - b already known (no A-product).
KktResiduals kkt_residuals_from_gradient(const QpView& qp, const Vec& x, const Vec& g,
                                         const Vec& lambda);

/// Multipliers for a solver that has none: least-squares fit of J_A' lambda = g on the rows
/// active at x (|J_i x - c_i| <= 1e-9 max(1,|c_i|) ... or violated), clipped at 0 is NOT applied
/// (a negative fitted multiplier is an honest dual infeasibility). Dependent rows are regularised.
Vec fit_multipliers(const QpView& qp, const Vec& x, const Vec& g);

/// Active-set tolerance tau_i = 1e-9 * max(1, |c_i|) (ALGORITHMS.md notation).
inline double active_tolerance(double c_i) { return 1e-9 * std::max(1.0, std::abs(c_i)); }

/// Largest constraint violation max_i max(0, c_i - J_i x) in the problem's length units.
double max_violation(const QpView& qp, const Vec& x);

} // namespace cb
