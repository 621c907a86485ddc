// Tests of `pgs` on the exact dual (ALGORITHMS.md §7): convergence on the common KKT, agreement
// with `ica` and with the reference `active-set`, the row limit, zero and infeasible rows.
#include "solvers/core/registry.hpp"
#include "solvers/methods/pgs.hpp"
#include "tests/solvers/dual_test_problems.hpp"

#include <Eigen/SparseCholesky>
#include <gtest/gtest.h>
#include <cmath>

namespace cb {
namespace {

using test::GridQpParams;
using test::make_grid_qp;
using test::relative_kkt;

SolverResult run_registered(const std::string& solver, const Qp& qp, const nlohmann::json& settings)
{
    return builtin_registry().create(solver, settings)->solve(qp.view(), SolveContext{});
}

double relative_gap(double a, double b) { return std::abs(a - b) / std::max(1.0, std::abs(b)); }

TEST(Pgs, ConvergesOnPlaneRowsToTheCommonKkt)
{
    const Qp qp = make_grid_qp(GridQpParams{});
    const SolverResult r = run_registered("pgs", qp, {{"tol", 1e-8}});
    ASSERT_EQ(r.status, SolveStatus::CONVERGED) << r.message;
    EXPECT_EQ(r.criterion, cb::StopCriterion::ACCURACY);
    EXPECT_LE(relative_kkt(qp, r.x, r.lambda), 1e-8);
    EXPECT_EQ(r.counters.cholmod_factorizations, 1);
    // One solve for A^-1 b, m for S, one per confirmed candidate and the final x.
    EXPECT_GE(r.counters.cholmod_solves, qp.m() + 2);
    EXPECT_EQ(r.counters.pgs_sweeps, r.iterations);
}

TEST(Pgs, AgreesWithIcaOnCoupledRows)
{
    GridQpParams p;
    p.coupled = true;
    const Qp qp = make_grid_qp(p);
    const SolverResult a = run_registered("pgs", qp, {{"tol", 1e-10}, {"max_iterations", 100000}});
    const SolverResult b = run_registered("ica", qp, {{"tol", 1e-10}, {"max_iterations", 100000}});
    ASSERT_EQ(a.status, SolveStatus::CONVERGED) << a.message;
    ASSERT_EQ(b.status, SolveStatus::CONVERGED) << b.message;
    EXPECT_LT(relative_gap(objective(qp.view(), a.x), objective(qp.view(), b.x)), 1e-8);
    EXPECT_LT((a.x - b.x).lpNorm<Eigen::Infinity>(), 1e-6);
}

TEST(Pgs, AgreesWithActiveSetReference)
{
    if (!builtin_registry().contains("active-set")) GTEST_SKIP() << "active-set not registered yet";
    for (bool coupled : {false, true}) {
        GridQpParams p;
        p.coupled = coupled;
        const Qp qp = make_grid_qp(p);
        const SolverResult ref = run_registered("active-set", qp, {});
        const SolverResult r = run_registered("pgs", qp, {{"tol", 1e-10}, {"max_iterations", 100000}});
        ASSERT_EQ(ref.status, SolveStatus::CONVERGED) << ref.message;
        ASSERT_EQ(r.status, SolveStatus::CONVERGED) << r.message;
        EXPECT_LT(relative_gap(objective(qp.view(), r.x), objective(qp.view(), ref.x)), 1e-8) << coupled;
    }
}

TEST(Pgs, NativeStopIsTheNaturalResidual)
{
    const Qp qp = make_grid_qp(GridQpParams{});
    const SolverResult r = run_registered("pgs", qp, {{"stop", "native"}, {"tol", 1e-9}});
    ASSERT_EQ(r.status, SolveStatus::CONVERGED) << r.message;
    EXPECT_EQ(r.criterion, cb::StopCriterion::NATIVE);
    // ||min(lambda, Jx - c)||_inf at the returned point (Jx - c = S lambda - q at x = x(lambda)).
    const Vec slack = qp.J * r.x - qp.c;
    EXPECT_LE(r.lambda.cwiseMin(slack).lpNorm<Eigen::Infinity>(), 1e-9 * 1.01);
    EXPECT_LE(r.native_residual, 1e-9);
}

TEST(Pgs, RefusesTooManyRowsWithTheLimitInTheMessage)
{
    const Qp qp = make_grid_qp(GridQpParams{});
    const SolverResult r = run_registered("pgs", qp, {{"max_rows", 10}});
    EXPECT_EQ(r.status, SolveStatus::NOT_APPLICABLE);
    EXPECT_EQ(r.message, "pgs: m = " + std::to_string(qp.m()) +
                             " rows exceeds max_rows = 10 (S = J A^-1 J' is a dense m x m matrix formed "
                             "with m CHOLMOD solves); raise the max_rows setting to allow it");
    EXPECT_EQ(r.counters.cholmod_factorizations, 0);
}

Qp with_zero_rows(Qp qp, double c_value)
{
    SpMat J(qp.m() + 2, qp.n());
    std::vector<Triplet> t;
    for (int i = 0; i < qp.J.outerSize(); ++i)
        for (SpMat::InnerIterator it(qp.J, i); it; ++it) t.emplace_back(i, static_cast<int>(it.col()), it.value());
    J.setFromTriplets(t.begin(), t.end());
    qp.J = J;
    qp.c.conservativeResize(qp.J.rows());
    qp.c.tail(2).setConstant(c_value);
    return qp;
}

TEST(Pgs, ZeroRowsKeepZeroMultipliers)
{
    const Qp qp = with_zero_rows(make_grid_qp(GridQpParams{}), -1.0);
    const SolverResult r = run_registered("pgs", qp, {{"tol", 1e-8}});
    ASSERT_EQ(r.status, SolveStatus::CONVERGED) << r.message;
    EXPECT_LE(relative_kkt(qp, r.x, r.lambda), 1e-8);
    EXPECT_EQ(r.lambda.tail(2), Vec::Zero(2));
    EXPECT_EQ(r.info.at("zero_rows"), 2);
}

TEST(Pgs, ZeroRowWithPositiveRightHandSideIsInfeasible)
{
    const Qp qp = with_zero_rows(make_grid_qp(GridQpParams{}), 0.5);
    const SolverResult r = run_registered("pgs", qp, {});
    EXPECT_EQ(r.status, SolveStatus::INFEASIBLE);
    EXPECT_EQ(r.message, "pgs: row " + std::to_string(qp.m() - 2) + " of J is zero but c_" +
                             std::to_string(qp.m() - 2) + " = 0.5 > 0: the constraint 0 >= c_i cannot hold");
}

TEST(Pgs, EmptyJGivesTheUnconstrainedMinimiser)
{
    Qp qp = make_grid_qp(GridQpParams{});
    qp.J = SpMat(0, qp.n());
    qp.c = Vec(0);
    const SolverResult r = run_registered("pgs", qp, {});
    ASSERT_EQ(r.status, SolveStatus::CONVERGED) << r.message;
    const Vec exact = Eigen::SimplicialLDLT<SpMatCol>(SpMatCol(qp.A)).solve(qp.b);
    EXPECT_LT((r.x - exact).lpNorm<Eigen::Infinity>(), 1e-10);
}

TEST(Pgs, SweepCapIsReported)
{
    GridQpParams p;
    p.coupled = true;
    const Qp qp = make_grid_qp(p);
    const SolverResult r = run_registered("pgs", qp, {{"tol", 1e-14}, {"max_iterations", 2}});
    EXPECT_EQ(r.status, SolveStatus::MAX_ITERATIONS);
    EXPECT_EQ(r.iterations, 2);
    EXPECT_EQ(r.criterion, cb::StopCriterion::NONE);
}

}  // namespace
}  // namespace cb

// Seeded synthetic FEM-like families of the io helper: both dual solvers reach the tolerance
// they are given (or say they did not), and `pgs` agrees with the reference in objective.
#include "problems/synthetic.hpp"
#include <iostream>

namespace cb {
namespace {

class SyntheticFamilies : public ::testing::TestWithParam<std::string> {};

TEST_P(SyntheticFamilies, PgsAndIcaMeetTheirToleranceAndAgreeWithActiveSet)
{
    const Qp qp = make_synthetic(GetParam(), nlohmann::json::object(), 7);
    ASSERT_GT(qp.m(), 0);
    const SolverResult ref = run_registered("active-set", qp, {});
    ASSERT_EQ(ref.status, SolveStatus::CONVERGED) << ref.message;
    const double f_ref = objective(qp.view(), ref.x);

    const SolverResult p =
        run_registered("pgs", qp, {{"tol", 1e-10}, {"max_iterations", 200000}, {"time_limit_s", 20}});
    ASSERT_EQ(p.status, SolveStatus::CONVERGED) << p.message;
    EXPECT_LE(relative_kkt(qp, p.x, p.lambda), 1e-10);
    const double gap = relative_gap(objective(qp.view(), p.x), f_ref);
    EXPECT_LT(gap, 1e-8);

    const SolverResult i = run_registered("ica", qp, {{"tol", 1e-6}, {"max_iterations", 200000}, {"time_limit_s", 20}});
    const double kkt_i = relative_kkt(qp, i.x, i.lambda);
    if (i.status == SolveStatus::CONVERGED)
        EXPECT_LE(kkt_i, 1e-6);
    else
        EXPECT_GT(kkt_i, 1e-6) << i.message;  // an honest "not converged"
    std::cout << GetParam() << ": n=" << qp.n() << " m=" << qp.m() << " |F_pgs-F*|/max(1,|F*|)=" << gap
              << " pgs sweeps=" << p.iterations << "; ica " << to_string(i.status) << " accuracy=" << kkt_i
              << " iterations=" << i.iterations
              << " |F_ica-F*|/max(1,|F*|)=" << relative_gap(objective(qp.view(), i.x), f_ref) << "\n";
}

INSTANTIATE_TEST_SUITE_P(Dual, SyntheticFamilies, ::testing::Values("plane", "coupled", "box"));

}  // namespace
}  // namespace cb
