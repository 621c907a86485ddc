#pragma once
/// Bounds l <= x <= u as the constraint set of the MPRGP engine's feasible steps
/// (solvers/mprgp/mprgp_feasible.hpp): `mprgp-box`. A DOF is on its lower (upper) bound within the
/// row's tolerance tau_i / |a| (solvers/measure/accuracy.hpp active_tolerance); the multipliers of the
/// rows are the bound DOFs' gradients.
/// Ref: Li et al., CGF 2015, eq. (11)-(12) free / chopped gradients for bounds, eq. (13) reduced
///      free gradient phitilde_i = min((x_i - l_i)/alpha_bar, phi_i) and its upper-bound mirror.
#include "solvers/measure/accuracy.hpp"
#include "solvers/mprgp/bounds.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace cb {

class BoundSet {
public:
    BoundSet(const QpView& qp, const RowBounds& bounds, const AccuracyScale& scale)
        : m_qp(qp), m_bounds(bounds), m_scale(scale), m_n(qp.n()), m_tol_lower(Vec::Zero(m_n)),
          m_tol_upper(Vec::Zero(m_n)), m_at_lower(static_cast<size_t>(m_n)), m_at_upper(static_cast<size_t>(m_n)),
          m_lambda(Vec::Zero(qp.m()))
    {
        // "At the bound" in x units: tau_i of the row divided by |a|.
        for (Eigen::Index j = 0; j < m_n; ++j) {
            const Eigen::Index rl = lower_row(j), ru = upper_row(j);
            if (rl >= 0) m_tol_lower[j] = active_tolerance(qp.c[rl]) / std::abs(bounds.coef[rl]);
            if (ru >= 0) m_tol_upper[j] = active_tolerance(qp.c[ru]) / std::abs(bounds.coef[ru]);
        }
    }

    /// No DOF beyond a bound (a NaN is left to the loop's finiteness check).
    bool contains(const Vec& x) const
    {
        for (Eigen::Index j = 0; j < m_n; ++j)
            if (x[j] < m_bounds.lower[j] || x[j] > m_bounds.upper[j]) return false;
        return true;
    }
    void project(Vec& x) const { x = x.cwiseMax(m_bounds.lower).cwiseMin(m_bounds.upper); }

    double feasible_step(const Vec& x, const Vec& p) const
    {
        const Vec& lower = m_bounds.lower;
        const Vec& upper = m_bounds.upper;
        double step = std::numeric_limits<double>::infinity();
        for (Eigen::Index j = 0; j < m_n; ++j) {
            if (p[j] > 0.0 && std::isfinite(lower[j]))
                step = std::min(step, (x[j] - lower[j]) / p[j]);
            else if (p[j] < 0.0 && std::isfinite(upper[j]))
                step = std::min(step, (x[j] - upper[j]) / p[j]);
        }
        return step;
    }

    bool classify(const Vec& x)
    {
        bool changed = false;
        for (Eigen::Index j = 0; j < m_n; ++j) {
            const size_t k = static_cast<size_t>(j);
            const char lo = x[j] <= m_bounds.lower[j] + m_tol_lower[j];
            const char up = !lo && x[j] >= m_bounds.upper[j] - m_tol_upper[j];
            changed = changed || lo != m_at_lower[k] || up != m_at_upper[k];
            m_at_lower[k] = lo;
            m_at_upper[k] = up;
        }
        return changed;
    }

    void gradients(const Vec& g, Vec& phi, Vec& beta) const
    {
        phi.resize(m_n);
        beta.resize(m_n);
        for (Eigen::Index j = 0; j < m_n; ++j) {
            const bool lo = m_at_lower[static_cast<size_t>(j)], up = m_at_upper[static_cast<size_t>(j)];
            phi[j] = (lo || up) ? 0.0 : g[j];
            beta[j] = lo ? std::min(g[j], 0.0) : (up ? std::max(g[j], 0.0) : 0.0);
        }
    }

    double reduced_free_gradient_dot(const Vec& x, const Vec& phi, double alpha_bar) const
    {
        double s = 0.0;
        for (Eigen::Index j = 0; j < m_n; ++j) {
            if (phi[j] > 0.0)
                s += std::min((x[j] - m_bounds.lower[j]) / alpha_bar, phi[j]) * phi[j];
            else if (phi[j] < 0.0)
                s += std::max((x[j] - m_bounds.upper[j]) / alpha_bar, phi[j]) * phi[j];
        }
        return s;
    }

    /// The rows' multipliers (a bound DOF's gradient over the row's coefficient, >= 0) and the
    /// accuracy error at x.
    double error(const Vec& x, const Vec& g)
    {
        m_lambda.setZero();
        for (Eigen::Index j = 0; j < m_n; ++j) {
            const Eigen::Index rl = lower_row(j), ru = upper_row(j);
            if (m_at_lower[static_cast<size_t>(j)] && rl >= 0) m_lambda[rl] = std::max(0.0, g[j] / m_bounds.coef[rl]);
            if (m_at_upper[static_cast<size_t>(j)] && ru >= 0) m_lambda[ru] = std::max(0.0, g[j] / m_bounds.coef[ru]);
        }
        return accuracy_from_gradient(m_qp, m_scale, x, g, m_lambda).max();
    }
    const Vec* multipliers() const { return &m_lambda; }

private:
    Eigen::Index lower_row(Eigen::Index j) const { return m_bounds.lower_row[static_cast<size_t>(j)]; }
    Eigen::Index upper_row(Eigen::Index j) const { return m_bounds.upper_row[static_cast<size_t>(j)]; }

    const QpView& m_qp;
    const RowBounds& m_bounds;
    const AccuracyScale& m_scale;
    const Eigen::Index m_n;
    Vec m_tol_lower, m_tol_upper;
    std::vector<char> m_at_lower, m_at_upper;
    Vec m_lambda;
};

}  // namespace cb
