#pragma once
/// The Barzilai-Borwein step length of `mprgp`'s expansion (expansion = bb): the long BB1 form
///     a = s's / s'y,  s = x_k - x_{k-1},  y = g_k - g_{k-1}
/// from the expansion's start point and the iterate before it (the last two iterates and their
/// gradients), safeguarded into [alpha_bar / 2, BB_MAX_RATIO alpha_bar] around the fixed step
/// alpha_bar = 2 / ||A||. For a quadratic y = A s, so a is the inverse of a Rayleigh quotient of A:
/// at least 1 / ||A||. A BB step that raises F(P(x)) is replaced by the fixed step from the same
/// point (PERMON's "fallback"): a long BB step repaired only by Alg. 3's capped safeguard
/// diverged on the random SPD stress case with m near n.
/// Ref: Barzilai, Borwein, "Two-point step size gradient methods", IMA J. Numer. Anal. 8 (1988);
///      Kruzik et al. 2020 (mprgp_parts.hpp) use it as an expansion step length.
#include "solvers/core/types.hpp"

#include <algorithm>
#include <cmath>

namespace cb {

/// The previous iterate and gradient, recorded by the steps class after every step.
class BarzilaiBorweinStep {
public:
    /// Upper safeguard as a multiple of alpha_bar: bounds the step where s'y is tiny.
    static constexpr double BB_MAX_RATIO = 100.0;

    /// Remember (x, g) as the previous iterate of the next length().
    void record(const Vec& x, const Vec& g)
    {
        m_x = x;
        m_g = g;
    }

    /// The safeguarded BB1 length at (x, g); alpha_bar before any record or when s'y <= 0.
    /// Keeps x as the start of the step, for fall_back().
    double length(const Vec& x, const Vec& g, double alpha_bar)
    {
        m_start = x;
        if (m_x.size() != x.size()) return alpha_bar;
        double ss = 0.0, sy = 0.0;
        for (Eigen::Index j = 0; j < x.size(); ++j) {
            const double s = x[j] - m_x[j];
            ss += s * s;
            sy += s * (g[j] - m_g[j]);
        }
        if (!(sy > 0.0) || !std::isfinite(ss / sy)) return alpha_bar;
        return std::clamp(ss / sy, 0.5 * alpha_bar, BB_MAX_RATIO * alpha_bar);
    }

    /// The start point of the last length(), to repeat the step with alpha_bar.
    const Vec& start() const { return m_start; }

private:
    Vec m_x, m_g, m_start;
};

}  // namespace cb
