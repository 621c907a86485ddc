// Tests of the reference solver `active-set` (Goldfarb-Idnani on CHOLMOD): hand-derived
// solutions, degenerate and infeasible sets, agreement with cg and with a brute-force
// enumeration of active sets, and the synthetic families at 1e-10 relative KKT.
#include "problems/synthetic.hpp"
#include "solvers/measure/accuracy.hpp"
#include "solvers/methods/active_set.hpp"
#include "solvers/methods/cg.hpp"
#include "tests/solvers/tiny_qps.hpp"

#include <Eigen/Dense>
#include <gtest/gtest.h>
#include <cctype>
#include <iostream>
#include <random>

namespace {

using cb::Qp;
using cb::SolverResult;
using cb::SolveStatus;
using cb::Vec;
using cb::testing_qps::dense_qp;

SolverResult run_active_set(const Qp& qp, const nlohmann::json& settings = nlohmann::json::object())
{
    cb::ActiveSetSolver solver(cb::ActiveSetSettings::from_json(settings));
    return solver.solve(qp.view(), cb::SolveContext{});
}

double relative_kkt_of_result(const Qp& qp, const SolverResult& r)
{
    return cb::accuracy(qp.view(), r.x, r.lambda).max();
}

/// Checks the multiplier sign and the exact zero on clearly inactive rows.
void expect_multipliers_clean(const Qp& qp, const SolverResult& r)
{
    const Vec slack = qp.J * r.x - qp.c;
    for (Eigen::Index i = 0; i < qp.m(); ++i) {
        EXPECT_GE(r.lambda[i], 0.0) << "row " << i;
        if (slack[i] > 1e-6 * std::max(1.0, std::abs(qp.c[i]))) {
            EXPECT_EQ(r.lambda[i], 0.0) << "inactive row " << i;
        }
    }
}

Eigen::MatrixXd row(std::initializer_list<double> values)
{
    Eigen::MatrixXd r(1, static_cast<Eigen::Index>(values.size()));
    Eigen::Index k = 0;
    for (double v : values) r(0, k++) = v;
    return r;
}

}  // namespace

// 1-D: min 2 x^2 - 2 x s.t. x >= 1. Unconstrained 0.5 violates, so x* = 1, lambda* = 4 - 2 = 2.
TEST(ActiveSet, OneDimensionalActiveRow)
{
    const Qp qp = dense_qp(Eigen::MatrixXd::Constant(1, 1, 4.0), Vec::Constant(1, 2.0), row({1.0}),
                           Vec::Constant(1, 1.0), Vec::Zero(1));
    const SolverResult r = run_active_set(qp);
    ASSERT_EQ(r.status, SolveStatus::CONVERGED) << r.message;
    EXPECT_EQ(r.criterion, cb::StopCriterion::ACCURACY);
    EXPECT_NEAR(r.x[0], 1.0, 1e-14);
    EXPECT_NEAR(r.lambda[0], 2.0, 1e-13);
    EXPECT_EQ(r.info["working_set"], 1);
    EXPECT_EQ(r.counters.cholmod_factorizations, 1);
    EXPECT_EQ(r.counters.cholmod_analyses, 1);
}

// Same with c = 0: the row is inactive, x* = 0.5 and lambda is exactly 0.
TEST(ActiveSet, OneDimensionalInactiveRowHasZeroMultiplier)
{
    const Qp qp = dense_qp(Eigen::MatrixXd::Constant(1, 1, 4.0), Vec::Constant(1, 2.0), row({1.0}),
                           Vec::Constant(1, 0.0), Vec::Zero(1));
    const SolverResult r = run_active_set(qp);
    ASSERT_EQ(r.status, SolveStatus::CONVERGED) << r.message;
    EXPECT_NEAR(r.x[0], 0.5, 1e-15);
    EXPECT_EQ(r.lambda[0], 0.0);
    EXPECT_EQ(r.info["working_set"], 0);
}

TEST(ActiveSet, StyleGuideExample)
{
    const Qp qp = cb::testing_qps::tiny_active_qp();
    const SolverResult r = run_active_set(qp);
    ASSERT_EQ(r.status, SolveStatus::CONVERGED) << r.message;
    EXPECT_NEAR(r.x[0], 1.0, 1e-14);
    EXPECT_NEAR(r.x[1], 1.0, 1e-14);
    EXPECT_NEAR(r.lambda[0], 2.0, 1e-13);
}

// 2-D, A = [[2,1],[1,2]], b = 0, x0 >= 1, x1 >= 1: x* = (1,1), lambda* = A x* = (3,3).
TEST(ActiveSet, TwoDimensionalTwoActiveRows)
{
    const Qp qp = cb::testing_qps::two_row_coupled_qp();
    const SolverResult r = run_active_set(qp);
    ASSERT_EQ(r.status, SolveStatus::CONVERGED) << r.message;
    EXPECT_NEAR(r.x[0], 1.0, 1e-14);
    EXPECT_NEAR(r.x[1], 1.0, 1e-14);
    EXPECT_NEAR(r.lambda[0], 3.0, 1e-13);
    EXPECT_NEAR(r.lambda[1], 3.0, 1e-13);
    EXPECT_EQ(r.info["working_set"], 2);
}

// A degenerate vertex: x0 >= 1, x1 >= 1, x0 + x1 >= 2 and x0 + 2 x1 >= 3 all pass through (1,1),
// with b chosen so the unconstrained minimiser (-1,-1) violates all four. x* = (1,1);
// the multipliers are not unique, but must be >= 0 with J' lambda = A x* = (3,3).
TEST(ActiveSet, DegenerateVertex)
{
    Eigen::MatrixXd A(2, 2);
    A << 2, 1, 1, 2;
    Eigen::MatrixXd J(4, 2);
    J << 1, 0, 0, 1, 1, 1, 1, 2;
    const Qp qp = dense_qp(A, Eigen::Vector2d(-3, -3), J, Eigen::Vector4d(1, 1, 2, 3), Vec::Zero(2));
    const SolverResult r = run_active_set(qp);
    ASSERT_EQ(r.status, SolveStatus::CONVERGED) << r.message;
    EXPECT_NEAR(r.x[0], 1.0, 1e-13);
    EXPECT_NEAR(r.x[1], 1.0, 1e-13);
    const Vec JtL = qp.J.transpose() * r.lambda;
    EXPECT_NEAR(JtL[0], 0.0 + 2 + 1 + 3, 1e-12);  // A x* - b = (3,3) + (3,3)
    EXPECT_NEAR(JtL[1], 6.0, 1e-12);
    EXPECT_GE(r.lambda.minCoeff(), 0.0);
    EXPECT_LE(relative_kkt_of_result(qp, r), 1e-12);
    EXPECT_LE(r.info["working_set"].get<long>(), 2);  // at most 2 independent rows in 2-D
}

// Duplicated rows (3 copies) and a zero row with c <= 0 change nothing: x* = (1,1), total lambda 2.
TEST(ActiveSet, DuplicateRowsAndFeasibleZeroRow)
{
    Eigen::MatrixXd J(4, 2);
    J << 1, 0, 1, 0, 0, 0, 1, 0;
    const Qp qp = dense_qp(2.0 * Eigen::MatrixXd::Identity(2, 2), Eigen::Vector2d(0, 2), J,
                           Eigen::Vector4d(1, 1, -0.5, 1), Vec::Zero(2));
    const SolverResult r = run_active_set(qp);
    ASSERT_EQ(r.status, SolveStatus::CONVERGED) << r.message;
    EXPECT_NEAR(r.x[0], 1.0, 1e-14);
    EXPECT_NEAR(r.x[1], 1.0, 1e-14);
    EXPECT_NEAR(r.lambda.sum(), 2.0, 1e-13);
    EXPECT_EQ(r.lambda[2], 0.0);
    EXPECT_GE(r.lambda.minCoeff(), 0.0);
    EXPECT_EQ(r.info["zero_rows"], 1);
}

TEST(ActiveSet, ZeroRowWithPositiveCIsInfeasible)
{
    Eigen::MatrixXd J(2, 2);
    J << 1, 0, 0, 0;
    const Qp qp = dense_qp(2.0 * Eigen::MatrixXd::Identity(2, 2), Eigen::Vector2d(0, 2), J, Eigen::Vector2d(1, 0.5),
                           Vec::Zero(2));
    const SolverResult r = run_active_set(qp);
    EXPECT_EQ(r.status, SolveStatus::INFEASIBLE);
    EXPECT_EQ(r.message, "active-set: infeasible: row 1 of J is zero and c = 0.5 > 0");
}

// x0 >= 1 and -x0 >= 0 cannot both hold.
TEST(ActiveSet, ContradictoryRowsAreInfeasible)
{
    Eigen::MatrixXd J(2, 2);
    J << 1, 0, -1, 0;
    const Qp qp =
        dense_qp(2.0 * Eigen::MatrixXd::Identity(2, 2), Eigen::Vector2d(0, 2), J, Eigen::Vector2d(1, 0), Vec::Zero(2));
    const SolverResult r = run_active_set(qp);
    EXPECT_EQ(r.status, SolveStatus::INFEASIBLE);
    EXPECT_NE(r.message.find("infeasible"), std::string::npos) << r.message;
}

TEST(ActiveSet, IndefiniteAIsInvalidInput)
{
    Eigen::MatrixXd A(2, 2);
    A << 1, 2, 2, 1;  // eigenvalues 3, -1
    const Qp qp = dense_qp(A, Eigen::Vector2d(0, 1), row({1.0, 0.0}), Vec::Constant(1, 1.0), Vec::Zero(2));
    const SolverResult r = run_active_set(qp);
    EXPECT_EQ(r.status, SolveStatus::INVALID_INPUT);
    EXPECT_EQ(r.message, "active-set: A is not positive definite (CHOLMOD Cholesky factorization failed)");
}

TEST(ActiveSet, UnknownSettingIsRejected)
{
    EXPECT_THROW(cb::ActiveSetSettings::from_json({{"gamma", 1.0}}), cb::InputError);
    EXPECT_EQ(cb::ActiveSetSettings::from_json(nlohmann::json::object()).common.tol, 1e-10);
    EXPECT_EQ(cb::ActiveSetSettings::from_json({{"tol", 1e-6}}).common.tol, 1e-6);
}

TEST(ActiveSet, GrowingCholeskyMatchesRecomputedFactor)
{
    std::mt19937 rng(7);
    std::normal_distribution<double> normal;
    const int q = 9;
    Eigen::MatrixXd B(q, q + 3);
    for (int i = 0; i < B.rows(); ++i)
        for (int j = 0; j < B.cols(); ++j) B(i, j) = normal(rng);
    const Eigen::MatrixXd S = B * B.transpose();
    cb::GrowingCholesky chol;
    for (int k = 0; k < q; ++k) {
        const Vec l = chol.forward(S.col(k).head(k));
        chol.append(l, S(k, k) - l.squaredNorm());
    }
    std::vector<int> kept(q);
    for (int k = 0; k < q; ++k) kept[k] = k;
    for (int remove : {4, 0, 6, 2}) {  // positions in the current factor
        chol.remove(remove);
        kept.erase(kept.begin() + remove);
        Eigen::MatrixXd Sk(kept.size(), kept.size());
        for (size_t a = 0; a < kept.size(); ++a)
            for (size_t b = 0; b < kept.size(); ++b) Sk(a, b) = S(kept[a], kept[b]);
        const Eigen::MatrixXd& L = chol.factor();
        EXPECT_LE((L * L.transpose() - Sk).norm(), 1e-12 * Sk.norm());
        EXPECT_TRUE(L.isLowerTriangular(0.0));
        EXPECT_GT(L.diagonal().minCoeff(), 0.0);
        const Vec d = Vec::LinSpaced(kept.size(), 1.0, 2.0);
        EXPECT_LE((Sk * chol.solve(d) - d).norm(), 1e-10);
    }
}

// Dense reference: enumerate every subset of rows, solve its equality QP, keep the primal
// feasible solution of least objective (the optimum is one of them).
double brute_force_objective(const Qp& qp, Vec* x_best)
{
    const Eigen::MatrixXd A = Eigen::MatrixXd(qp.A);
    const Eigen::MatrixXd J = Eigen::MatrixXd(qp.J);
    const int m = static_cast<int>(qp.m()), n = static_cast<int>(qp.n());
    double best = std::numeric_limits<double>::infinity();
    for (long mask = 0; mask < (1L << m); ++mask) {
        std::vector<int> rows;
        for (int i = 0; i < m; ++i)
            if (mask & (1L << i)) rows.push_back(i);
        const int q = static_cast<int>(rows.size());
        Eigen::MatrixXd K = Eigen::MatrixXd::Zero(n + q, n + q);
        Vec rhs(n + q);
        K.topLeftCorner(n, n) = A;
        rhs.head(n) = qp.b;
        for (int a = 0; a < q; ++a) {
            K.block(n + a, 0, 1, n) = J.row(rows[a]);
            K.block(0, n + a, n, 1) = J.row(rows[a]).transpose();
            rhs[n + a] = qp.c[rows[a]];
        }
        Eigen::FullPivLU<Eigen::MatrixXd> lu(K);
        if (!lu.isInvertible()) continue;
        const Vec x = lu.solve(rhs).head(n);
        if ((J * x - qp.c).minCoeff() < -1e-9) continue;
        const double f = cb::objective(qp.view(), x);
        if (f < best) {
            best = f;
            if (x_best) *x_best = x;
        }
    }
    return best;
}

TEST(ActiveSet, MatchesEnumerationOfActiveSetsOnRandomDenseQps)
{
    std::mt19937 rng(11);
    std::normal_distribution<double> normal;
    for (int trial = 0; trial < 6; ++trial) {
        const int n = 5, m = 8;
        Eigen::MatrixXd B(n, n);
        for (int i = 0; i < n; ++i)
            for (int j = 0; j < n; ++j) B(i, j) = normal(rng);
        const Eigen::MatrixXd A = B * B.transpose() + 0.5 * Eigen::MatrixXd::Identity(n, n);
        Vec b(n), c(m);
        Eigen::MatrixXd J(m, n);
        for (int i = 0; i < n; ++i) b[i] = normal(rng);
        for (int i = 0; i < m; ++i) {
            c[i] = normal(rng);
            for (int j = 0; j < n; ++j) J(i, j) = normal(rng);
        }
        const Qp qp = dense_qp(A, b, J, c, Vec::Zero(n));
        Vec x_ref;
        const double f_ref = brute_force_objective(qp, &x_ref);
        const SolverResult r = run_active_set(qp);
        if (!std::isfinite(f_ref)) {
            EXPECT_EQ(r.status, SolveStatus::INFEASIBLE) << "trial " << trial;
            continue;
        }
        ASSERT_EQ(r.status, SolveStatus::CONVERGED) << "trial " << trial << ": " << r.message;
        EXPECT_NEAR(cb::objective(qp.view(), r.x), f_ref, 1e-10 * std::max(1.0, std::abs(f_ref)));
        EXPECT_LE((r.x - x_ref).lpNorm<Eigen::Infinity>(), 1e-8) << "trial " << trial;
        EXPECT_LE(relative_kkt_of_result(qp, r), 1e-10);
        expect_multipliers_clean(qp, r);
    }
}

TEST(ActiveSet, MatchesEnumerationOnSmallSyntheticBox)
{
    for (std::uint64_t seed : {1u, 2u, 3u}) {
        const Qp qp = cb::make_synthetic("box", {{"nx", 1}, {"ny", 1}, {"nz", 1}, {"fraction", 0.35}}, seed);
        ASSERT_GT(qp.m(), 2);
        ASSERT_LE(qp.m(), 14);
        Vec x_ref;
        const double f_ref = brute_force_objective(qp, &x_ref);
        const SolverResult r = run_active_set(qp);
        ASSERT_EQ(r.status, SolveStatus::CONVERGED) << r.message;
        EXPECT_NEAR(cb::objective(qp.view(), r.x), f_ref, 1e-10 * std::max(1.0, std::abs(f_ref)));
        EXPECT_LE((r.x - x_ref).lpNorm<Eigen::Infinity>(), 1e-8 * std::max(1.0, x_ref.lpNorm<Eigen::Infinity>()));
        expect_multipliers_clean(qp, r);
    }
}

TEST(ActiveSet, AgreesWithCgOnUnconstrainedProblems)
{
    const Qp hand = cb::testing_qps::unconstrained_qp();
    const SolverResult h = run_active_set(hand);
    ASSERT_EQ(h.status, SolveStatus::CONVERGED) << h.message;
    EXPECT_LE((h.x - cb::testing_qps::unconstrained_x()).lpNorm<Eigen::Infinity>(), 1e-14);
    EXPECT_EQ(h.lambda.size(), 0);

    const Qp qp = cb::make_synthetic("unconstrained", {{"nx", 3}, {"ny", 3}, {"nz", 3}}, 5);
    const SolverResult a = run_active_set(qp);
    ASSERT_EQ(a.status, SolveStatus::CONVERGED) << a.message;
    cb::CgSolver cg(cb::CgSettings::from_json({{"tol", 1e-12}, {"max_iterations", 5000}}));
    const SolverResult c = cg.solve(qp.view(), cb::SolveContext{});
    ASSERT_EQ(c.status, SolveStatus::CONVERGED) << c.message;
    EXPECT_LE((a.x - c.x).lpNorm<Eigen::Infinity>(), 1e-8 * std::max(1.0, a.x.lpNorm<Eigen::Infinity>()));
}

struct FamilyCase {
    const char* family;
    const char* params;
};
/// ctest names an instance by its printed parameter: the case's name, not its bytes (pointers that
/// moved from build to build).
// NOLINTNEXTLINE(readability-identifier-naming): GoogleTest looks up this name
void PrintTo(const FamilyCase& c, std::ostream* os)
{
    std::string name = std::string(c.family) + c.params;
    for (char& ch : name)
        if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
    *os << name;
}

class ActiveSetFamilies : public ::testing::TestWithParam<FamilyCase> {};

TEST_P(ActiveSetFamilies, ReachesRelativeKkt1e10)
{
    const FamilyCase fc = GetParam();
    for (std::uint64_t seed : {1u, 2u}) {
        const Qp qp = cb::make_synthetic(fc.family, nlohmann::json::parse(fc.params), seed);
        ASSERT_GT(qp.m(), 0);
        const SolverResult r = run_active_set(qp);
        ASSERT_EQ(r.status, SolveStatus::CONVERGED) << fc.family << " seed " << seed << ": " << r.message;
        EXPECT_LE(relative_kkt_of_result(qp, r), 1e-10) << fc.family << " seed " << seed;
        EXPECT_LE(cb::max_violation(qp.view(), r.x), 1e-10 * std::max(1.0, qp.c.lpNorm<Eigen::Infinity>()));
        expect_multipliers_clean(qp, r);
        EXPECT_GT(r.info["working_set"].get<long>(), 0);
        // Feasible x0 projected... the constrained optimum is never below the unconstrained one.
        const Vec x_unc = Eigen::MatrixXd(qp.A).ldlt().solve(qp.b);
        EXPECT_GE(cb::objective(qp.view(), r.x), cb::objective(qp.view(), x_unc) - 1e-12);
    }
}

INSTANTIATE_TEST_SUITE_P(
    Synthetic, ActiveSetFamilies,
    ::testing::Values(FamilyCase{"plane", R"({"nx": 3, "ny": 2, "nz": 3})"},
                      FamilyCase{"plane", R"({"nx": 3, "ny": 2, "nz": 3, "tilt_deg": 20})"},
                      FamilyCase{"coupled", R"({"nx": 3, "ny": 2, "nz": 3})"},
                      FamilyCase{"box", R"({"nx": 2, "ny": 2, "nz": 2})"},
                      FamilyCase{"duplicate-rows", R"({"nx": 3, "ny": 2, "nz": 3})"},
                      FamilyCase{"scaled-rows", R"({"nx": 3, "ny": 2, "nz": 3})"},
                      FamilyCase{"zero-rows", R"({"nx": 3, "ny": 2, "nz": 3})"},
                      FamilyCase{"random-spd", R"({"n": 60, "m": 40})"},
                      FamilyCase{"plane", R"({"nx": 3, "ny": 2, "nz": 3, "youngs": 1e10})"},
                      FamilyCase{"plane", R"({"nx": 3, "ny": 2, "nz": 3, "length_scale": 1e-3})"},
                      FamilyCase{"plane", R"({"nx": 3, "ny": 2, "nz": 3, "length_scale": 1e3, "mass_scale": 1e3})"}),
    [](const auto& info) {
        std::string name = info.param.family;
        for (char& ch : name)
            if (ch == '-') ch = '_';
        return name + "_" + std::to_string(info.index);
    });

TEST(ActiveSet, InfeasibleFamilyIsReportedInfeasible)
{
    const Qp qp = cb::make_synthetic("infeasible", {{"nx", 2}, {"ny", 2}, {"nz", 2}}, 3);
    const SolverResult r = run_active_set(qp);
    EXPECT_EQ(r.status, SolveStatus::INFEASIBLE) << r.message;
    EXPECT_EQ(r.criterion, cb::StopCriterion::NONE);
}

TEST(ActiveSet, IterationCapIsNotConverged)
{
    const Qp qp = cb::make_synthetic("plane", {{"nx", 3}, {"ny", 2}, {"nz", 3}}, 1);
    const SolverResult r = run_active_set(qp, {{"max_iterations", 1}});
    EXPECT_EQ(r.status, SolveStatus::MAX_ITERATIONS) << r.message;
    EXPECT_EQ(r.iterations, 1);
    EXPECT_GT(cb::max_violation(qp.view(), r.x), 0.0);
}

// A working set of ~2000 rows still works (more slowly): bounds on most DOFs of a small grid.
TEST(ActiveSet, HandlesTwoThousandRows)
{
    const Qp qp = cb::make_synthetic("box", {{"nx", 8}, {"ny", 8}, {"nz", 8}, {"fraction", 0.9}}, 4);
    ASSERT_GT(qp.m(), 1500);
    const SolverResult r = run_active_set(qp);
    ASSERT_EQ(r.status, SolveStatus::CONVERGED) << r.message;
    EXPECT_LE(relative_kkt_of_result(qp, r), 1e-10);
    expect_multipliers_clean(qp, r);
    std::cout << "m = " << qp.m() << ", n = " << qp.n() << ": setup " << r.setup_s << " s, solve " << r.solve_s
              << " s, info " << r.info.dump() << "\n";
}

// A = I, b = (0, -10); rows x0 >= 1, x1 >= 1, x0 + 2 x1 >= 3.5. GI adds x1 >= 1, then x0 >= 1,
// reaching (1, 1) with a full working set; the third row is then violated and lies in the span
// of the two (n_2 = n_0 + 2 n_1): a pure dual step drops x0 >= 1 before the third row enters.
// x* = (1.5, 1): x* - b = (1.5, 11) = 8 (0, 1) + 1.5 (1, 2)  ->  lambda* = (0, 8, 1.5).
TEST(ActiveSet, DependentRowTakesADualStep)
{
    Eigen::MatrixXd J(3, 2);
    J << 1, 0, 0, 1, 1, 2;
    const Qp qp =
        dense_qp(Eigen::MatrixXd::Identity(2, 2), Eigen::Vector2d(0, -10), J, Eigen::Vector3d(1, 1, 3.5), Vec::Zero(2));
    const SolverResult r = run_active_set(qp);
    ASSERT_EQ(r.status, SolveStatus::CONVERGED) << r.message;
    EXPECT_NEAR(r.x[0], 1.5, 1e-14);
    EXPECT_NEAR(r.x[1], 1.0, 1e-14);
    EXPECT_EQ(r.lambda[0], 0.0);
    EXPECT_NEAR(r.lambda[1], 8.0, 1e-13);
    EXPECT_NEAR(r.lambda[2], 1.5, 1e-13);
    EXPECT_EQ(r.info["dependent_steps"], 1);
    EXPECT_EQ(r.info["rows_added"], 3);
    EXPECT_EQ(r.info["rows_dropped"], 1);
    EXPECT_EQ(r.counters.pivots, 4);
}

TEST(ActiveSet, TimeLimitIsHonoured)
{
    const Qp qp = cb::make_synthetic("plane", {{"nx", 3}, {"ny", 2}, {"nz", 3}}, 1);
    const SolverResult r = run_active_set(qp, {{"time_limit_s", 1e-12}});
    EXPECT_EQ(r.status, SolveStatus::TIME_LIMIT) << r.message;
    EXPECT_EQ(r.criterion, cb::StopCriterion::NONE);
}

namespace {
struct PivotMonitor : cb::Monitor {
    std::vector<cb::StepKind> steps;
    std::vector<long> active;
    Vec last_x;
    double last_native = 0.0;
    bool on_iteration(const cb::IterationInfo& info) override
    {
        steps.push_back(info.step);
        active.push_back(info.active_set_size);
        last_x = *info.x;
        last_native = info.native_residual;
        return true;
    }
};
}  // namespace

TEST(ActiveSet, MonitorSeesEveryPivot)
{
    const Qp qp = cb::testing_qps::two_row_coupled_qp();
    PivotMonitor monitor;
    cb::ActiveSetSolver solver(cb::ActiveSetSettings::from_json(nlohmann::json::object()));
    cb::SolveContext context;
    context.monitor = &monitor;
    const SolverResult r = solver.solve(qp.view(), context);
    ASSERT_EQ(r.status, SolveStatus::CONVERGED) << r.message;
    // start, two pivots (one row each), final
    ASSERT_EQ(monitor.steps.size(), 4u);
    EXPECT_EQ(monitor.steps[0], cb::StepKind::START);
    EXPECT_EQ(monitor.steps[1], cb::StepKind::PIVOT);
    EXPECT_EQ(monitor.steps[3], cb::StepKind::FINAL);
    EXPECT_EQ(monitor.active[0], 0);
    EXPECT_EQ(monitor.active[1], 1);
    EXPECT_EQ(monitor.active[2], 2);
    // The final call shows the returned (polished) point itself, so a history's last row is it.
    EXPECT_TRUE(monitor.last_x == r.x);
    EXPECT_EQ(monitor.last_native, r.native_residual);
}
