// Tests of `cg` (PCG on A x = b, constraints ignored): hand-derived solutions, its stop rules,
// counters, monitor calls, breakdown and settings errors.
#include "problems/synthetic.hpp"
#include "solvers/measure/accuracy.hpp"
#include "solvers/methods/cg.hpp"
#include "tests/solvers/tiny_qps.hpp"

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace {

using cb::Qp;
using cb::SolverResult;
using cb::SolveStatus;
using cb::Vec;

SolverResult run_cg(const Qp& qp, const nlohmann::json& settings, cb::Monitor* monitor = nullptr)
{
    cb::CgSolver solver(cb::CgSettings::from_json(settings));
    cb::SolveContext context;
    context.monitor = monitor;
    return solver.solve(qp.view(), context);
}

struct RecordingMonitor : cb::Monitor {
    std::vector<cb::StepKind> steps;
    std::vector<double> residuals;
    std::vector<double> true_residuals;
    const Qp* qp = nullptr;
    bool on_iteration(const cb::IterationInfo& info) override
    {
        steps.push_back(info.step);
        residuals.push_back(info.native_residual);
        true_residuals.push_back((qp->b - qp->A * *info.x).norm());
        EXPECT_EQ(info.lambda->size(), qp->m());
        return true;
    }
};

}  // namespace

// A = [[4,1,0],[1,3,1],[0,1,2]], b = (3,0,3): x* = (1,-1,2). Plain CG is exact in n = 3 steps.
TEST(Cg, SolvesHandUnconstrainedQpInThreeSteps)
{
    const Qp qp = cb::testing_qps::unconstrained_qp();
    const SolverResult r = run_cg(qp, {{"tol", 1e-12}, {"precond", "none"}});
    ASSERT_EQ(r.status, SolveStatus::CONVERGED) << r.message;
    EXPECT_EQ(r.criterion, cb::StopCriterion::ACCURACY);
    EXPECT_LE((r.x - cb::testing_qps::unconstrained_x()).lpNorm<Eigen::Infinity>(), 1e-12);
    EXPECT_LE(r.iterations, 3);
    EXPECT_EQ(r.lambda.size(), 0);
    EXPECT_EQ(r.info["ignores_constraints"], true);
    EXPECT_EQ(r.counters.precond_applications, 0);
    // one product for r0, one per iteration, one to confirm on the true residual, plus the
    // accuracy scale's (x0 = 0 is one point: l is the extent of a PCG estimate of x_u)
    const long scale_products = cb::accuracy_scale(qp.view()).a_products;
    EXPECT_GE(scale_products, 2);
    EXPECT_EQ(r.counters.a_products, r.iterations + 2 + scale_products);
    EXPECT_EQ(r.counters.cg_steps, r.iterations);
}

// With a diagonal A, Jacobi-PCG is exact after one step.
TEST(Cg, JacobiIsExactOnDiagonalA)
{
    Eigen::MatrixXd A = Eigen::MatrixXd::Zero(4, 4);
    A.diagonal() << 1, 10, 100, 1000;
    const Qp qp =
        cb::testing_qps::dense_qp(A, Eigen::Vector4d(1, 20, 300, 4000), Eigen::MatrixXd(0, 4), Vec(0), Vec::Zero(4));
    const SolverResult r = run_cg(qp, {{"tol", 1e-14}});
    ASSERT_EQ(r.status, SolveStatus::CONVERGED) << r.message;
    EXPECT_EQ(r.iterations, 1);
    EXPECT_LE((r.x - Eigen::Vector4d(1, 2, 3, 4)).norm(), 1e-12);
    EXPECT_EQ(r.counters.precond_applications, 2);  // z0 and z1
}

// The constrained STYLE example: cg ignores x0 >= 1 and returns the unconstrained (0, 1), lambda = 0.
TEST(Cg, IgnoresConstraintsAndReturnsZeroMultipliers)
{
    const Qp qp = cb::testing_qps::tiny_active_qp();
    const SolverResult r = run_cg(qp, {{"tol", 1e-12}});
    ASSERT_EQ(r.status, SolveStatus::CONVERGED) << r.message;
    EXPECT_NEAR(r.x[0], 0.0, 1e-12);
    EXPECT_NEAR(r.x[1], 1.0, 1e-12);
    ASSERT_EQ(r.lambda.size(), 1);
    EXPECT_EQ(r.lambda[0], 0.0);
    EXPECT_FALSE(r.lambda_fitted);
    EXPECT_EQ(r.info["ignores_constraints"], true);
    EXPECT_GT(cb::max_violation(qp.view(), r.x), 0.99);  // x0 >= 1 violated by 1
}

// stop=kkt: the accuracy error of the unconstrained problem, its stationarity part <= tol, with
// l the extent of x0 (docs/accuracy.md); checked on the returned x.
TEST(Cg, KktStopIsTheUnconstrainedAccuracyError)
{
    const Qp qp = cb::make_synthetic("unconstrained", {{"nx", 3}, {"ny", 3}, {"nz", 3}}, 2);
    const cb::AccuracyScale scale = cb::accuracy_scale(qp.view());
    for (double tol : {1e-3, 1e-6, 1e-9}) {
        const SolverResult r = run_cg(qp, {{"tol", tol}});
        ASSERT_EQ(r.status, SolveStatus::CONVERGED) << r.message;
        const Vec g = qp.A * r.x - qp.b;
        const double jacobi = g.cwiseQuotient(Vec(qp.A.diagonal())).lpNorm<Eigen::Infinity>() / scale.length;
        // With m = 0 the accuracy error is the stationarity part: the larger of the Jacobi step and
        // the body's rigid motion (docs/accuracy.md), computed here from its definition.
        const double body = scale.body_motion(r.x, Vec(0));
        const double at_x = std::max(jacobi, body);
        EXPECT_LE(at_x, tol);
        EXPECT_NEAR(cb::accuracy(qp.view(), r.x, r.lambda).max(), at_x, 1e-12 * at_x);
        EXPECT_NEAR(r.info["unconstrained_error"].get<double>(), at_x, 1e-9 * at_x);
    }
}

TEST(Cg, NativeStopIsAbsoluteResidualNorm)
{
    const Qp qp = cb::make_synthetic("unconstrained", {{"nx", 3}, {"ny", 3}, {"nz", 3}}, 2);
    const SolverResult r = run_cg(qp, {{"tol", 1e-9}, {"stop", "native"}});
    ASSERT_EQ(r.status, SolveStatus::CONVERGED) << r.message;
    EXPECT_EQ(r.criterion, cb::StopCriterion::NATIVE);
    const double residual = (qp.b - qp.A * r.x).norm();
    EXPECT_LE(residual, 1e-9);
    EXPECT_NEAR(r.native_residual, residual, 1e-12);
}

TEST(Cg, StartAtSolutionConvergesWithoutIterations)
{
    Qp qp = cb::testing_qps::unconstrained_qp();
    qp.x0 = cb::testing_qps::unconstrained_x();
    const SolverResult r = run_cg(qp, {});
    EXPECT_EQ(r.status, SolveStatus::CONVERGED) << r.message;
    EXPECT_EQ(r.iterations, 0);
}

TEST(Cg, IterationCapGivesMaxIterations)
{
    const Qp qp = cb::make_synthetic("unconstrained", {{"nx", 3}, {"ny", 3}, {"nz", 3}}, 2);
    const SolverResult r = run_cg(qp, {{"max_iterations", 2}});
    EXPECT_EQ(r.status, SolveStatus::MAX_ITERATIONS);
    EXPECT_EQ(r.iterations, 2);
    EXPECT_EQ(r.criterion, cb::StopCriterion::NONE);
    EXPECT_NEAR(r.native_residual, (qp.b - qp.A * r.x).norm(), 1e-12 * std::max(1.0, r.native_residual));
}

TEST(Cg, MonitorSeesEveryIterationWithTheResidualNorm)
{
    const Qp qp = cb::make_synthetic("unconstrained", {{"nx", 2}, {"ny", 2}, {"nz", 2}}, 2);
    RecordingMonitor monitor;
    monitor.qp = &qp;
    const SolverResult r = run_cg(qp, {{"tol", 1e-8}}, &monitor);
    ASSERT_EQ(r.status, SolveStatus::CONVERGED) << r.message;
    ASSERT_EQ(static_cast<long>(monitor.steps.size()), r.iterations + 1);
    EXPECT_EQ(monitor.steps.front(), cb::StepKind::START);
    EXPECT_EQ(monitor.steps.back(), cb::StepKind::CG);
    for (size_t k = 0; k < monitor.steps.size(); ++k)
        EXPECT_NEAR(monitor.residuals[k], monitor.true_residuals[k], 1e-8 * std::max(1.0, monitor.true_residuals[0]));
}

// A = [[1,2],[2,1]] is indefinite: from x0 = 0 with b = (1,-1) the first direction has
// p'Ap = -2 < 0 (unpreconditioned: p = b).
TEST(Cg, NegativeCurvatureIsDiverged)
{
    Eigen::MatrixXd A(2, 2);
    A << 1, 2, 2, 1;
    const Qp qp = cb::testing_qps::dense_qp(A, Eigen::Vector2d(1, -1), Eigen::MatrixXd(0, 2), Vec(0), Vec::Zero(2));
    const SolverResult r = run_cg(qp, {{"precond", "none"}});
    EXPECT_EQ(r.status, SolveStatus::DIVERGED);
    EXPECT_EQ(r.message, "cg: breakdown at iteration 0: p'Ap = -2 < 0 (A is not positive definite)");
}

TEST(Cg, JacobiNeedsPositiveDiagonal)
{
    Eigen::MatrixXd A(2, 2);
    A << 1, 0, 0, 0;
    const Qp qp = cb::testing_qps::dense_qp(A, Eigen::Vector2d(1, 1), Eigen::MatrixXd(0, 2), Vec(0), Vec::Zero(2));
    const SolverResult r = run_cg(qp, {});
    EXPECT_EQ(r.status, SolveStatus::INVALID_INPUT);
    EXPECT_EQ(r.message, "cg: jacobi preconditioner needs a positive diagonal; A(1,1) = 0");
}

TEST(Cg, SettingsAreCheckedByName)
{
    try {
        cb::CgSettings::from_json({{"precond", "ilu"}});
        FAIL() << "no exception";
    } catch (const cb::InputError& e) {
        EXPECT_EQ(std::string(e.what()), "cg: /precond: expected one of none | jacobi | ichol, got \"ilu\"");
    }
    EXPECT_THROW(cb::CgSettings::from_json({{"start", "projected"}}), cb::InputError);
    const cb::CgSettings d = cb::CgSettings::from_json(nlohmann::json::object());
    EXPECT_EQ(d.precond, "jacobi");
    EXPECT_EQ(d.to_json()["precond"], "jacobi");
    EXPECT_EQ(d.to_json()["tol"], 1e-6);
}

namespace {

// cg's setup in the record (info.setup_phases_s): the accuracy measure's scale is part of the
// setup, as in the other solvers, and the preconditioner and deflation have parts of their own.
TEST(Cg, SetupPhasesIncludeTheMeasureScale)
{
    const Qp qp = cb::make_synthetic("plane", {{"nx", 4}, {"ny", 3}, {"nz", 4}}, 2);
    const SolverResult plain = run_cg(qp, {{"tol", 1e-8}});
    ASSERT_TRUE(plain.info.contains("setup_phases_s")) << plain.info.dump();
    std::vector<std::string> keys;
    double sum = 0.0;
    for (const auto& [key, value] : plain.info["setup_phases_s"].items()) {
        keys.push_back(key);
        sum += value.get<double>();
    }
    EXPECT_EQ(keys, (std::vector<std::string>{"a_prepare", "measure_scale", "other", "preconditioner"}));
    EXPECT_NEAR(sum, plain.setup_s, 1e-9);
    EXPECT_GT(plain.info["setup_phases_s"]["measure_scale"].get<double>(), 0.0);
    const SolverResult rigid = run_cg(qp, {{"tol", 1e-8}, {"deflation", "rigid"}});
    EXPECT_TRUE(rigid.info["setup_phases_s"].contains("deflation")) << rigid.info.dump();
    EXPECT_GT(rigid.iterations, 0);
}

}  // namespace
