// The accuracy measure's body modes (solvers/measure/body_motion.hpp, n x 6 doubles of AV and
// n-sized parts) are held once: copies of a scale and accuracy_scale_with_rows share them, and a
// run without a recorded history never holds two blocks at once (the solver's, for its stop
// test, then the harness's, built after the solve: harness/runner.cpp). Counted by
// BodyMotion::peak_live_modes(), not by the process's resident memory.
#include "harness/runner.hpp"
#include "problems/synthetic.hpp"
#include "solvers/measure/accuracy.hpp"
#include "solvers/measure/body_motion.hpp"

#include <gtest/gtest.h>

namespace {

using cb::AccuracyScale;
using cb::BodyMotion;
using cb::Qp;

Qp body_motion_sharing_qp() { return cb::make_synthetic("plane", {{"nx", 3}, {"ny", 2}, {"nz", 3}}, 5); }

TEST(BodyMotionSharing, CopiesAndRowVariantsShareOneBlock)
{
    const Qp qp = body_motion_sharing_qp();
    ASSERT_GT(qp.m(), 2);
    const long before = BodyMotion::live_modes();
    const AccuracyScale scale = cb::accuracy_scale(qp.view());
    EXPECT_EQ(BodyMotion::live_modes(), before + 1);
    const AccuracyScale copy = scale;
    const cb::SpMat no_rows(0, qp.n());
    const cb::Vec no_c(0);
    const cb::QpView relaxed{qp.A, qp.b, no_rows, no_c, qp.x0, &qp.length};
    const AccuracyScale with_rows = cb::accuracy_scale_with_rows(scale, relaxed);
    EXPECT_EQ(BodyMotion::live_modes(), before + 1);  // neither the copy nor the row variant built one
    EXPECT_TRUE(copy.bodies.shares_modes_with(scale.bodies));
    EXPECT_TRUE(with_rows.bodies.shares_modes_with(scale.bodies));
    // The row variant is still the fresh scale of its view, to the bit.
    const AccuracyScale fresh = cb::accuracy_scale(relaxed);
    EXPECT_FALSE(fresh.bodies.shares_modes_with(scale.bodies));
    cb::Vec x = qp.x0;
    for (Eigen::Index j = 0; j < x.size(); ++j) x[j] += 1e-4 * double((j * 7) % 5 - 2);
    const double motion = fresh.body_motion(x, cb::Vec());
    EXPECT_GT(motion, 0.0);
    EXPECT_EQ(with_rows.body_motion(x, cb::Vec()), motion);
    EXPECT_EQ(with_rows.inv_row_norm.size(), 0);
}

TEST(BodyMotionSharing, RunWithoutHistoryHoldsOneBlockAtATime)
{
    const Qp qp = body_motion_sharing_qp();
    for (const char* solver : {"cg", "mprgp", "mprgp-coupled"}) {
        for (const bool history : {false, true}) {
            cb::RunOptions options;
            options.record_history = history;
            BodyMotion::reset_peak_live_modes();
            const long before = BodyMotion::live_modes();
            const cb::RunOutcome run = cb::run_solver(qp, solver, {{"tol", 1e-8}}, options);
            EXPECT_EQ(run.status, std::string(solver) == "cg" ? "solved_relaxation" : "converged") << solver;
            EXPECT_GT(run.scale.bodies.bodies(), 0) << solver;  // the record's scale is there
            // Without a history the harness builds its scale after the solver has freed its own;
            // with one, the monitor measures iterates during the solve and both are alive.
            EXPECT_EQ(BodyMotion::peak_live_modes() - before, history ? 2 : 1) << solver << " history " << history;
        }
    }
}

}  // namespace
