#pragma once
/// The Tresca set of a frictional local problem (solvers/core/friction_problem.hpp) as a constraint set
/// of the MPRGP engine (solvers/mprgp/mprgp_feasible.hpp): per contact i, the 3-block
/// r_i = (r_n, r_t1, r_t2) with the normal on a half-line and the tangential part in a disc,
///     r_n >= 0,   ||r_T|| <= s_i   (s_i the slip bound, fixed during one solve),
/// a separable convex set. Minimising 1/2 r'Wr + q'r over it is the Tresca problem in the dual
/// (u = W r + q its gradient); Coulomb's is its fixed point s_i = mu_i r_n (solvers/friction/mprgp_tresca.hpp).
///
/// The face (classify): the normal is on its bound when r_n <= normal_tol (as mprgp-box's bound at
/// c = 0, so that at mu = 0 the two take the same decisions); the tangential pair is on its circle
/// when ||r_T|| >= s_i (1 - disc_tol), and a zero-radius disc (s_i = 0) always is. Free gradient phi:
/// g on free components, 0 on the face. Chopped gradient beta (Dostal and Kozubek 2012, Sec. 2, for
/// a curved boundary): the normal min(g_n, 0); on a circle with outward normal n, g_T - min(g_T'n, 0) n,
/// the part of g_T that a feasible descent can follow; 0 on a zero-radius disc (no direction stays
/// in it). phi + beta is then the projected gradient, zero exactly at a Tresca solution.
/// Ref: Dostal, Kozubek, Math. Program. 135 (2012), MPGP; Dostal 2009, eq. (7.8) reduced free gradient.
#include "solvers/core/types.hpp"
#include "solvers/mprgp/disc_geometry.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace cb {

class TrescaSet {
public:
    static constexpr double NORMAL_TOL = 1e-9;  ///< mprgp-box's active tolerance at c = 0 (accuracy.hpp)
    static constexpr double DISC_TOL = 1e-12;   ///< relative to the slip bound, as DiscSet's

    /// slip[i] >= 0 bounds contact i's tangential part.
    explicit TrescaSet(Vec slip) : m_slip(std::move(slip)) {}

    Eigen::Index contacts() const { return m_slip.size(); }
    Eigen::Index size() const { return 3 * contacts(); }
    double slip(Eigen::Index i) const { return m_slip[i]; }
    void set_slip(const Vec& slip) { m_slip = slip; }

    bool contains(const Vec& x) const
    {
        for (Eigen::Index i = 0; i < contacts(); ++i)
            if (x[3 * i] < 0.0 || !(tangent_norm(x, i) <= m_slip[i] * (1.0 + DISC_TOL))) return false;
        return true;
    }

    void project(Vec& x) const
    {
        for (Eigen::Index i = 0; i < contacts(); ++i) {
            x[3 * i] = std::max(x[3 * i], 0.0);
            disc::project(x[3 * i + 1], x[3 * i + 2], m_slip[i]);
        }
    }

    /// The largest a >= 0 with x - a p in the set (x in it): the normal's bound, and per disc the
    /// positive root of ||x_T - a p_T|| = s (solvers/mprgp/disc_geometry.hpp).
    double feasible_step(const Vec& x, const Vec& p) const
    {
        double step = std::numeric_limits<double>::infinity();
        for (Eigen::Index i = 0; i < contacts(); ++i) {
            if (p[3 * i] > 0.0) step = std::min(step, x[3 * i] / p[3 * i]);
            step =
                std::min(step, disc::step_to_circle(x[3 * i + 1], x[3 * i + 2], p[3 * i + 1], p[3 * i + 2], m_slip[i]));
        }
        return step;
    }

    /// The face at x and the circles' outward normals. @return whether the face changed
    bool classify(const Vec& x)
    {
        const size_t m = static_cast<size_t>(contacts());
        if (m_normal_on.size() != m) {
            m_normal_on.assign(m, 2);  // 2: no face yet, so the first classify reports a change
            m_disc_on.assign(m, 2);
        }
        m_outward.resize(2 * contacts());
        bool changed = false;
        for (Eigen::Index i = 0; i < contacts(); ++i) {
            const size_t k = static_cast<size_t>(i);
            const char normal_on = x[3 * i] <= NORMAL_TOL;
            const double len = tangent_norm(x, i);
            const char disc_on = m_slip[i] == 0.0 || len >= m_slip[i] * (1.0 - DISC_TOL);
            changed = changed || normal_on != m_normal_on[k] || disc_on != m_disc_on[k];
            m_normal_on[k] = normal_on;
            m_disc_on[k] = disc_on;
            const bool direction = disc_on && len > 0.0;
            m_outward[2 * i] = direction ? x[3 * i + 1] / len : 0.0;
            m_outward[2 * i + 1] = direction ? x[3 * i + 2] / len : 0.0;
        }
        return changed;
    }

    /// Free and chopped gradients on the classified face.
    void gradients(const Vec& g, Vec& phi, Vec& beta) const
    {
        phi.resize(size());
        beta.resize(size());
        for (Eigen::Index i = 0; i < contacts(); ++i) {
            const size_t k = static_cast<size_t>(i);
            const bool normal_on = m_normal_on[k] == 1;
            phi[3 * i] = normal_on ? 0.0 : g[3 * i];
            beta[3 * i] = normal_on ? std::min(g[3 * i], 0.0) : 0.0;
            const bool disc_on = m_disc_on[k] == 1;
            const double n0 = m_outward[2 * i], n1 = m_outward[2 * i + 1];
            phi[3 * i + 1] = disc_on ? 0.0 : g[3 * i + 1];
            phi[3 * i + 2] = disc_on ? 0.0 : g[3 * i + 2];
            beta[3 * i + 1] = beta[3 * i + 2] = 0.0;
            if (disc_on && (n0 != 0.0 || n1 != 0.0))
                disc::chopped_gradient(g[3 * i + 1], g[3 * i + 2], n0, n1, beta[3 * i + 1], beta[3 * i + 2]);
        }
    }

    /// phitilde'phi, phitilde = (x - P(x - alpha_bar phi)) / alpha_bar (Dostal 2009, eq. 7.8). The
    /// normal in mprgp-box's form min(x_n / alpha_bar, phi_n) (BoundSet), so that at mu = 0 the
    /// proportioning test reads the same number.
    double reduced_free_gradient_dot(const Vec& x, const Vec& phi, double alpha_bar) const
    {
        double sum = 0.0;
        for (Eigen::Index i = 0; i < contacts(); ++i) {
            const double pn = phi[3 * i];
            if (pn > 0.0)
                sum += std::min(x[3 * i] / alpha_bar, pn) * pn;
            else if (pn < 0.0)
                sum += pn * pn;
            const double p0 = phi[3 * i + 1], p1 = phi[3 * i + 2];
            if (p0 == 0.0 && p1 == 0.0) continue;
            double y0 = x[3 * i + 1] - alpha_bar * p0, y1 = x[3 * i + 2] - alpha_bar * p1;
            disc::project(y0, y1, m_slip[i]);
            sum += ((x[3 * i + 1] - y0) * p0 + (x[3 * i + 2] - y1) * p1) / alpha_bar;
        }
        return sum;
    }

    /// The inner solve's measure: the largest entry of the projected gradient phi + beta (the
    /// outer loop judges by FCLIB's error; the inner one stops on the native ||phi + beta||).
    double error(const Vec&, const Vec& g) const
    {
        Vec phi, beta;
        gradients(g, phi, beta);
        return size() > 0 ? (phi + beta).cwiseAbs().maxCoeff() : 0.0;
    }
    const Vec* multipliers() const { return nullptr; }

private:
    double tangent_norm(const Vec& x, Eigen::Index i) const { return std::hypot(x[3 * i + 1], x[3 * i + 2]); }

    Vec m_slip;
    std::vector<char> m_normal_on, m_disc_on;
    Vec m_outward;
};

}  // namespace cb
