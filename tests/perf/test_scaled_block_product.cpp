// mprgp-coupled's precond = scaled multiplies by U A U (U = diag(u)) without a scaled copy of A. On
// BSR with one thread the block kernels scale each row's sum and sum the dots as they store y;
// this checks them against the pass they replaced (U x into a buffer, the plain product, then y
// scaled and the dots summed in index order): every y entry and every dot equal to the last bit,
// for both kernels.
#include "problems/synthetic.hpp"
#include "solvers/linalg/a_product.hpp"
#include "tests/perf/fem_grid.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

using namespace cb;

namespace {

Vec spread(Eigen::Index n, std::uint64_t seed, double decades)
{
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    Vec v(n);
    for (Eigen::Index i = 0; i < n; ++i) v[i] = u(rng) * std::pow(10.0, decades * u(rng));
    return v;
}

struct Unfused {
    Vec y;
    double xy = 0.0, xw = 0.0, xw_masked = 0.0;
};

/// The buffer-and-passes product: ux = u .* x, y = A ux, y .* u, dots in index order.
Unfused unfused(const AOperator& plain, const Vec& u, const Vec& x, const Vec& w, const std::vector<char>& skip)
{
    Unfused r;
    const Vec ux = u.cwiseProduct(x);
    a_product(plain, ux, r.y);
    for (Eigen::Index i = 0; i < r.y.size(); ++i) {
        r.y[i] *= u[i];
        r.xy += x[i] * r.y[i];
        r.xw += x[i] * w[i];
        if (!skip[static_cast<size_t>(i)]) r.xw_masked += x[i] * w[i];
    }
    return r;
}

}  // namespace

// Several chunks of the AVX2 kernel's row pairs (4096 block rows a chunk) and an odd block-row count.
TEST(ScaledBlockProduct, FusedScalingEqualsTheBufferedPassesToTheLastBit)
{
    const SpMat A = test::fem_grid(40, 22, 20);  // 19803 vertices
    ASSERT_EQ(A.rows() / 3 % 2, 1);
    const Vec u = spread(A.rows(), 11, 2.0).cwiseAbs();  // D^-1/2: positive, spread over decades
    const Vec x = spread(A.rows(), 12, 3.0), w = spread(A.rows(), 13, 3.0);
    std::vector<char> skip(static_cast<size_t>(A.rows()));
    for (size_t i = 0; i < skip.size(); ++i) skip[i] = static_cast<char>(i % 7 == 2);
    for (const bool scalar : {false, true}) {
        SCOPED_TRACE(scalar ? "scalar kernel" : "default kernel");
        force_scalar_block_kernel(scalar);
        AOperator plain(A), scaled(A);
        ASSERT_EQ(plain.prepare(AFormat::BSR), AFormat::BSR);
        ASSERT_EQ(scaled.prepare(AFormat::BSR), AFormat::BSR);
        scaled.scale_by(&u);
        const Unfused ref = unfused(plain, u, x, w, skip);
        const long before = a_product_count();
        Vec y1, y2, y3;
        a_product(scaled, x, y1);
        double xw = 0.0, xw_masked = 0.0;
        const double xy = a_product_dots(scaled, x, y2, w, xw);
        const double xy_masked = a_product_dots(scaled, x, y3, w, skip.data(), xw_masked);
        EXPECT_EQ(a_product_count() - before, 3);
        long differing = 0;
        for (Eigen::Index i = 0; i < A.rows(); ++i)
            differing += (y1[i] != ref.y[i]) + (y2[i] != ref.y[i]) + (y3[i] != ref.y[i]);
        EXPECT_EQ(differing, 0);
        EXPECT_EQ(xy, ref.xy);
        EXPECT_EQ(xw, ref.xw);
        EXPECT_EQ(xy_masked, ref.xy);
        EXPECT_EQ(xw_masked, ref.xw_masked);
        // Not vacuous: U changes the product.
        Vec plain_y;
        a_product(plain, x, plain_y);
        EXPECT_GT((plain_y - ref.y).cwiseAbs().maxCoeff(), 0.0);
    }
    force_scalar_block_kernel(false);
}

// On SBSR the blocks are a copy already, so scale_by() scales them in place: the product of U A U
// then reads x itself. Its y equals the buffered product's to rounding (another order of the
// same products), whether the scaling came before prepare() or after it, both kernels give the
// same bits, and scale_by(nullptr) gives A's own product back to the bit.
TEST(ScaledBlockProduct, SymmetricBlocksScaledInPlaceEqualTheBufferedPassesToRounding)
{
    const SpMat A = test::fem_grid(12, 10, 9);
    const Vec u = spread(A.rows(), 21, 2.0).cwiseAbs();
    const Vec x = spread(A.rows(), 22, 3.0), w = spread(A.rows(), 23, 3.0);
    std::vector<char> skip(static_cast<size_t>(A.rows()));
    for (size_t i = 0; i < skip.size(); ++i) skip[i] = static_cast<char>(i % 7 == 2);
    AOperator bsr(A);
    ASSERT_EQ(bsr.prepare(AFormat::BSR), AFormat::BSR);
    const Unfused ref = unfused(bsr, u, x, w, skip);
    // |U||A||U||x| per row: the size of each y_i's terms, for the rounding bound.
    const Vec size = u.asDiagonal() * (A.cwiseAbs() * u.cwiseProduct(x).cwiseAbs());
    Vec y_kernel[2];
    for (const int scalar : {0, 1}) {
        force_scalar_block_kernel(scalar == 1);
        AOperator before(A), after(A);
        before.scale_by(&u);
        ASSERT_EQ(before.prepare(AFormat::SBSR), AFormat::SBSR);
        ASSERT_EQ(after.prepare(AFormat::SBSR), AFormat::SBSR);
        after.scale_by(&u);
        EXPECT_TRUE(before.blocks_scaled());
        EXPECT_TRUE(after.blocks_scaled());
        Vec y_before, y_after, y_masked;
        double xw = 0.0, xw_masked = 0.0;
        const double xy = a_product_dots(before, x, y_before, w, xw);
        const double xy_masked = a_product_dots(before, x, y_masked, w, skip.data(), xw_masked);
        a_product(after, x, y_after);
        double worst = 0.0;
        for (Eigen::Index i = 0; i < A.rows(); ++i) worst = std::max(worst, std::abs(y_before[i] - ref.y[i]) / size[i]);
        EXPECT_LT(worst, 1e-14);
        EXPECT_GT(worst, 0.0);  // not the buffered order: the rounding differs somewhere
        EXPECT_EQ((y_before - y_after).cwiseAbs().maxCoeff(), 0.0);
        EXPECT_EQ((y_before - y_masked).cwiseAbs().maxCoeff(), 0.0);
        EXPECT_NEAR(xy, ref.xy, 1e-14 * x.cwiseAbs().dot(size));
        EXPECT_NEAR(xy_masked, ref.xy, 1e-14 * x.cwiseAbs().dot(size));
        // x'w does not read A: only the order of its sum differs (four partial sums)
        EXPECT_NEAR(xw, ref.xw, 1e-14 * x.cwiseAbs().dot(w.cwiseAbs()));
        EXPECT_NEAR(xw_masked, ref.xw_masked, 1e-14 * x.cwiseAbs().dot(w.cwiseAbs()));
        y_kernel[scalar] = y_before;
        // A's own product again, to the bit.
        after.scale_by(nullptr);
        EXPECT_FALSE(after.blocks_scaled());
        AOperator plain(A);
        ASSERT_EQ(plain.prepare(AFormat::SBSR), AFormat::SBSR);
        Vec y_plain, y_unscaled;
        a_product(plain, x, y_plain);
        a_product(after, x, y_unscaled);
        EXPECT_EQ((y_plain - y_unscaled).cwiseAbs().maxCoeff(), 0.0);
    }
    force_scalar_block_kernel(false);
    EXPECT_EQ((y_kernel[0] - y_kernel[1]).cwiseAbs().maxCoeff(), 0.0);
}
