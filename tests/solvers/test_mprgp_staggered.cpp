// `mprgp-staggered` (solvers/friction/mprgp_staggered.hpp): at mu = 0 it is mprgp-coupled, iterate for
// iterate; with friction it reaches the frictional e and agrees with nsgs-friction; on two free
// particles its tangential multipliers are the closed-form sticking and sliding forces; an outer
// cap ends as max_iterations and says which cap.
#include "friction_test_qps.hpp"
#include "harness/runner.hpp"
#include "problems/synthetic.hpp"
#include "solvers/core/registry.hpp"
#include "solvers/measure/accuracy.hpp"
#include "tests/solvers/max_abs.hpp"
#include "tests/solvers/quiet_run_options.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

namespace cb {
namespace {

/// Every iterate x a solver reports.
class StaggeredIterateRecorder : public Monitor {
public:
    bool on_iteration(const IterationInfo& info) override
    {
        if (info.x) iterates.push_back(*info.x);
        return true;
    }
    std::vector<Vec> iterates;
};

TEST(MprgpStaggered, AtMuZeroTakesMprgpCoupledsIterates)
{
    for (const char* family : {"plane", "coupled"}) {
        Qp qp = make_synthetic(family, {{"nx", 3}, {"ny", 2}, {"nz", 3}}, 5);
        testing_qps::add_friction(qp, [](Eigen::Index) { return 0.0; });
        const nlohmann::json settings = {{"tol", 1e-10}};
        StaggeredIterateRecorder ours, coupled;
        const SolverResult r =
            builtin_registry().create("mprgp-staggered", settings)->solve(qp.view(), SolveContext{&ours});
        const SolverResult ref =
            builtin_registry().create("mprgp-coupled", settings)->solve(qp.view(), SolveContext{&coupled});
        SCOPED_TRACE(family);
        ASSERT_EQ(r.status, SolveStatus::CONVERGED) << r.message;
        ASSERT_EQ(ref.status, SolveStatus::CONVERGED) << ref.message;
        EXPECT_EQ(r.info.value("rounds", 0L), 1);  // one outer iteration
        EXPECT_EQ(r.iterations, ref.iterations);
        ASSERT_EQ(ours.iterates.size(), coupled.iterates.size());
        ASSERT_GT(ours.iterates.size(), 3u);
        const double l = accuracy_scale(qp.view()).length;
        for (size_t k = 0; k < ours.iterates.size(); ++k)
            EXPECT_LE(test::max_abs(ours.iterates[k] - coupled.iterates[k]), 1e-14 * l) << "iterate " << k;
        EXPECT_LE(test::max_abs(r.lambda - ref.lambda), 0.0);
        EXPECT_EQ(test::max_abs(r.lambda_t), 0.0);
        EXPECT_EQ(r.message.rfind("mprgp-staggered: converged: accuracy error ", 0), 0u) << r.message;
        // The harness judges it on the snapshot with its friction fields: converged.
        const RunOutcome run = run_solver(qp, "mprgp-staggered", settings, test::quiet_run_options());
        EXPECT_EQ(run.status, "converged") << run.result.message;
    }
}

TEST(MprgpStaggered, ConvergesOnAFrictionalSnapshotAndAgreesWithNsgsFriction)
{
    // The pushed body of test_nsgs_friction.cpp: with mu = 0.5 some contacts stick and some slide,
    // with mu = 0.1 all slide.
    for (const double mu : {0.5, 0.1}) {
        const Qp qp = testing_qps::pushed_plane(0.2, mu);
        const std::string what = "mu = " + std::to_string(mu);
        const RunOutcome run = run_solver(qp, "mprgp-staggered", {{"tol", 1e-8}}, test::quiet_run_options());
        ASSERT_EQ(run.status, "converged") << what << ": " << run.result.message;
        EXPECT_GT(run.result.info.value("rounds", 0L), 1) << what;  // friction takes more than one round
        const Vec& x = run.result.x;
        const double e = accuracy(qp.view(), x, run.result.lambda, &run.result.lambda_t).max();
        EXPECT_LE(e, 1e-8 * (1 + 1e-9)) << what;
        EXPECT_LE(run.record["fclib_error"].get<double>(), 1e-6) << what;
        const RunOutcome ref =
            run_solver(qp, "nsgs-friction", {{"tol", 1e-10}, {"max_iterations", 100000}}, test::quiet_run_options());
        ASSERT_EQ(ref.status, "converged") << what << ": " << ref.result.message;
        const double l = run.scale.length;
        EXPECT_LE(test::max_abs(x - ref.result.x) / l, 1e-6) << what;
        const double force = test::max_abs(ref.lambda_full);
        EXPECT_LE(test::max_abs(run.lambda_full - ref.lambda_full), 1e-5 * force) << what;
        EXPECT_LE(test::max_abs(run.result.lambda_t - ref.result.lambda_t), 1e-5 * force) << what;
    }
}

// stop=native stops on FCLIB's error, which the inner solves' e does not bound: their tolerances
// tighten when the error stops falling (before, a loose schedule held FCLIB's error up: stalled).
TEST(MprgpStaggered, StopNativeReachesFclibsError)
{
    for (const double mu : {0.5, 0.1}) {
        const Qp qp = testing_qps::pushed_plane(0.2, mu);
        for (const double tol : {1e-8, 1e-10}) {
            const RunOutcome run =
                run_solver(qp, "mprgp-staggered", {{"tol", tol}, {"stop", "native"}}, test::quiet_run_options());
            const std::string what = "mu = " + std::to_string(mu) + ", tol " + std::to_string(tol);
            ASSERT_EQ(run.result.status, SolveStatus::CONVERGED) << what << ": " << run.result.message;
            EXPECT_LE(run.record["fclib_error"].get<double>(), tol * (1 + 1e-9)) << what;
            EXPECT_EQ(run.status, "converged") << what;  // and e <= 1e-6, the harness's rule for native
        }
    }
}

/// Two free unit-mass particles on the plane z >= 0, each pressed down by 1 and pushed sideways by
/// `push0` and `push1`; mu = 0.5 and the identity tangent frame (T picks x and y).
Qp two_particles(const Eigen::Vector2d& push0, const Eigen::Vector2d& push1)
{
    Qp qp;
    qp.A.resize(6, 6);
    qp.A.setIdentity();
    qp.b = Vec::Zero(6);
    qp.b << push0[0], push0[1], -1.0, push1[0], push1[1], -1.0;
    qp.J.resize(2, 6);
    qp.J.insert(0, 2) = 1.0;
    qp.J.insert(1, 5) = 1.0;
    qp.c = Vec::Zero(2);
    qp.x0 = Vec::Zero(6);
    qp.friction.T.resize(4, 6);
    qp.friction.T.insert(0, 0) = 1.0;
    qp.friction.T.insert(1, 1) = 1.0;
    qp.friction.T.insert(2, 3) = 1.0;
    qp.friction.T.insert(3, 4) = 1.0;
    qp.friction.mu = Vec::Constant(2, 0.5);
    qp.friction.cT = Vec::Zero(4);
    qp.A.makeCompressed();  // as the snapshot reader gives them (mprgp-coupled reads raw storage)
    qp.J.makeCompressed();
    qp.friction.T.makeCompressed();
    return qp;
}

TEST(MprgpStaggered, StickingAndSlidingParticlesGetTheClosedFormTangentialForces)
{
    // A x - b = J'lambda + T'lambda_T with x_z = 0: lambda = 1. Particle 0 (push 0.3 < mu) sticks:
    // x_T = 0, lambda_T = -push. Particle 1 (push |(2, 1)| > mu) slides: lambda_T = -mu push / |push|
    // on the cone, against the slip x_T = push + lambda_T.
    const Eigen::Vector2d push0(0.3, 0.0), push1(2.0, 1.0);
    const Qp qp = two_particles(push0, push1);
    const SolverResult r =
        builtin_registry().create("mprgp-staggered", {{"tol", 1e-12}})->solve(qp.view(), SolveContext{});
    ASSERT_EQ(r.status, SolveStatus::CONVERGED) << r.message;
    EXPECT_NEAR(r.lambda[0], 1.0, 1e-10);
    EXPECT_NEAR(r.lambda[1], 1.0, 1e-10);
    const Eigen::Vector2d slide = -0.5 * push1.normalized();
    EXPECT_NEAR(r.lambda_t[0], -push0[0], 1e-10);
    EXPECT_NEAR(r.lambda_t[1], -push0[1], 1e-10);
    EXPECT_NEAR(r.lambda_t[2], slide[0], 1e-10);
    EXPECT_NEAR(r.lambda_t[3], slide[1], 1e-10);
    EXPECT_NEAR(r.x[0], 0.0, 1e-10);  // sticks
    EXPECT_NEAR(r.x[3], push1[0] + slide[0], 1e-10);
    EXPECT_NEAR(r.x[4], push1[1] + slide[1], 1e-10);
}

TEST(MprgpStaggered, TheOuterCapEndsAsMaxIterationsAndSaysSo)
{
    const Qp qp = testing_qps::pushed_plane(0.2, 0.5);
    const SolverResult r = builtin_registry()
                               .create("mprgp-staggered", {{"tol", 1e-8}, {"max_outer", 1}})
                               ->solve(qp.view(), SolveContext{});
    ASSERT_EQ(r.status, SolveStatus::MAX_ITERATIONS) << r.message;
    EXPECT_EQ(r.message.rfind("mprgp-staggered: outer cap max_outer = 1 rounds reached; 1 rounds (", 0), 0u)
        << r.message;
    EXPECT_EQ(r.lambda_t.size(), 2 * qp.m());
}

// The frictional path keeps the solve-loop contract that Conformance checks on frictionless problems.
TEST(MprgpStaggered, FrictionalRunsKeepTheSolveLoopContract)
{
    Qp qp = testing_qps::pushed_plane(0.2, 0.5);
    auto solve = [&](const nlohmann::json& settings) {
        return builtin_registry().create("mprgp-staggered", settings)->solve(qp.view(), SolveContext{});
    };
    const SolverResult timed = solve({{"time_limit_s", 1e-12}});
    EXPECT_EQ(timed.status, SolveStatus::TIME_LIMIT) << timed.message;
    EXPECT_EQ(timed.message.rfind("mprgp-staggered: time limit of 1e-12 s reached during setup (after ", 0), 0u)
        << timed.message;
    const SolverResult capped = solve({{"tol", 1e-12}, {"max_iterations", 5}});
    EXPECT_EQ(capped.status, SolveStatus::MAX_ITERATIONS) << capped.message;
    EXPECT_EQ(capped.message.rfind("mprgp-staggered: iteration cap 5 reached", 0), 0u) << capped.message;
    EXPECT_LE(capped.iterations, 5);
    const SolverResult refused = solve({{"max_contacts", qp.m() - 1}});
    EXPECT_EQ(refused.status, SolveStatus::NOT_APPLICABLE) << refused.message;
    qp.b[0] = std::numeric_limits<double>::quiet_NaN();
    const SolverResult nan = solve(nlohmann::json::object());
    EXPECT_EQ(nan.status, SolveStatus::DIVERGED) << nan.message;
    EXPECT_EQ(nan.message.rfind("mprgp-staggered: non-finite iterate", 0), 0u) << nan.message;
}

}  // namespace
}  // namespace cb
