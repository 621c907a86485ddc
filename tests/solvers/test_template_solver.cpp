// Tests of the model solver solvers/methods/template_solver.{hpp,cpp}: registered the way README "Adding a
// solver" says (in a registry of its own here), it solves hand-derived bound QPs (STYLE.md §7) to
// the KKT accuracy asked, honours stop=native and max_iterations, and refuses what it cannot solve.
#include "solvers/core/registry.hpp"
#include "solvers/measure/accuracy.hpp"
#include "solvers/methods/template_solver.hpp"
#include "tests/solvers/tiny_qps.hpp"

#include <gtest/gtest.h>

namespace {

using cb::SolveStatus;
using cb::Vec;

cb::SolverRegistry registry_with_template()
{
    cb::SolverRegistry registry;
    registry.add("template", cb::template_entry());  // step 2 of the recipe
    return registry;
}

TEST(TemplateSolver, SolvesTinyBoundQpToTheAskedKktError)
{
    const cb::Qp qp = cb::testing_qps::tiny_active_qp();  // x* = (1, 1), lambda* = 2
    const auto solver = registry_with_template().create("template", {{"tol", 1e-10}});
    const cb::SolverResult r = solver->solve(qp.view(), {});
    ASSERT_EQ(r.status, SolveStatus::CONVERGED) << r.message;
    EXPECT_EQ(r.criterion, cb::StopCriterion::ACCURACY);
    EXPECT_LE(cb::accuracy(qp.view(), r.x, r.lambda).max(), 1e-10);
    EXPECT_NEAR(r.x[0], 1.0, 1e-9);
    EXPECT_NEAR(r.x[1], 1.0, 1e-9);
    EXPECT_NEAR(r.lambda[0], 2.0, 1e-8);
    EXPECT_EQ(r.counters.a_products,
              r.iterations + 1 + cb::accuracy_scale(qp.view()).a_products);  // a step each, the start, the scale
}

TEST(TemplateSolver, CoupledMatrixWithTwoBoundsAndNativeStop)
{
    const cb::Qp qp = cb::testing_qps::two_row_coupled_qp();  // A = [[2,1],[1,2]]: x* = (1,1), lambda* = (3,3)
    const auto solver = registry_with_template().create("template", {{"stop", "native"}, {"tol", 1e-12}});
    const cb::SolverResult r = solver->solve(qp.view(), {});
    ASSERT_EQ(r.status, SolveStatus::CONVERGED) << r.message;
    EXPECT_EQ(r.criterion, cb::StopCriterion::NATIVE);
    EXPECT_LE(r.native_residual, 1e-12);
    EXPECT_NEAR(r.x[0], 1.0, 1e-12);
    EXPECT_NEAR(r.lambda[0], 3.0, 1e-12);
    EXPECT_NEAR(r.lambda[1], 3.0, 1e-12);
}

TEST(TemplateSolver, IterationCapIsReportedNotHidden)
{
    const cb::Qp qp = cb::testing_qps::two_row_decoupled_qp();
    const auto solver = registry_with_template().create("template", {{"max_iterations", 1}, {"tol", 1e-14}});
    const cb::SolverResult r = solver->solve(qp.view(), {});
    EXPECT_EQ(r.status, SolveStatus::MAX_ITERATIONS);
    EXPECT_EQ(r.iterations, 1);
}

TEST(TemplateSolver, RefusesRowsThatAreNotBounds)
{
    Eigen::MatrixXd J(1, 2);
    J << 1, 1;
    const cb::Qp qp = cb::testing_qps::dense_qp(2.0 * Eigen::MatrixXd::Identity(2, 2), Vec::Zero(2), J,
                                                Vec::Constant(1, 1.0), Vec::Zero(2));
    const cb::SolverResult r = registry_with_template().create("template", {})->solve(qp.view(), {});
    EXPECT_EQ(r.status, SolveStatus::NOT_APPLICABLE);
    EXPECT_EQ(r.message, "template: row 0 of J has 2 nonzeros (bound rows only: one nonzero per row, a x_j >= c)");
}

TEST(TemplateSolver, SettingsAreCheckedAndRecorded)
{
    const auto registry = registry_with_template();
    try {
        registry.create("template", {{"step_size", 1.0}});
        FAIL() << "an unknown key must be rejected";
    } catch (const cb::InputError& e) {
        EXPECT_NE(std::string(e.what()).find("step_size"), std::string::npos) << e.what();
    }
    EXPECT_THROW(registry.create("template", {{"step_scale", 2.5}}), cb::InputError);
    EXPECT_EQ(registry.create("template", {{"step_scale", 0.5}})->settings()["step_scale"], 0.5);
    EXPECT_EQ(registry.entry("template").applies_to, "bounds only (every row of J has at most one nonzero)");
}

}  // namespace
