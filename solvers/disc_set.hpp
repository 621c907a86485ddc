#pragma once
/// A separable convex set of discs: x holds 2-vectors x_i = (x[2i], x[2i+1]), each constrained to
/// |x_i| <= r_i. It is the first implementation of the MPRGP engine's constraint-set interface
/// (issue 44): the operations the MPRGP / MPGP iteration needs from the geometry, with the
/// iteration itself written once over them. A disc per contact is MPGP's friction set (issue 45:
/// the tangential force within mu times the normal one); half-spaces (decoupled rows) and bounds
/// will implement the same five operations.
///
///   contains(x)            x in the set, |x_i| <= r_i (1 + tol)
///   project(x)             the nearest point of the set (block by block: x_i r_i / |x_i| outside)
///   feasible_step(x, p)    the largest alpha >= 0 with x - alpha p in the set (x in the set)
///   free_gradient(x, g)    phi: g_i on blocks inside the disc, 0 on blocks on its circle
///   chopped_gradient(x, g) beta: 0 inside; on the circle (outward normal n_i = x_i / |x_i|),
///                          g_i - min(g_i'n_i, 0) n_i (the part of g_i a feasible descent can follow)
/// so that phi + beta is the projected gradient: -(phi + beta) is the steepest feasible descent.
/// Block i is "on the circle" when |x_i| >= r_i (1 - tol): the engine's active set.
#include "solvers/types.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace cb {

class DiscSet {
public:
    /// radius[i] >= 0 bounds block i; tol is relative to the radius.
    explicit DiscSet(std::vector<double> radius, double tol = 1e-12) : m_radius(std::move(radius)), m_tol(tol) {}

    Eigen::Index blocks() const { return static_cast<Eigen::Index>(m_radius.size()); }
    Eigen::Index size() const { return 2 * blocks(); }
    double radius(Eigen::Index i) const { return m_radius[static_cast<size_t>(i)]; }

    bool contains(const Vec& x) const
    {
        for (Eigen::Index i = 0; i < blocks(); ++i)
            if (!(norm(x, i) <= radius(i) * (1.0 + m_tol))) return false;
        return true;
    }
    /// Block i lies on its circle (the engine's active set).
    bool active(const Vec& x, Eigen::Index i) const { return norm(x, i) >= radius(i) * (1.0 - m_tol); }

    void project(Vec& x) const
    {
        for (Eigen::Index i = 0; i < blocks(); ++i) {
            const double len = norm(x, i);
            if (len <= radius(i)) continue;
            const double s = radius(i) / len;
            x[2 * i] *= s;
            x[2 * i + 1] *= s;
        }
    }

    /// The positive root of |x_i - alpha p_i| = r_i per block, the smallest over blocks (+inf when
    /// p moves no block). Both root forms avoid cancellation: (x'p + s) / |p|^2 when x'p >= 0,
    /// (r^2 - |x|^2) / (s - x'p) otherwise, s = sqrt((x'p)^2 + |p|^2 (r^2 - |x|^2)).
    double feasible_step(const Vec& x, const Vec& p) const
    {
        double step = std::numeric_limits<double>::infinity();
        for (Eigen::Index i = 0; i < blocks(); ++i) {
            const double x0 = x[2 * i], x1 = x[2 * i + 1], p0 = p[2 * i], p1 = p[2 * i + 1];
            const double pp = p0 * p0 + p1 * p1;
            if (pp == 0.0) continue;
            const double xp = x0 * p0 + x1 * p1;
            const double room = std::max(0.0, radius(i) * radius(i) - (x0 * x0 + x1 * x1));
            const double s = std::sqrt(xp * xp + pp * room);
            step = std::min(step, xp >= 0.0 ? (xp + s) / pp : (s - xp > 0.0 ? room / (s - xp) : 0.0));
        }
        return step;
    }

    void free_gradient(const Vec& x, const Vec& g, Vec& phi) const
    {
        phi.resize(size());
        for (Eigen::Index i = 0; i < blocks(); ++i) {
            const bool on = active(x, i);
            phi[2 * i] = on ? 0.0 : g[2 * i];
            phi[2 * i + 1] = on ? 0.0 : g[2 * i + 1];
        }
    }

    void chopped_gradient(const Vec& x, const Vec& g, Vec& beta) const
    {
        beta.resize(size());
        for (Eigen::Index i = 0; i < blocks(); ++i) {
            beta[2 * i] = beta[2 * i + 1] = 0.0;
            if (!active(x, i)) continue;
            const double len = norm(x, i);
            if (!(len > 0.0)) continue;  // a zero-radius disc: no direction stays in it, no descent
            const double n0 = x[2 * i] / len, n1 = x[2 * i + 1] / len;
            const double gn = std::min(g[2 * i] * n0 + g[2 * i + 1] * n1, 0.0);
            beta[2 * i] = g[2 * i] - gn * n0;
            beta[2 * i + 1] = g[2 * i + 1] - gn * n1;
        }
    }

private:
    double norm(const Vec& x, Eigen::Index i) const { return std::hypot(x[2 * i], x[2 * i + 1]); }

    std::vector<double> m_radius;
    double m_tol;
};

}  // namespace cb
