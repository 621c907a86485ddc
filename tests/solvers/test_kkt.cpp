// Tests of the common KKT metric (solvers/kkt.cpp) on hand-worked QPs: each of the four parts,
// the scalings s, s_c and max(1, |lambda|), the relative reference, fit_multipliers and NaN.
#include "solvers/kkt.hpp"
#include "tests/solvers/tiny_qps.hpp"

#include <gtest/gtest.h>
#include <cmath>
#include <limits>

namespace {

using cb::Qp;
using cb::Vec;
using cb::testing_qps::dense_qp;

/// A = 2I, b = (0, b1), J = I, c given.
Qp diag_qp(double b1, const Eigen::Vector2d& c, const Eigen::Vector2d& x0 = Eigen::Vector2d::Zero())
{
    return dense_qp(2.0 * Eigen::MatrixXd::Identity(2, 2), Eigen::Vector2d(0, b1), Eigen::MatrixXd::Identity(2, 2),
                    c, x0);
}

} // namespace

// x = (0.5, 1), lambda = (1, -0.25), b = (0, 2), c = (1, 0.5):
//   g = Ax - b = (1, 0); g - J'lambda = (0, 0.25)         -> stationarity 0.25 / s(=2) = 0.125
//   Jx - c = (-0.5, 0.5); max(0, c - Jx) = 0.5            -> primal 0.5 / s_c(=1) = 0.5
//   max(0, -lambda) = 0.25, |lambda|_inf = 1              -> dual 0.25
//   |lambda_i (Jx - c)_i| = (0.5, 0.125)                  -> complementarity 0.5 / 2 = 0.25
TEST(Kkt, FourPartsOnHandWorkedPoint)
{
    const Qp qp = diag_qp(2.0, Eigen::Vector2d(1, 0.5));
    const cb::KktResiduals k = cb::kkt_residuals(qp.view(), Eigen::Vector2d(0.5, 1), Eigen::Vector2d(1, -0.25));
    EXPECT_DOUBLE_EQ(k.stationarity, 0.125);
    EXPECT_DOUBLE_EQ(k.primal, 0.5);
    EXPECT_DOUBLE_EQ(k.dual, 0.25);
    EXPECT_DOUBLE_EQ(k.complementarity, 0.25);
    EXPECT_DOUBLE_EQ(k.max(), 0.5);
    const nlohmann::json j = k.to_json();
    EXPECT_DOUBLE_EQ(j["max"].get<double>(), 0.5);
    EXPECT_DOUBLE_EQ(j["stationarity"].get<double>(), 0.125);
    EXPECT_DOUBLE_EQ(k.scaled(2.0).dual, 0.5);
}

// The same point with b = (0, 4), c = (3, 0.5), lambda = (4, -1) exercises every scale:
//   g = (1, -2); g - J'lambda = (-3, -1)                  -> 3 / s(=4) = 0.75
//   Jx - c = (-2.5, 0.5)                                  -> primal 2.5 / s_c(=3)
//   max(0, -lambda) = 1, |lambda|_inf = 4                 -> dual 0.25
//   |lambda_i (Jx - c)_i| = (10, 0.5)                     -> complementarity 10 / 4 = 2.5
TEST(Kkt, ScalesByBAndCAndLambda)
{
    const Qp qp = diag_qp(4.0, Eigen::Vector2d(3, 0.5));
    const cb::KktResiduals k = cb::kkt_residuals(qp.view(), Eigen::Vector2d(0.5, 1), Eigen::Vector2d(4, -1));
    EXPECT_DOUBLE_EQ(k.stationarity, 0.75);
    EXPECT_DOUBLE_EQ(k.primal, 2.5 / 3.0);
    EXPECT_DOUBLE_EQ(k.dual, 0.25);
    EXPECT_DOUBLE_EQ(k.complementarity, 2.5);
    // from_gradient gives the same without the A-product
    const Vec g = qp.A * Eigen::Vector2d(0.5, 1) - qp.b;
    EXPECT_DOUBLE_EQ(cb::kkt_residuals_from_gradient(qp.view(), Eigen::Vector2d(0.5, 1), g, Eigen::Vector2d(4, -1)).max(),
                     2.5);
}

// The exact solution of the STYLE example has zero error in all parts.
TEST(Kkt, ZeroAtTheHandSolution)
{
    const Qp qp = cb::testing_qps::tiny_active_qp();
    const cb::KktResiduals k = cb::kkt_residuals(qp.view(), Eigen::Vector2d(1, 1), Vec::Constant(1, 2.0));
    EXPECT_EQ(k.max(), 0.0);
}

// Reference = KKT max at (x0, lambda = 0). b = (0, 4), c = (0.5, 0.25), x0 = (0, 1):
//   stationarity |(0, 2 - 4)|_inf / 4 = 0.5; primal max(0.5 - 0, 0.25 - 1) / 1 = 0.5.
TEST(Kkt, RelativeReferenceIsTheStartPoint)
{
    const Qp qp = diag_qp(4.0, Eigen::Vector2d(0.5, 0.25), Eigen::Vector2d(0, 1));
    const cb::KktScale scale = cb::kkt_scale(qp.view());
    EXPECT_DOUBLE_EQ(scale.reference, 0.5);
    EXPECT_DOUBLE_EQ(scale.inverse_reference, 2.0);
}

// x0 already optimal (unconstrained minimiser, feasible): reference 0 falls back to 1.
TEST(Kkt, ZeroReferenceFallsBackToOne)
{
    const Qp qp = diag_qp(2.0, Eigen::Vector2d(-1, -1), Eigen::Vector2d(0, 1));
    const cb::KktScale scale = cb::kkt_scale(qp.view());
    EXPECT_EQ(scale.reference, 1.0);
    EXPECT_EQ(scale.inverse_reference, 1.0);
}

TEST(Kkt, UnconstrainedUsesGradientOnly)
{
    const Qp qp = cb::testing_qps::unconstrained_qp();
    // x = 0: g = -b = (-3, 0, -3), s = 3 -> 1.
    const cb::KktResiduals k = cb::kkt_residuals(qp.view(), Vec::Zero(3), Vec(0));
    EXPECT_DOUBLE_EQ(k.stationarity, 1.0);
    EXPECT_EQ(k.primal, 0.0);
    EXPECT_EQ(k.dual, 0.0);
    EXPECT_EQ(k.complementarity, 0.0);
}

// Without multipliers (lambda of the wrong size) stationarity is |g| and dual/complementarity 0.
TEST(Kkt, MissingLambdaMeansGradientOnly)
{
    const Qp qp = diag_qp(2.0, Eigen::Vector2d(1, 0.5));
    const cb::KktResiduals k = cb::kkt_residuals(qp.view(), Eigen::Vector2d(0.5, 1), Vec(0));
    EXPECT_DOUBLE_EQ(k.stationarity, 0.5);  // |(1, 0)| / 2
    EXPECT_DOUBLE_EQ(k.primal, 0.5);
    EXPECT_EQ(k.dual, 0.0);
    EXPECT_EQ(k.complementarity, 0.0);
}

TEST(Kkt, NonFiniteReadsAsInfinity)
{
    const Qp qp = diag_qp(2.0, Eigen::Vector2d(1, 0.5));
    const double nan = std::numeric_limits<double>::quiet_NaN();
    const cb::KktResiduals k = cb::kkt_residuals(qp.view(), Eigen::Vector2d(nan, 1), Eigen::Vector2d(1, 0));
    EXPECT_TRUE(std::isinf(k.stationarity));
    EXPECT_TRUE(std::isinf(k.max()));
    const cb::KktResiduals k2 = cb::kkt_residuals(qp.view(), Eigen::Vector2d(1, 1), Eigen::Vector2d(nan, 0));
    EXPECT_TRUE(std::isinf(k2.max()));
    EXPECT_TRUE(std::isinf(k2.stationarity));
    const double inf = std::numeric_limits<double>::infinity();
    EXPECT_TRUE(std::isinf(cb::kkt_residuals(qp.view(), Eigen::Vector2d(inf, 1), Eigen::Vector2d(0, 0)).max()));
}

// STYLE example at x* = (1,1): g = (2, 0), one active row -> lambda = J g / |J|^2 = 2.
TEST(Kkt, FitMultipliersOnActiveRow)
{
    const Qp qp = cb::testing_qps::tiny_active_qp();
    const Vec x = Eigen::Vector2d(1, 1);
    const Vec lambda = cb::fit_multipliers(qp.view(), x, qp.A * x - qp.b);
    ASSERT_EQ(lambda.size(), 1);
    EXPECT_NEAR(lambda[0], 2.0, 1e-10);
}

// An inactive row gets exactly 0; a violated row is fitted.
TEST(Kkt, FitMultipliersInactiveRowIsZero)
{
    const Qp qp = diag_qp(2.0, Eigen::Vector2d(1, 0.5));
    const Vec x = Eigen::Vector2d(1, 1);  // row 0 active (slack 0), row 1 slack 0.5
    const Vec g = qp.A * x - qp.b;        // (2, 0)
    const Vec lambda = cb::fit_multipliers(qp.view(), x, g);
    EXPECT_NEAR(lambda[0], 2.0, 1e-10);
    EXPECT_EQ(lambda[1], 0.0);
}

// Duplicated active rows: the fit splits the multiplier (1 + 1), stationarity stays exact.
TEST(Kkt, FitMultipliersSplitsDependentRows)
{
    Eigen::MatrixXd J(3, 2);
    J << 1, 0, 1, 0, 2, 0;
    const Qp qp = dense_qp(2.0 * Eigen::MatrixXd::Identity(2, 2), Eigen::Vector2d(0, 2), J,
                           Eigen::Vector3d(1, 1, 2), Vec::Zero(2));
    const Vec x = Eigen::Vector2d(1, 1);
    const Vec g = qp.A * x - qp.b;
    const Vec lambda = cb::fit_multipliers(qp.view(), x, g);
    EXPECT_LE((g - qp.J.transpose() * lambda).lpNorm<Eigen::Infinity>(), 1e-9);
    // Close to the least-norm split of 2 = l0 + l1 + 2 l2, (1/3, 1/3, 2/3). Only close: the
    // Tikhonov term (1e-12 of the diagonal) on a singular J_A J_A' fixes the null-space
    // component to about eps * cond = 1e-4 (stationarity above is unaffected).
    EXPECT_NEAR(lambda[0], 1.0 / 3.0, 1e-3);
    EXPECT_NEAR(lambda[1], 1.0 / 3.0, 1e-3);
    EXPECT_NEAR(lambda[2], 2.0 / 3.0, 1e-3);
}

// A nearly active row (slack 1e-8: inside the loose candidate tolerance, outside the strict one)
// whose fitted multiplier would be negative is dropped; an exactly active one keeps its honest
// negative multiplier. b = (0, 3), x = (1, 1): g = (2, -1).
TEST(Kkt, FitMultipliersDropsNearActiveNegativeRows)
{
    const Vec x = Eigen::Vector2d(1, 1);
    {
        const Qp qp = diag_qp(3.0, Eigen::Vector2d(1, 1 - 1e-8));
        const Vec lambda = cb::fit_multipliers(qp.view(), x, qp.A * x - qp.b);
        EXPECT_NEAR(lambda[0], 2.0, 1e-10);
        EXPECT_EQ(lambda[1], 0.0);
    }
    {
        const Qp qp = diag_qp(3.0, Eigen::Vector2d(1, 1));
        const Vec lambda = cb::fit_multipliers(qp.view(), x, qp.A * x - qp.b);
        EXPECT_NEAR(lambda[0], 2.0, 1e-10);
        EXPECT_NEAR(lambda[1], -1.0, 1e-10);
    }
}

TEST(Kkt, MaxViolationAndActiveTolerance)
{
    const Qp qp = diag_qp(2.0, Eigen::Vector2d(1, 0.5));
    EXPECT_DOUBLE_EQ(cb::max_violation(qp.view(), Eigen::Vector2d(0.25, 1)), 0.75);
    EXPECT_EQ(cb::max_violation(qp.view(), Eigen::Vector2d(2, 1)), 0.0);
    EXPECT_EQ(cb::active_tolerance(0.5), 1e-9);
    EXPECT_DOUBLE_EQ(cb::active_tolerance(-1e3), 1e-6);
    const Qp free = cb::testing_qps::unconstrained_qp();
    EXPECT_EQ(cb::max_violation(free.view(), Vec::Zero(3)), 0.0);
    EXPECT_EQ(cb::fit_multipliers(free.view(), Vec::Zero(3), Vec::Zero(3)).size(), 0);
}
