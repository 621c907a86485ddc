// The MPRGP engine (solvers/mprgp/mprgp_engine.hpp) on a separable convex set other than half-spaces:
// a Tresca-like problem, min 1/2 x'Ax - b'x with |x_i| <= g_i per 2-block (solvers/mprgp/disc_set.hpp).
// Its answer is checked against an independent projected-gradient solve and against the KKT
// conditions of the disc problem.
#include "solvers/linalg/a_product.hpp"
#include "solvers/mprgp/disc_set.hpp"
#include "solvers/mprgp/mprgp_feasible.hpp"
#include "solvers/mprgp/mprgp_kernels.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace {

using cb::Vec;

struct DiscProblem {
    cb::SpMat A;
    Vec b;
    std::vector<double> radius;
};

/// A random SPD A (blocks coupled), b large enough that some discs bind and some do not.
DiscProblem make_problem(unsigned seed, Eigen::Index blocks)
{
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    const Eigen::Index n = 2 * blocks;
    Eigen::MatrixXd m(n, n);
    for (Eigen::Index i = 0; i < n; ++i)
        for (Eigen::Index j = 0; j < n; ++j) m(i, j) = u(rng);
    const Eigen::MatrixXd dense = m.transpose() * m + 0.5 * Eigen::MatrixXd::Identity(n, n);
    DiscProblem p;
    p.A = dense.sparseView();
    p.b.resize(n);
    for (Eigen::Index k = 0; k < n; ++k) p.b[k] = 4.0 * u(rng);
    for (Eigen::Index i = 0; i < blocks; ++i) p.radius.push_back(0.2 + 0.8 * (0.5 + 0.5 * u(rng)));
    return p;
}

/// Projected gradient x = P(x - t(Ax - b)), t = 1/||A||_F, until a step moves x by <= 1e-15.
Vec projected_gradient(const DiscProblem& p, const cb::DiscSet& set)
{
    const double t = 1.0 / Eigen::MatrixXd(p.A).norm();
    Vec x = Vec::Zero(p.b.size());
    for (int k = 0; k < 2000000; ++k) {
        Vec next = x - t * (p.A * x - p.b);
        set.project(next);
        const double moved = (next - x).norm();
        x = next;
        if (moved <= 1e-15) break;
    }
    return x;
}

/// The KKT residual of the disc problem at a feasible x: off the circle g_i = 0; on it
/// g_i = -lambda_i x_i / |x_i| with lambda_i >= 0 (no tangential part, no outward part).
double kkt_residual(const DiscProblem& p, const cb::DiscSet& set, const Vec& x)
{
    const Vec g = p.A * x - p.b;
    double worst = 0.0;
    for (Eigen::Index i = 0; i < set.blocks(); ++i) {
        const double g0 = g[2 * i], g1 = g[2 * i + 1];
        const double len = std::hypot(x[2 * i], x[2 * i + 1]);
        if (len < set.radius(i) * (1.0 - 1e-9)) {
            worst = std::max(worst, std::hypot(g0, g1));
            continue;
        }
        const double n0 = x[2 * i] / len, n1 = x[2 * i + 1] / len;
        const double gn = g0 * n0 + g1 * n1;
        worst = std::max(worst, std::max(gn, 0.0));                       // lambda = -g'n >= 0
        worst = std::max(worst, std::hypot(g0 - gn * n0, g1 - gn * n1));  // no tangential part
    }
    return worst;
}

struct EngineRun {
    Vec x;
    cb::SolveStatus status;
    cb::Counters counters;
};

EngineRun run_engine(const DiscProblem& p, cb::DiscSet& set, const std::string& precond)
{
    const Eigen::Index n = p.b.size();
    const cb::SpMat no_rows(0, n);
    const Vec no_c(0), x0 = Vec::Zero(n);
    const cb::QpView qp{p.A, p.b, no_rows, no_c, x0};
    cb::CommonSettings common;
    common.tol = 1e-10;
    common.max_iterations = 10000;
    cb::SolveLoop loop("mprgp-disc", qp, common, {});
    EngineRun run;
    cb::AOperator a_op(p.A);
    Vec v;
    const cb::PowerResult power = cb::power_method(a_op, v, cb::PowerRule::POWER, 1000, 1e-12, false, 1);
    const double alpha_bar = 2.0 / (1.01 * power.estimate);
    const Vec dinv = precond == "jacobi" ? Vec(p.A.diagonal().cwiseInverse()) : Vec(Vec::Ones(n));
    EXPECT_TRUE(loop.end_setup());
    cb::FeasibleMprgpSteps<cb::DiscSet> steps(set, a_op, p.b, dinv, alpha_bar, 1.0, loop, run.counters);
    steps.start(x0);
    std::string why;
    run.status = cb::run_mprgp(steps, loop, run.counters, why);
    EXPECT_EQ(why, "");
    run.x = steps.x();
    return run;
}

TEST(MprgpDisc, EngineMatchesProjectedGradientAndKkt)
{
    long cg_steps = 0, mixed_faces = 0;  // over all runs: CG steps taken, runs with free and bound discs
    for (unsigned seed : {1u, 2u, 3u, 4u, 5u}) {
        for (const std::string precond : {"none", "jacobi"}) {
            const DiscProblem p = make_problem(seed, 5);
            cb::DiscSet set(p.radius);
            const EngineRun run = run_engine(p, set, precond);
            const Vec reference = projected_gradient(p, set);
            ASSERT_EQ(run.status, cb::SolveStatus::CONVERGED)
                << "seed " << seed << " " << precond << ": " << run.counters.iterations << " iterations, "
                << run.counters.cg_steps << " cg, " << run.counters.expansion_steps << " expansion, "
                << run.counters.proportioning_steps << " proportioning, " << run.counters.projections << " projections";
            EXPECT_TRUE(set.contains(run.x));
            EXPECT_LE(kkt_residual(p, set, run.x), 1e-9) << "seed " << seed << " " << precond;
            EXPECT_LE(kkt_residual(p, set, reference), 1e-9) << "seed " << seed << " (the reference itself)";
            EXPECT_LE((run.x - reference).norm(), 1e-8 * (1.0 + reference.norm())) << "seed " << seed << " " << precond;
            long on = 0;
            for (Eigen::Index i = 0; i < set.blocks(); ++i) on += set.active(run.x, i);
            EXPECT_GT(on, 0) << "seed " << seed;  // a disc binds at the solution
            mixed_faces += on < set.blocks();
            cg_steps += run.counters.cg_steps;
        }
    }
    // The problems exercise the whole iteration: CG chains on free discs next to bound ones.
    EXPECT_GT(mixed_faces, 0);
    EXPECT_GT(cg_steps, 0);
}

TEST(MprgpDisc, ReducedFreeGradientMatchesItsDefinition)
{
    // phitilde'phi from the projection equals phi'phi where x - alpha_bar phi stays inside.
    cb::DiscSet set({1.0, 1.0});
    Vec x(4), phi(4);
    x << 0.1, 0.2, 0.9, 0.0;
    phi << 0.5, -0.5, 0.5, 0.0;
    set.classify(x);
    EXPECT_NEAR(set.reduced_free_gradient_dot(x, phi, 0.1), phi.squaredNorm(), 1e-15);
    // A step that leaves block 1's disc: x_1 - 0.5 (-1, 0) = (1.4, 0), projected to (1, 0), so
    // phitilde_1 = ((0.9, 0) - (1, 0)) / 0.5 = (-0.2, 0) and phitilde'phi = 0.2, not phi'phi = 1.
    Vec out(4);
    out << 0.0, 0.0, -1.0, 0.0;
    EXPECT_NEAR(set.reduced_free_gradient_dot(x, out, 0.5), 0.2, 1e-15);
}

}  // namespace
