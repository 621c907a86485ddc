// Tests of the accuracy measure's row kernel (solvers/measure/accuracy_rows.hpp): the parts of one row
// against hand-computed values, zero rows, and NaN reading as +inf in every part (the fused
// evaluations of mprgp, mprgp-coupled and pgs dropped a NaN row part through std::max before
// they called the kernel).
#include "solvers/measure/accuracy_rows.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace {

using cb::RowParts;
constexpr double INF = std::numeric_limits<double>::infinity();
constexpr double NaN = std::numeric_limits<double>::quiet_NaN();

TEST(AccuracyRows, OneRowByHand)
{
    RowParts rows;
    // slack -0.5 (a penetration of 0.5 / n_i = 0.25 with n_i = 2), lambda 2, n_i / k_i = 0.25.
    rows.add_row(1.0, -0.5, 2.0, 0.5, 0.25);
    EXPECT_EQ(rows.primal, 0.25);
    EXPECT_EQ(rows.dual, 0.0);
    EXPECT_EQ(rows.complementarity, 0.25);  // min(2 * 0.25, 0.5 * 0.5)
    EXPECT_EQ(rows.gap, 1.0);
    // A pulling multiplier on a free row: dual part, no primal part; gap sums, the others are maxima.
    rows.add_row(0.0, 4.0, -1.0, 1.0, 3.0);
    EXPECT_EQ(rows.primal, 0.25);
    EXPECT_EQ(rows.dual, 3.0);
    EXPECT_EQ(rows.complementarity, 3.0);  // min(|-3|, 4)
    EXPECT_EQ(rows.gap, 5.0);
    const RowParts e = rows.scaled(0.5, 0.1);
    EXPECT_EQ(e.primal, 0.125);
    EXPECT_EQ(e.dual, 1.5);
    EXPECT_EQ(e.complementarity, 1.5);
    EXPECT_DOUBLE_EQ(e.gap, 0.5);
}

TEST(AccuracyRows, ZeroRowHoldsIffItsBoundIsNotPositive)
{
    RowParts rows;
    rows.add_row(0.0, 0.0, 5.0, 0.0, 0.0);  // c = 0: feasible, and its multiplier exerts no force
    rows.add_row(-1.0, 1.0, -7.0, 0.0, 0.0);
    EXPECT_EQ(rows.primal, 0.0);
    EXPECT_EQ(rows.dual, 0.0);
    EXPECT_EQ(rows.complementarity, 0.0);
    EXPECT_EQ(rows.gap, 0.0);
    rows.add_row(1e-12, -1e-12, 0.0, 0.0, 0.0);
    EXPECT_EQ(rows.primal, INF);
    RowParts nan_bound;
    nan_bound.add_zero_row(NaN);
    EXPECT_EQ(nan_bound.primal, INF);
}

TEST(AccuracyRows, NaNReadsAsInfiniteWhateverTheOrder)
{
    // A NaN slack after a finite row: std::max(part, NaN) would return the finite part.
    RowParts rows;
    rows.add_row(0.0, -1.0, 1.0, 1.0, 1.0);
    rows.add_row(0.0, NaN, 1.0, 1.0, 1.0);
    rows.add_row(0.0, -2.0, 1.0, 1.0, 1.0);  // a finite row after it keeps it infinite
    EXPECT_EQ(rows.primal, INF);
    EXPECT_EQ(rows.scaled(1.0, 1.0).gap, INF);
    RowParts lambda_nan;
    lambda_nan.add_multiplier(1.0, NaN, 1.0, 1.0);
    EXPECT_EQ(lambda_nan.dual, INF);
    EXPECT_EQ(lambda_nan.complementarity, INF);
    EXPECT_EQ(lambda_nan.scaled(1.0, 1.0).gap, INF);
    RowParts primal_only;
    primal_only.add_primal(NaN, 1.0);
    EXPECT_EQ(primal_only.primal, INF);
}

}  // namespace
