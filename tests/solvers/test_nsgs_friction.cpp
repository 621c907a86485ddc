// `nsgs-friction` (solvers/friction/nsgs_friction.hpp): at mu = 0 it is pgs on the same dual and agrees with
// pgs and active-set; with friction it converges on the frictional e, sticks and slides as
// Coulomb says; and frictionless solvers on a frictional problem are never `converged`.
#include "friction_test_qps.hpp"
#include "harness/runner.hpp"
#include "problems/synthetic.hpp"
#include "solvers/core/registry.hpp"
#include "solvers/measure/accuracy.hpp"
#include "tests/solvers/max_abs.hpp"
#include "tests/solvers/quiet_run_options.hpp"

#include <gtest/gtest.h>
#include <cmath>

namespace cb {
namespace {

TEST(NsgsFriction, AtMuZeroAgreesWithPgsAndActiveSet)
{
    for (const char* family : {"plane", "coupled"}) {
        Qp qp = make_synthetic(family, {{"nx", 3}, {"ny", 2}, {"nz", 3}}, 5);
        for (const bool with_fields : {false, true}) {
            if (with_fields) testing_qps::add_friction(qp, [](Eigen::Index) { return 0.0; });
            const std::string what = std::string(family) + (with_fields ? " (mu = 0 given)" : " (no friction fields)");
            const double l = accuracy_scale(qp.view()).length;
            const RunOutcome ours = run_solver(qp, "nsgs-friction", {{"tol", 1e-12}, {"max_iterations", 100000}},
                                               test::quiet_run_options());
            ASSERT_EQ(ours.status, "converged") << what << ": " << ours.result.message;
            for (const char* other : {"pgs", "active-set"}) {
                const RunOutcome ref =
                    run_solver(qp, other, {{"tol", 1e-12}, {"max_iterations", 100000}}, test::quiet_run_options());
                ASSERT_EQ(ref.status, "converged") << what << " " << other << ": " << ref.result.message;
                EXPECT_LE(test::max_abs(ours.result.x - ref.result.x) / l, 1e-8) << what << " vs " << other;
                EXPECT_LE(test::max_abs(ours.lambda_full - ref.lambda_full), 1e-8 * test::max_abs(ref.lambda_full))
                    << what << " vs " << other;
            }
            EXPECT_FALSE(ours.record.contains("fclib_error")) << what;
            EXPECT_LE(test::max_abs(ours.result.lambda_t), 0.0) << what;  // no tangential force at mu = 0
        }
    }
}

TEST(NsgsFriction, SticksAndSlidesAsCoulombSays)
{
    // Pushed sideways by 0.2 of its weight, the deformable body: with mu = 0.5 its inner contacts
    // stick and its edges slide (measured: 6 of 16 stick), with mu = 0.1 every contact slides on the cone.
    double widest_slip[2] = {0.0, 0.0};
    for (const double mu : {0.5, 0.1}) {
        const Qp qp = testing_qps::pushed_plane(0.2, mu);
        const RunOutcome run =
            run_solver(qp, "nsgs-friction", {{"tol", 1e-8}, {"max_iterations", 100000}}, test::quiet_run_options());
        const std::string what = "mu = " + std::to_string(mu);
        ASSERT_EQ(run.status, "converged") << what << ": " << run.result.message;
        EXPECT_LE(run.accuracy.max(), 1e-8) << what;
        EXPECT_TRUE(run.record["accuracy"].contains("friction")) << what;
        ASSERT_TRUE(run.record.contains("fclib_error")) << what;
        EXPECT_LE(run.record["fclib_error"].get<double>(), 1e-6) << what;
        // Each pressing contact sticks (no slip, force inside the cone) or slides (force on the
        // cone, against the slip).
        const Vec& lt = run.result.lambda_t;
        const Vec slip_all = qp.friction.T * run.result.x - qp.friction.cT;
        const double l = run.scale.length, normal = run.lambda_full.sum();
        long sticking = 0, sliding = 0;
        for (Eigen::Index i = 0; i < qp.m(); ++i) {
            const double lambda = run.lambda_full[i];
            if (!(lambda > 1e-9 * normal)) continue;
            const Eigen::Vector2d force(lt[2 * i], lt[2 * i + 1]), slip(slip_all[2 * i], slip_all[2 * i + 1]);
            const std::string contact = what + ", contact " + std::to_string(i);
            if (slip.norm() <= 1e-6 * l) {
                EXPECT_LE(force.norm(), mu * lambda * (1 + 1e-9)) << contact << ": sticks inside the cone";
                ++sticking;
            } else {
                EXPECT_NEAR(force.norm(), mu * lambda, 1e-6 * lambda) << contact << ": slides on the cone";
                EXPECT_NEAR(force.dot(slip) / (force.norm() * slip.norm()), -1.0, 1e-6)
                    << contact << ": against the slip";
                ++sliding;
            }
            widest_slip[mu == 0.5 ? 0 : 1] = std::max(widest_slip[mu == 0.5 ? 0 : 1], slip.norm() / l);
        }
        if (mu == 0.5) {
            EXPECT_GE(sticking, 4) << what;
            EXPECT_GE(sliding, 1) << what;
        } else {
            EXPECT_EQ(sticking, 0) << what;
            EXPECT_GE(sliding, 8) << what;
        }
    }
    EXPECT_LT(widest_slip[0], widest_slip[1]);  // more friction, less slip
}

TEST(NsgsFriction, FrictionlessSolversOnAFrictionalProblemSolveTheRelaxation)
{
    const Qp qp = testing_qps::pushed_plane(0.2, 0.5);
    ASSERT_TRUE(qp.frictional());
    long relaxations = 0;
    for (const std::string& solver : builtin_registry().names()) {
        const RunOutcome run = run_solver(qp, solver, {{"tol", 1e-6}}, test::quiet_run_options());
        const SolverEntry& entry = builtin_registry().entry(solver);
        if (!entry.needs_settings && entry.make(nlohmann::json::object())->handles_friction()) {
            // A frictional solver (tests/solvers/test_friction_registry.cpp) solves the Coulomb problem or fails.
            EXPECT_NE(run.status, "solved_relaxation") << solver << ": " << run.result.message;
            if (solver == "nsgs-friction" || solver == "mprgp-staggered") {
                EXPECT_EQ(run.status, "converged") << solver << ": " << run.result.message;
            }
            continue;
        }
        EXPECT_NE(run.status, "converged") << solver;
        if (run.result.status != SolveStatus::CONVERGED) continue;
        // It met tol on the problem it solved (the frictionless one), and says so.
        EXPECT_EQ(run.status, "solved_relaxation") << solver;
        EXPECT_LE(run.accuracy_solved.max(), 1e-6 * (1 + 1e-9)) << solver;
        EXPECT_GT(run.accuracy.friction, 1e-6) << solver << ": the push slides a frictionless body";
        const std::string solved = run.record.value("solved_problem", "");
        EXPECT_TRUE(solved == "frictionless" || solved == "decoupled" || solved == "unconstrained") << solver;
        ++relaxations;
    }
    EXPECT_GE(relaxations, 3);  // pgs, active-set, mprgp-coupled at least
}

}  // namespace
}  // namespace cb
