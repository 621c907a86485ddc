#pragma once
/// A separable convex set of discs: x holds 2-vectors x_i = (x[2i], x[2i+1]), each constrained to
/// |x_i| <= r_i. It is the first implementation of the MPRGP engine's constraint-set interface
/// (solvers/mprgp/mprgp_feasible.hpp): the operations the MPRGP / MPGP iteration needs from the
/// geometry, the iteration itself written once over them (solvers/mprgp/mprgp_engine.hpp). A disc per
/// contact is MPGP's friction set (the tangential force within mu times the normal one); bounds
/// (solvers/mprgp/bound_set.hpp) implement the same operations.
///
///   contains(x)            x in the set, |x_i| <= r_i (1 + tol)
///   project(x)             the nearest point of the set (block by block: x_i r_i / |x_i| outside)
///   feasible_step(x, p)    the largest alpha >= 0 with x - alpha p in the set (x in the set)
///   free_gradient(x, g)    phi: g_i on blocks inside the disc, 0 on blocks on its circle
///   chopped_gradient(x, g) beta: 0 inside; on the circle (outward normal n_i = x_i / |x_i|),
///                          g_i - min(g_i'n_i, 0) n_i (the part of g_i a feasible descent can follow)
/// so that phi + beta is the projected gradient: -(phi + beta) is the steepest feasible descent.
/// Block i is "on the circle" when |x_i| >= r_i (1 - tol): the engine's active set.
#include "solvers/core/types.hpp"
#include "solvers/mprgp/disc_geometry.hpp"

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
        for (Eigen::Index i = 0; i < blocks(); ++i) disc::project(x[2 * i], x[2 * i + 1], radius(i));
    }

    /// The positive root of |x_i - alpha p_i| = r_i per block, the smallest over blocks (+inf when
    /// p moves no block; solvers/mprgp/disc_geometry.hpp).
    double feasible_step(const Vec& x, const Vec& p) const
    {
        double step = std::numeric_limits<double>::infinity();
        for (Eigen::Index i = 0; i < blocks(); ++i)
            step = std::min(step, disc::step_to_circle(x[2 * i], x[2 * i + 1], p[2 * i], p[2 * i + 1], radius(i)));
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
            disc::chopped_gradient(g[2 * i], g[2 * i + 1], x[2 * i] / len, x[2 * i + 1] / len, beta[2 * i],
                                   beta[2 * i + 1]);
        }
    }

    // --- the engine's face interface (solvers/mprgp/mprgp_feasible.hpp): the face fixed by classify ---

    /// The blocks on their circle at x and their outward normals. @return whether the face changed
    bool classify(const Vec& x)
    {
        m_on.resize(static_cast<size_t>(blocks()), 0);
        m_normal.resize(size());
        bool changed = false;
        for (Eigen::Index i = 0; i < blocks(); ++i) {
            const char on = active(x, i);
            changed = changed || on != m_on[static_cast<size_t>(i)];
            m_on[static_cast<size_t>(i)] = on;
            const double len = norm(x, i);
            const bool direction = on && len > 0.0;  // a zero-radius disc has no normal: no descent stays in it
            m_normal[2 * i] = direction ? x[2 * i] / len : 0.0;
            m_normal[2 * i + 1] = direction ? x[2 * i + 1] / len : 0.0;
        }
        return changed;
    }
    /// free_gradient and chopped_gradient on the classified face.
    void gradients(const Vec& g, Vec& phi, Vec& beta) const
    {
        phi.resize(size());
        beta.resize(size());
        for (Eigen::Index i = 0; i < blocks(); ++i) {
            const bool on = m_on[static_cast<size_t>(i)];
            const double n0 = m_normal[2 * i], n1 = m_normal[2 * i + 1];
            phi[2 * i] = on ? 0.0 : g[2 * i];
            phi[2 * i + 1] = on ? 0.0 : g[2 * i + 1];
            beta[2 * i] = beta[2 * i + 1] = 0.0;
            if (on && (n0 != 0.0 || n1 != 0.0))
                disc::chopped_gradient(g[2 * i], g[2 * i + 1], n0, n1, beta[2 * i], beta[2 * i + 1]);
        }
    }
    /// phitilde'phi, phitilde = (x - P(x - alpha_bar phi)) / alpha_bar (Dostal 2009, eq. 7.8).
    double reduced_free_gradient_dot(const Vec& x, const Vec& phi, double alpha_bar) const
    {
        Vec y = x - alpha_bar * phi;
        project(y);
        return (x - y).dot(phi) / alpha_bar;
    }
    /// The measure of a set without rows: the largest entry of the projected gradient phi + beta.
    double error(const Vec&, const Vec& g) const
    {
        Vec phi, beta;
        gradients(g, phi, beta);
        return size() > 0 ? (phi + beta).cwiseAbs().maxCoeff() : 0.0;
    }
    const Vec* multipliers() const { return nullptr; }

private:
    double norm(const Vec& x, Eigen::Index i) const { return std::hypot(x[2 * i], x[2 * i + 1]); }

    std::vector<double> m_radius;
    double m_tol;
    std::vector<char> m_on;  ///< classify's face: block i on its circle
    Vec m_normal;            ///< classify's outward unit normals (0 off the face)
};

}  // namespace cb
