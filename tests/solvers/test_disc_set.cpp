// The disc constraint set (solvers/mprgp/disc_set.hpp), the engine's first separable convex set other
// than half-spaces: projection, feasible step length and free / chopped gradients against brute
// force (grids of points, steps and directions), on seeded random blocks.
#include "solvers/mprgp/disc_set.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace {

using cb::DiscSet;
using cb::Vec;
constexpr double PI = 3.14159265358979323846;

double block_norm(const Vec& x, Eigen::Index i) { return std::hypot(x[2 * i], x[2 * i + 1]); }

TEST(DiscSet, ProjectionIsTheNearestPointOfAGrid)
{
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(-3.0, 3.0);
    const DiscSet set({1.0, 0.5, 2.0, 0.0});
    for (int trial = 0; trial < 6; ++trial) {
        Vec x(set.size());
        for (Eigen::Index k = 0; k < x.size(); ++k) x[k] = u(rng);
        Vec p = x;
        set.project(p);
        EXPECT_TRUE(set.contains(p));
        for (Eigen::Index i = 0; i < set.blocks(); ++i) {
            const double r = set.radius(i);
            const double d_proj = std::hypot(p[2 * i] - x[2 * i], p[2 * i + 1] - x[2 * i + 1]);
            // Brute force: every point of a polar grid over the disc.
            double d_best = std::hypot(x[2 * i], x[2 * i + 1]);  // the centre
            const int radii = 200, angles = 2000;
            for (int a = 0; a < radii; ++a)
                for (int b = 0; b < angles; ++b) {
                    const double rho = r * (a + 1) / radii, th = 2.0 * PI * b / angles;
                    d_best =
                        std::min(d_best, std::hypot(rho * std::cos(th) - x[2 * i], rho * std::sin(th) - x[2 * i + 1]));
                }
            EXPECT_LE(d_proj, d_best + 1e-12) << "block " << i;  // never farther than a grid point
            EXPECT_NEAR(d_proj, d_best, r * (1.0 / radii + 2.0 * PI / angles) + 1e-15) << "block " << i;
        }
    }
    Vec inside = Vec::Zero(set.size());
    inside[0] = 0.3;
    Vec same = inside;
    set.project(same);
    EXPECT_EQ(same, inside);  // a point of the set is its own projection
}

TEST(DiscSet, FeasibleStepIsTheLargestStepOfAScan)
{
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    const DiscSet set({1.0, 0.25, 3.0});
    for (int trial = 0; trial < 20; ++trial) {
        Vec x(set.size()), p(set.size());
        for (Eigen::Index k = 0; k < x.size(); ++k) p[k] = u(rng);
        for (Eigen::Index i = 0; i < set.blocks(); ++i) {
            // A point inside each disc, some on its circle (an active block).
            const double rho = set.radius(i) * (trial % 4 == 0 && i == 0 ? 1.0 : std::abs(u(rng)));
            const double th = PI * u(rng);
            x[2 * i] = rho * std::cos(th);
            x[2 * i + 1] = rho * std::sin(th);
        }
        const double step = set.feasible_step(x, p);
        ASSERT_TRUE(std::isfinite(step));
        ASSERT_GE(step, 0.0);
        // Brute force: the first step of a fine scan that leaves the set.
        const double h = 1e-5;
        double scan = 0.0;
        while (set.contains(Vec(x - (scan + h) * p))) scan += h;
        EXPECT_NEAR(step, scan, h) << "trial " << trial;
        // The step reaches a circle exactly and stays in the set.
        const Vec y = x - step * p;
        EXPECT_TRUE(set.contains(y));
        double closest = 1.0;
        for (Eigen::Index i = 0; i < set.blocks(); ++i)
            closest = std::min(closest, std::abs(block_norm(y, i) - set.radius(i)) / set.radius(i));
        EXPECT_LE(closest, 1e-12);
    }
    Vec x = Vec::Zero(set.size()), p = Vec::Zero(set.size());
    EXPECT_EQ(set.feasible_step(x, p), std::numeric_limits<double>::infinity());  // no block moves
}

TEST(DiscSet, FreeAndChoppedGradientsAreTheSteepestFeasibleDescent)
{
    std::mt19937 rng(13);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    const DiscSet set({1.0, 2.0, 0.5, 1.5});
    int inward = 0, outward = 0;
    for (int trial = 0; trial < 10; ++trial) {
        Vec x(set.size()), g(set.size());
        for (Eigen::Index k = 0; k < g.size(); ++k) g[k] = u(rng);
        for (Eigen::Index i = 0; i < set.blocks(); ++i) {
            const double rho = set.radius(i) * (i % 2 == 0 ? 1.0 : 0.5);  // blocks 0, 2 on their circle
            const double th = PI * u(rng);
            x[2 * i] = rho * std::cos(th);
            x[2 * i + 1] = rho * std::sin(th);
        }
        Vec phi, beta;
        set.free_gradient(x, g, phi);
        set.chopped_gradient(x, g, beta);
        for (Eigen::Index i = 0; i < set.blocks(); ++i) {
            const bool on = i % 2 == 0;
            ASSERT_EQ(set.active(x, i), on);
            // The projected gradient of block i: phi_i + beta_i, one of them zero.
            const double gp0 = phi[2 * i] + beta[2 * i], gp1 = phi[2 * i + 1] + beta[2 * i + 1];
            EXPECT_EQ(on ? phi[2 * i] : beta[2 * i], 0.0);
            EXPECT_EQ(on ? phi[2 * i + 1] : beta[2 * i + 1], 0.0);
            // Brute force: the steepest descent g_i'd over unit directions d that stay in the disc to
            // first order (d'x_i <= 0 on the circle, any d inside) is -|g_i^P|, along -g_i^P.
            double best = 0.0, best0 = 0.0, best1 = 0.0;
            const int directions = 200000;
            for (int k = 0; k < directions; ++k) {
                const double th = 2.0 * PI * k / directions, d0 = std::cos(th), d1 = std::sin(th);
                if (on && d0 * x[2 * i] + d1 * x[2 * i + 1] > 0.0) continue;
                const double slope = g[2 * i] * d0 + g[2 * i + 1] * d1;
                if (slope < best) {
                    best = slope;
                    best0 = d0;
                    best1 = d1;
                }
            }
            // The grid misses the optimum by at most one angle step (it may lie on the cone's edge,
            // the tangent, where the slope changes linearly with the angle).
            const double norm_gp = std::hypot(gp0, gp1), step = 2.0 * PI / directions;
            EXPECT_GE(norm_gp, -best - 1e-12) << "block " << i;
            EXPECT_LE(norm_gp, -best + std::hypot(g[2 * i], g[2 * i + 1]) * step) << "block " << i;
            if (norm_gp > 1e-3) {
                EXPECT_NEAR(-gp0 / norm_gp, best0, 2.0 * step) << "block " << i;
                EXPECT_NEAR(-gp1 / norm_gp, best1, 2.0 * step) << "block " << i;
            }
            if (on) ++(g[2 * i] * x[2 * i] + g[2 * i + 1] * x[2 * i + 1] < 0.0 ? outward : inward);
        }
    }
    EXPECT_GT(inward, 0);   // both cases covered: -g pointing into the disc (beta = g) ...
    EXPECT_GT(outward, 0);  // ... and out of it (beta = the tangential part)
}

}  // namespace
