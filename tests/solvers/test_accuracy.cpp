// Tests of the accuracy measure (solvers/measure/accuracy.cpp) on hand-worked QPs: each of the four parts
// with its row norm and stiffness, the length scale and its fallbacks, zero rows, NaN, the energy
// figures and fit_multipliers. Invariances are in test_accuracy_metamorphic.cpp.
#include "solvers/measure/accuracy.hpp"
#include "tests/solvers/tiny_qps.hpp"

#include <gtest/gtest.h>
#include <cmath>
#include <limits>

namespace {

using cb::Qp;
using cb::Vec;
using cb::testing_qps::dense_qp;

/// A = diag(2, 8), J rows (3, 0) and (0, 1): n = (3, 1), k = (2, 8), n/k = (1.5, 0.125).
Qp worked_qp(const Vec& b, const Vec& c, const Vec& x0)
{
    Eigen::MatrixXd A = Eigen::MatrixXd::Zero(2, 2);
    A(0, 0) = 2;
    A(1, 1) = 8;
    Eigen::MatrixXd J = Eigen::MatrixXd::Zero(2, 2);
    J(0, 0) = 3;
    J(1, 1) = 1;
    return dense_qp(A, b, J, c, x0);
}

/// A = 2I, b = (0, b1), J = I, c given.
Qp diag_qp(double b1, const Eigen::Vector2d& c, const Eigen::Vector2d& x0 = Eigen::Vector2d::Zero())
{
    return dense_qp(2.0 * Eigen::MatrixXd::Identity(2, 2), Eigen::Vector2d(0, b1), Eigen::MatrixXd::Identity(2, 2), c,
                    x0);
}

}  // namespace

TEST(Accuracy, ScaleOfTheWorkedQp)
{
    const Qp qp = worked_qp(Eigen::Vector2d(2, 0), Eigen::Vector2d(3, 1), Eigen::Vector2d(0, 2));
    const cb::AccuracyScale s = cb::accuracy_scale(qp.view());
    EXPECT_DOUBLE_EQ(s.inv_diag[0], 0.5);
    EXPECT_DOUBLE_EQ(s.inv_diag[1], 0.125);
    EXPECT_DOUBLE_EQ(s.inv_row_norm[0], 1.0 / 3.0);
    EXPECT_DOUBLE_EQ(s.inv_row_norm[1], 1.0);
    EXPECT_DOUBLE_EQ(s.length_per_multiplier[0], 1.5);
    EXPECT_DOUBLE_EQ(s.length_per_multiplier[1], 0.125);
    EXPECT_DOUBLE_EQ(s.length, 2.0);  // n = 2 is no multiple of 3: the range of x0
    EXPECT_EQ(s.length_source, "x0_range");
    EXPECT_DOUBLE_EQ(s.stiffness, 5.0);  // mean of D
    EXPECT_DOUBLE_EQ(s.inv_energy, 1.0 / 20.0);
    EXPECT_EQ(s.a_products, 0);
    const nlohmann::json j = s.to_json();
    EXPECT_EQ(j["length_scale_source"], "x0_range");
}

// x = (0.5, 1), lambda = (1, -0.5), b = (2, 0), c = (3, 1), l = 2:
//   g = Ax - b = (-1, 8); J'lambda = (3, -0.5); r = (-4, 8.5); D^-1 r = (-2, 1.0625) -> 2 / l = 1
//   Jx - c = (-1.5, 0): row 0 penetrates 1.5 / n0 = 0.5                          -> 0.5 / l = 0.25
//   row 1 pulls: lambda n/k = -0.5 * 0.125 = -0.0625                               -> 0.03125
//   complementarity: row 0 min(1 * 1.5, 0.5) = 0.5, row 1 min(0.0625, 0) = 0     -> 0.25
//   gap: |1 * -1.5| + |-0.5 * 0| = 1.5 over d_ref l^2 = 5 * 4                      -> 0.075
TEST(Accuracy, FivePartsOnHandWorkedPoint)
{
    const Qp qp = worked_qp(Eigen::Vector2d(2, 0), Eigen::Vector2d(3, 1), Eigen::Vector2d(0, 2));
    const cb::AccuracyParts e = cb::accuracy(qp.view(), Eigen::Vector2d(0.5, 1), Eigen::Vector2d(1, -0.5));
    EXPECT_DOUBLE_EQ(e.stationarity, 1.0);
    EXPECT_DOUBLE_EQ(e.primal, 0.25);
    EXPECT_DOUBLE_EQ(e.dual, 0.03125);
    EXPECT_DOUBLE_EQ(e.complementarity, 0.25);
    EXPECT_DOUBLE_EQ(e.gap, 0.075);
    EXPECT_DOUBLE_EQ(e.max(), 1.0);
    const nlohmann::json j = e.to_json();
    EXPECT_DOUBLE_EQ(j["max"].get<double>(), 1.0);
    EXPECT_DOUBLE_EQ(j["dual"].get<double>(), 0.03125);
    EXPECT_DOUBLE_EQ(j["gap"].get<double>(), 0.075);
    // from_gradient gives the same without the A-product
    const cb::AccuracyScale s = cb::accuracy_scale(qp.view());
    const Vec x = Eigen::Vector2d(0.5, 1);
    const Vec g = qp.A * x - qp.b;
    EXPECT_DOUBLE_EQ(cb::accuracy_from_gradient(qp.view(), s, x, g, Eigen::Vector2d(1, -0.5)).complementarity, 0.25);
}

TEST(Accuracy, ZeroAtTheHandSolution)
{
    const Qp qp = cb::testing_qps::tiny_active_qp();
    EXPECT_EQ(cb::accuracy(qp.view(), Eigen::Vector2d(1, 1), Vec::Constant(1, 2.0)).max(), 0.0);
}

// n a multiple of 3: x0 as points (0,0,0), (1,5,0), (2,0,-1): extents 2, 5, 1 -> l = 5.
TEST(Accuracy, LengthScaleIsTheLargestAxisExtentOfTheStart)
{
    Vec x0(9);
    x0 << 0, 0, 0, 1, 5, 0, 2, 0, -1;
    const Qp qp = dense_qp(Eigen::MatrixXd::Identity(9, 9), Vec::Zero(9), Eigen::MatrixXd(0, 9), Vec(0), x0);
    const cb::AccuracyScale s = cb::accuracy_scale(qp.view());
    EXPECT_DOUBLE_EQ(s.length, 5.0);
    EXPECT_EQ(s.length_source, "x0_extent");
    // A rigid move of the start leaves it unchanged (exactly: the shifts are powers of two).
    Vec moved = x0;
    for (int k = 0; k < 3; ++k) {
        moved[3 * k] += 1024.0;
        moved[3 * k + 1] -= 512.0;
        moved[3 * k + 2] += 2048.0;
    }
    const Qp shifted = dense_qp(Eigen::MatrixXd::Identity(9, 9), Vec::Zero(9), Eigen::MatrixXd(0, 9), Vec(0), moved);
    EXPECT_DOUBLE_EQ(cb::accuracy_scale(shifted.view()).length, 5.0);
}

// A degenerate start (range 0) falls back on the extent of the unconstrained minimiser, then on
// the constraint gaps |c_i - J_i x0| / n_i, then on 1.
TEST(Accuracy, LengthScaleFallbacks)
{
    // A diagonal: Jacobi-PCG is exact in one step, x_u = D^-1 b = (3, 0) -> l = 3
    // (A-products: the start residual and one iteration).
    const Qp unconstrained = worked_qp(Eigen::Vector2d(6, 0), Eigen::Vector2d(0, 4), Eigen::Vector2d(1, 1));
    const cb::AccuracyScale s1 = cb::accuracy_scale(unconstrained.view());
    EXPECT_DOUBLE_EQ(s1.length, 3.0);
    EXPECT_EQ(s1.length_source, "unconstrained_extent");
    EXPECT_EQ(s1.a_products, 2);
    // b = A x0: the gaps |0 - 3| / 3 = 1 and |4 - 1| / 1 = 3 -> l = 3.
    const Qp gap = worked_qp(Eigen::Vector2d(2, 8), Eigen::Vector2d(0, 4), Eigen::Vector2d(1, 1));
    const cb::AccuracyScale s2 = cb::accuracy_scale(gap.view());
    EXPECT_DOUBLE_EQ(s2.length, 3.0);
    EXPECT_EQ(s2.length_source, "constraint_gap");
    EXPECT_EQ(s2.a_products, 1);  // the start residual, already 0
    // Every row exactly active at an unconstrained minimiser: nothing to measure a length by.
    const Qp none = worked_qp(Eigen::Vector2d(2, 8), Eigen::Vector2d(3, 1), Eigen::Vector2d(1, 1));
    const cb::AccuracyScale s3 = cb::accuracy_scale(none.view());
    EXPECT_DOUBLE_EQ(s3.length, 1.0);
    EXPECT_EQ(s3.length_source, "unit");
}

// A zero row holds iff c_i <= 0 and exerts no force whatever its multiplier.
TEST(Accuracy, ZeroRows)
{
    const Eigen::MatrixXd J = Eigen::MatrixXd::Zero(1, 2);
    const Qp feasible = dense_qp(2.0 * Eigen::MatrixXd::Identity(2, 2), Eigen::Vector2d(2, 2), J,
                                 Vec::Constant(1, -1.0), Eigen::Vector2d(0, 1));
    EXPECT_EQ(cb::accuracy(feasible.view(), Eigen::Vector2d(1, 1), Vec::Constant(1, -5.0)).max(), 0.0);
    const Qp infeasible = dense_qp(2.0 * Eigen::MatrixXd::Identity(2, 2), Eigen::Vector2d(2, 2), J,
                                   Vec::Constant(1, 1.0), Eigen::Vector2d(0, 1));
    const cb::AccuracyParts bad = cb::accuracy(infeasible.view(), Eigen::Vector2d(1, 1), Vec::Constant(1, 0.0));
    EXPECT_TRUE(std::isinf(bad.primal));
    EXPECT_EQ(bad.to_json()["primal"], nullptr);
}

// Without multipliers (wrong size) stationarity uses g alone; dual and complementarity are 0.
TEST(Accuracy, MissingLambdaMeansGradientOnly)
{
    const Qp qp = worked_qp(Eigen::Vector2d(2, 0), Eigen::Vector2d(3, 1), Eigen::Vector2d(0, 2));
    const cb::AccuracyParts e = cb::accuracy(qp.view(), Eigen::Vector2d(0.5, 1), Vec(0));
    EXPECT_DOUBLE_EQ(e.stationarity, 0.5);  // D^-1 g = (-0.5, 1) -> 1 / l
    EXPECT_DOUBLE_EQ(e.primal, 0.25);
    EXPECT_EQ(e.dual, 0.0);
    EXPECT_EQ(e.complementarity, 0.0);
    EXPECT_EQ(e.gap, 0.0);
}

TEST(Accuracy, NonFiniteReadsAsInfinity)
{
    const Qp qp = worked_qp(Eigen::Vector2d(2, 0), Eigen::Vector2d(3, 1), Eigen::Vector2d(0, 2));
    const double nan = std::numeric_limits<double>::quiet_NaN();
    EXPECT_TRUE(std::isinf(cb::accuracy(qp.view(), Eigen::Vector2d(nan, 1), Eigen::Vector2d(1, 0)).max()));
    const cb::AccuracyParts e = cb::accuracy(qp.view(), Eigen::Vector2d(1, 1), Eigen::Vector2d(nan, 0));
    EXPECT_TRUE(std::isinf(e.stationarity));
    EXPECT_TRUE(std::isinf(e.complementarity));
}

// Energy figures: |F - F*| / (d_ref l^2) with d_ref = 5, l = 2; |x - x*|_A / (sqrt(d_ref) l).
TEST(Accuracy, EnergyGapAndANormDistance)
{
    const Qp qp = worked_qp(Eigen::Vector2d(2, 0), Eigen::Vector2d(3, 1), Eigen::Vector2d(0, 2));
    const cb::AccuracyScale s = cb::accuracy_scale(qp.view());
    EXPECT_DOUBLE_EQ(cb::energy_gap(s, -1.0, -3.0), 0.1);
    EXPECT_TRUE(std::isnan(cb::energy_gap(s, std::numeric_limits<double>::infinity(), 0.0)));
    // x - x* = (1, 0.5): |.|_A^2 = 2 + 2 = 4 -> 2 / (sqrt(5) * 2)
    EXPECT_DOUBLE_EQ(cb::a_norm_distance(qp.view(), s, Eigen::Vector2d(1, 1.5), Eigen::Vector2d(0, 1)),
                     1.0 / std::sqrt(5.0));
}

// STYLE example at x* = (1,1): g = (2, 0), one active row -> lambda = J g / |J|^2 = 2.
TEST(Accuracy, FitMultipliersOnActiveRow)
{
    const Qp qp = cb::testing_qps::tiny_active_qp();
    const Vec x = Eigen::Vector2d(1, 1);
    const Vec lambda = cb::fit_multipliers(qp.view(), cb::accuracy_scale(qp.view()), x, qp.A * x - qp.b);
    ASSERT_EQ(lambda.size(), 1);
    EXPECT_NEAR(lambda[0], 2.0, 1e-10);
}

// An inactive row gets exactly 0; the active one is fitted.
TEST(Accuracy, FitMultipliersInactiveRowIsZero)
{
    const Qp qp = diag_qp(2.0, Eigen::Vector2d(1, 0.5));
    const Vec x = Eigen::Vector2d(1, 1);  // row 0 active (slack 0), row 1 slack 0.5
    const Vec lambda = cb::fit_multipliers(qp.view(), cb::accuracy_scale(qp.view()), x, qp.A * x - qp.b);
    EXPECT_NEAR(lambda[0], 2.0, 1e-10);
    EXPECT_EQ(lambda[1], 0.0);
}

// Duplicated active rows: the fit splits the multiplier, stationarity stays exact.
TEST(Accuracy, FitMultipliersSplitsDependentRows)
{
    Eigen::MatrixXd J(3, 2);
    J << 1, 0, 1, 0, 2, 0;
    const Qp qp = dense_qp(2.0 * Eigen::MatrixXd::Identity(2, 2), Eigen::Vector2d(0, 2), J, Eigen::Vector3d(1, 1, 2),
                           Vec::Zero(2));
    const Vec x = Eigen::Vector2d(1, 1);
    const Vec g = qp.A * x - qp.b;
    const Vec lambda = cb::fit_multipliers(qp.view(), cb::accuracy_scale(qp.view()), x, g);
    EXPECT_LE((g - qp.J.transpose() * lambda).lpNorm<Eigen::Infinity>(), 1e-9);
    // Close to the least-norm split of 2 = l0 + l1 + 2 l2, (1/3, 1/3, 2/3) (the Tikhonov term
    // fixes the null-space component to about eps * cond).
    EXPECT_NEAR(lambda[0], 1.0 / 3.0, 1e-3);
    EXPECT_NEAR(lambda[1], 1.0 / 3.0, 1e-3);
    EXPECT_NEAR(lambda[2], 2.0 / 3.0, 1e-3);
}

// The thresholds are lengths relative to l (= 1.5 here: x0 = 0 falls back on x_u = (0, 1.5)),
// A row off its face by 1e-8 (inside 1e-6 l, outside 1e-9 l) whose fitted multiplier would be
// negative is dropped; an exactly active one keeps its honest negative multiplier.
TEST(Accuracy, FitMultipliersDropsNearActiveNegativeRows)
{
    const Vec x = Eigen::Vector2d(1, 1);
    {
        const Qp qp = diag_qp(3.0, Eigen::Vector2d(1, 1 - 1e-8));
        EXPECT_DOUBLE_EQ(cb::accuracy_scale(qp.view()).length, 1.5);
        const Vec lambda = cb::fit_multipliers(qp.view(), cb::accuracy_scale(qp.view()), x, qp.A * x - qp.b);
        EXPECT_NEAR(lambda[0], 2.0, 1e-10);
        EXPECT_EQ(lambda[1], 0.0);
    }
    {
        const Qp qp = diag_qp(3.0, Eigen::Vector2d(1, 1));
        const Vec lambda = cb::fit_multipliers(qp.view(), cb::accuracy_scale(qp.view()), x, qp.A * x - qp.b);
        EXPECT_NEAR(lambda[0], 2.0, 1e-10);
        EXPECT_NEAR(lambda[1], -1.0, 1e-10);
    }
}

TEST(Accuracy, MaxViolationAndActiveTolerance)
{
    const Qp qp = diag_qp(2.0, Eigen::Vector2d(1, 0.5));
    EXPECT_DOUBLE_EQ(cb::max_violation(qp.view(), Eigen::Vector2d(0.25, 1)), 0.75);
    EXPECT_EQ(cb::max_violation(qp.view(), Eigen::Vector2d(2, 1)), 0.0);
    EXPECT_EQ(cb::active_tolerance(0.5), 1e-9);
    EXPECT_DOUBLE_EQ(cb::active_tolerance(-1e3), 1e-6);
    const Qp free = cb::testing_qps::unconstrained_qp();
    EXPECT_EQ(cb::max_violation(free.view(), Vec::Zero(3)), 0.0);
    EXPECT_EQ(cb::fit_multipliers(free.view(), cb::accuracy_scale(free.view()), Vec::Zero(3), Vec::Zero(3)).size(), 0);
}
