// Tests of `ica` (ALGORITHMS.md §6): convergence on the common KKT, the published native stop
// and what it misses, counters, options and refusals.
#include "harness/runner.hpp"
#include "solvers/core/registry.hpp"
#include "solvers/methods/ica.hpp"
#include "tests/solvers/dual_test_problems.hpp"

#include <Eigen/SparseCholesky>
#include <gtest/gtest.h>

namespace cb {
namespace {

using test::GridQpParams;
using test::make_grid_qp;
using test::relative_kkt;

SolverResult run_ica(const Qp& qp, const nlohmann::json& settings, const SolveContext& context = {})
{
    return builtin_registry().create("ica", settings)->solve(qp.view(), context);
}

TEST(Ica, ConvergesOnPlaneRowsToTheCommonKkt)
{
    const Qp qp = make_grid_qp(GridQpParams{});
    ASSERT_GT(qp.m(), 10);
    const SolverResult r = run_ica(qp, {{"tol", 1e-6}});
    ASSERT_EQ(r.status, SolveStatus::CONVERGED) << r.message;
    EXPECT_EQ(r.criterion, cb::StopCriterion::ACCURACY);
    EXPECT_LE(relative_kkt(qp, r.x, r.lambda), 1e-6);
    EXPECT_FALSE(r.lambda_fitted);
    EXPECT_LT(max_violation(qp.view(), r.x), 1e-6);
    // Native residual recorded beside the KKT: ||Ax - b - J'lambda||_2 at the returned point.
    EXPECT_NEAR(r.native_residual, (qp.A * r.x - qp.b - qp.J.transpose() * r.lambda).norm(), 1e-12);
    // Counting documented in ica.hpp: A x0 (+ the accuracy scale's, none for this start with an
    // extent), then 2 per outer iteration.
    EXPECT_EQ(accuracy_scale(qp.view()).a_products, 0);
    EXPECT_EQ(r.counters.a_products, 1 + 2 * r.iterations);
    EXPECT_EQ(r.counters.iterations, r.iterations);
    EXPECT_GE(r.counters.pgs_sweeps, r.iterations);
    EXPECT_LE(r.counters.pgs_sweeps, 20 * r.iterations);
    EXPECT_EQ(r.counters.cholmod_factorizations, 0);
}

TEST(Ica, ConvergesWithCoupledRows)
{
    GridQpParams p;
    p.coupled = true;
    const Qp qp = make_grid_qp(p);
    const SolverResult r = run_ica(qp, {{"tol", 1e-6}, {"max_iterations", 20000}});
    ASSERT_EQ(r.status, SolveStatus::CONVERGED) << r.message;
    EXPECT_LE(relative_kkt(qp, r.x, r.lambda), 1e-6);
    EXPECT_EQ(r.info.at("B_diagonal"), false);
}

TEST(Ica, ReportsMaxIterationsHonestly)
{
    const Qp qp = make_grid_qp(GridQpParams{});
    const SolverResult r = run_ica(qp, {{"tol", 1e-12}, {"max_iterations", 3}});
    EXPECT_EQ(r.status, SolveStatus::MAX_ITERATIONS);
    EXPECT_EQ(r.iterations, 3);
    EXPECT_EQ(r.criterion, cb::StopCriterion::NONE);
    EXPECT_GT(relative_kkt(qp, r.x, r.lambda), 1e-12);
}

// What the common metric adds: ICA's published stop looks at stationarity only, so it can
// declare success at a point that still penetrates.
TEST(Ica, NativeStopMeetsStationarityWhileStillPenetrating)
{
    GridQpParams p;
    p.stiffness = 200.0;  // stiff: GS sweeps propagate the contact forces slowly
    const Qp qp = make_grid_qp(p);
    const double tol = 1e-2;
    const SolverResult r = run_ica(qp, {{"stop", "native"}, {"tol", tol}});
    ASSERT_EQ(r.status, SolveStatus::CONVERGED) << r.message;
    EXPECT_EQ(r.criterion, cb::StopCriterion::NATIVE);
    EXPECT_LE(r.native_residual, tol);
    const double violation = max_violation(qp.view(), r.x);
    EXPECT_GT(violation, 1e-4);
    const AccuracyParts k = accuracy(qp.view(), r.x, r.lambda);
    EXPECT_GT(k.primal, 1e-4);  // the accuracy measure shows the penetration ICA never checks
    EXPECT_GT(relative_kkt(qp, r.x, r.lambda), 1e-4);

    // Through the harness: the solver's "converged" is not the run's status (unconfirmed).
    RunOptions options;
    options.decouple = "none";
    const RunOutcome out = run_solver(qp, "ica", {{"stop", "native"}, {"tol", tol}}, options);
    EXPECT_EQ(out.result.status, SolveStatus::CONVERGED);
    EXPECT_EQ(out.result.criterion, cb::StopCriterion::NATIVE);
    EXPECT_GT(out.accuracy.primal, 1e-4);
    EXPECT_GT(out.violation, 1e-4);
    EXPECT_FALSE(out.status_confirmed);
    EXPECT_EQ(out.status, "unconfirmed");
    EXPECT_EQ(out.record.at("status"), "unconfirmed");
    EXPECT_EQ(out.record.at("solver_status"), "converged");
    EXPECT_EQ(out.record.at("criterion"), "native");
}

TEST(Ica, UnconstrainedStartIsTimedApartAndCounted)
{
    const Qp qp = make_grid_qp(GridQpParams{});
    const SolverResult r = run_ica(qp, {{"tol", 1e-6}, {"start", "unconstrained"}});
    ASSERT_EQ(r.status, SolveStatus::CONVERGED) << r.message;
    EXPECT_LE(relative_kkt(qp, r.x, r.lambda), 1e-6);
    EXPECT_EQ(r.counters.cholmod_factorizations, 1);
    EXPECT_EQ(r.counters.cholmod_solves, 1);
    EXPECT_EQ(r.info.at("start"), "unconstrained");
    EXPECT_GE(r.info.at("start_solve_s").get<double>(), 0.0);
    EXPECT_LE(r.info.at("start_solve_s").get<double>(), r.setup_s);
}

TEST(Ica, EmptyJIsBlockGaussSeidel)
{
    Qp qp = make_grid_qp(GridQpParams{});
    qp.J = SpMat(0, qp.n());
    qp.c = Vec(0);
    const SolverResult r = run_ica(qp, {{"tol", 1e-8}});
    ASSERT_EQ(r.status, SolveStatus::CONVERGED) << r.message;
    const Vec exact = Eigen::SimplicialLDLT<SpMatCol>(SpMatCol(qp.A)).solve(qp.b);
    EXPECT_LT((r.x - exact).lpNorm<Eigen::Infinity>(), 1e-6);
    EXPECT_EQ(r.lambda.size(), 0);
}

TEST(Ica, ZeroRowsOfJAreHarmless)
{
    Qp qp = make_grid_qp(GridQpParams{});
    // Append two zero rows with c = 0 (satisfied by every x).
    SpMat J(qp.m() + 2, qp.n());
    std::vector<Triplet> t;
    for (int i = 0; i < qp.J.outerSize(); ++i)
        for (SpMat::InnerIterator it(qp.J, i); it; ++it) t.emplace_back(i, static_cast<int>(it.col()), it.value());
    J.setFromTriplets(t.begin(), t.end());
    qp.J = J;
    qp.c.conservativeResize(qp.J.rows());
    qp.c.tail(2).setZero();
    const SolverResult r = run_ica(qp, {{"tol", 1e-6}});
    ASSERT_EQ(r.status, SolveStatus::CONVERGED) << r.message;
    EXPECT_LE(relative_kkt(qp, r.x, r.lambda), 1e-6);
    EXPECT_EQ(r.lambda.tail(2), Vec::Zero(2));
    EXPECT_EQ(r.info.at("zero_rows"), 2);
}

TEST(Ica, RefusesNonSpdBlocks)
{
    Qp qp = make_grid_qp(GridQpParams{});
    qp.A.coeffRef(4, 4) = -1.0;
    const SolverResult r = run_ica(qp, {});
    EXPECT_EQ(r.status, SolveStatus::INVALID_INPUT);
    EXPECT_EQ(r.message, "ica: A must be SPD: 3x3 diagonal block of vertex 1 (rows 3..5) is not positive definite");
}

TEST(Ica, TimeLimitStopsTheLoop)
{
    GridQpParams p;
    p.nx = 12, p.ny = 6, p.nz = 12;
    p.stiffness = 1e4;
    const Qp qp = make_grid_qp(p);
    const SolverResult r = run_ica(qp, {{"tol", 1e-14}, {"time_limit_s", 0.05}, {"max_iterations", 100000000}});
    EXPECT_EQ(r.status, SolveStatus::TIME_LIMIT);
    EXPECT_LT(r.setup_s + r.solve_s, 0.5);
}

TEST(Ica, SettingsAreCheckedByName)
{
    EXPECT_THROW(builtin_registry().create("ica", {{"pgs_sweep", 3}}), InputError);
    try {
        builtin_registry().create("ica", {{"start", "cold"}});
        FAIL();
    } catch (const InputError& e) {
        EXPECT_EQ(std::string(e.what()), "ica: /start: expected one of x0 | unconstrained, got \"cold\"");
    }
    const auto solver = builtin_registry().create("ica", {{"pgs_sweeps", 5}});
    EXPECT_EQ(solver->settings().at("pgs_sweeps"), 5);
    EXPECT_EQ(solver->settings().at("pgs_tol"), 1e-3);
    EXPECT_EQ(solver->settings().at("start"), "x0");
}

}  // namespace
}  // namespace cb
