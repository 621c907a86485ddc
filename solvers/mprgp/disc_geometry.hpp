#pragma once
/// The geometry of one disc |x| <= r in the plane, for the engine's disc constraint sets: DiscSet
/// (solvers/mprgp/disc_set.hpp: contiguous 2-blocks) and TrescaSet (solvers/mprgp/tresca_set.hpp: the tangential
/// pair of each contact's 3-block). Written once so that the two sets take the same steps.
#include <algorithm>
#include <cmath>
#include <limits>

namespace cb::disc {

/// (x0, x1) scaled onto the circle when it lies outside the disc of radius r.
inline void project(double& x0, double& x1, double r)
{
    const double len = std::hypot(x0, x1);
    if (len <= r) return;
    const double s = r / len;
    x0 *= s;
    x1 *= s;
}

/// The largest a >= 0 with |x - a p| <= r for x in the disc: the positive root of |x - a p| = r
/// (+inf when p = 0). Both root forms avoid cancellation: (x'p + s) / |p|^2 when x'p >= 0,
/// (r^2 - |x|^2) / (s - x'p) otherwise, s = sqrt((x'p)^2 + |p|^2 (r^2 - |x|^2)).
inline double step_to_circle(double x0, double x1, double p0, double p1, double r)
{
    const double pp = p0 * p0 + p1 * p1;
    if (pp == 0.0) return std::numeric_limits<double>::infinity();
    const double xp = x0 * p0 + x1 * p1;
    const double room = std::max(0.0, r * r - (x0 * x0 + x1 * x1));
    const double s = std::sqrt(xp * xp + pp * room);
    return xp >= 0.0 ? (xp + s) / pp : (s - xp > 0.0 ? room / (s - xp) : 0.0);
}

/// The chopped gradient on a circle with outward unit normal n: g - min(g'n, 0) n, the part of g
/// that a feasible descent can follow (the outward-pointing part of -g is dropped).
inline void chopped_gradient(double g0, double g1, double n0, double n1, double& beta0, double& beta1)
{
    const double gn = std::min(g0 * n0 + g1 * n1, 0.0);
    beta0 = g0 - gn * n0;
    beta1 = g1 - gn * n1;
}

}  // namespace cb::disc
