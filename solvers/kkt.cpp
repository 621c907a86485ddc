#include "solvers/kkt.hpp"

#include "solvers/a_product.hpp"

#include <Eigen/SparseCholesky>
#include <algorithm>
#include <cmath>
#include <vector>

namespace cb {

double KktResiduals::max() const
{
    return std::max(std::max(stationarity, primal), std::max(dual, complementarity));
}

KktResiduals KktResiduals::scaled(double factor) const
{
    return {stationarity * factor, primal * factor, dual * factor, complementarity * factor};
}

nlohmann::json KktResiduals::to_json() const
{
    return {{"stationarity", stationarity}, {"primal", primal}, {"dual", dual},
            {"complementarity", complementarity}, {"max", max()}};
}

KktResiduals kkt_residuals_from_gradient(const QpView& qp, const Vec& x, const Vec& g, const Vec& lambda)
{
    const double s = std::max(1.0, qp.b.size() ? qp.b.lpNorm<Eigen::Infinity>() : 0.0);
    const double s_c = std::max(1.0, qp.c.size() ? qp.c.lpNorm<Eigen::Infinity>() : 0.0);
    KktResiduals k;
    const bool has_lambda = qp.m() > 0 && lambda.size() == qp.m();
    if (has_lambda) {
        k.stationarity = (g - qp.J.transpose() * lambda).lpNorm<Eigen::Infinity>() / s;
    } else {
        k.stationarity = g.size() ? g.lpNorm<Eigen::Infinity>() / s : 0.0;
    }
    if (qp.m() > 0) {
        const Vec slack = qp.J * x - qp.c;  // >= 0 when feasible
        k.primal = std::max(0.0, (-slack).maxCoeff()) / s_c;
        if (has_lambda) {
            const double lambda_inf = lambda.lpNorm<Eigen::Infinity>();
            k.dual = std::max(0.0, (-lambda).maxCoeff()) / std::max(1.0, lambda_inf);
            k.complementarity = lambda.cwiseProduct(slack).lpNorm<Eigen::Infinity>() / s;
        }
    }
    // NaN anywhere must not read as "small": max() with NaN would drop it.
    auto sanitize = [](double v) { return std::isfinite(v) ? v : std::numeric_limits<double>::infinity(); };
    k.stationarity = sanitize(k.stationarity);
    k.primal = sanitize(k.primal);
    k.dual = sanitize(k.dual);
    k.complementarity = sanitize(k.complementarity);
    return k;
}

KktResiduals kkt_residuals(const QpView& qp, const Vec& x, const Vec& lambda)
{
    const Vec g = a_product(qp.A, x) - qp.b;
    return kkt_residuals_from_gradient(qp, x, g, lambda);
}

KktScale kkt_scale(const QpView& qp)
{
    const Vec zero = Vec::Zero(qp.m());
    const double reference = kkt_residuals(qp, qp.x0, zero).max();
    KktScale scale;
    if (reference > 0.0 && std::isfinite(reference)) {
        scale.reference = reference;
        scale.inverse_reference = 1.0 / reference;
    }
    return scale;
}

double max_violation(const QpView& qp, const Vec& x)
{
    if (qp.m() == 0) return 0.0;
    return std::max(0.0, (qp.c - qp.J * x).maxCoeff());
}

Vec fit_multipliers(const QpView& qp, const Vec& x, const Vec& g)
{
    const Eigen::Index m = qp.m();
    Vec lambda = Vec::Zero(m);
    if (m == 0) return lambda;
    const Vec slack = qp.J * x - qp.c;
    // Candidate rows: near-active (loose tolerance, because approximate iterates sit a little
    // off their face) or violated.
    std::vector<int> rows;
    for (Eigen::Index i = 0; i < m; ++i)
        if (slack[i] <= 1e-6 * std::max(1.0, std::abs(qp.c[i]))) rows.push_back(static_cast<int>(i));
    for (int round = 0; round < 8 && !rows.empty(); ++round) {
        std::vector<Triplet> t;
        for (size_t r = 0; r < rows.size(); ++r)
            for (SpMat::InnerIterator it(qp.J, rows[r]); it; ++it)
                t.emplace_back(static_cast<int>(r), static_cast<int>(it.col()), it.value());
        SpMat JA(static_cast<Eigen::Index>(rows.size()), qp.n());
        JA.setFromTriplets(t.begin(), t.end());
        SpMatCol M = SpMatCol(JA * JA.transpose());
        double max_diag = 0.0;
        for (Eigen::Index i = 0; i < M.rows(); ++i) max_diag = std::max(max_diag, M.coeff(i, i));
        // Tikhonov term: keeps dependent (duplicated, parallel) rows solvable; the fit then
        // splits their multiplier, which leaves stationarity unchanged.
        SpMatCol reg(M.rows(), M.cols());
        reg.setIdentity();
        M += (1e-12 * std::max(max_diag, 1e-300)) * reg;
        Eigen::SimplicialLDLT<SpMatCol> ldlt(M);
        if (ldlt.info() != Eigen::Success) break;
        const Vec mu = ldlt.solve(Vec(JA * g));
        // Drop rows whose fitted multiplier is negative but that are not strictly active:
        // those are the ones the loose candidate tolerance let in.
        std::vector<int> keep;
        bool dropped = false;
        for (size_t r = 0; r < rows.size(); ++r) {
            if (mu[static_cast<Eigen::Index>(r)] < 0.0 && slack[rows[r]] > active_tolerance(qp.c[rows[r]])) {
                dropped = true;
                continue;
            }
            keep.push_back(rows[r]);
        }
        if (!dropped) {
            for (size_t r = 0; r < rows.size(); ++r) lambda[rows[r]] = mu[static_cast<Eigen::Index>(r)];
            return lambda;
        }
        rows.swap(keep);
    }
    return lambda;
}

} // namespace cb
