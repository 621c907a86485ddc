// The symmetric block product (solvers/linalg/a_product, AFormat::SBSR: A's upper block triangle) against
// Eigen's CSR product, the oracle: y, x'y and x'w equal to rounding on every synthetic and stress
// family; honest CSR fallbacks (n not a multiple of 3, A not symmetric); one thread whatever
// `threads` asks; about half the bytes of BSR.
#include "harness/stress_families.hpp"
#include "problems/synthetic.hpp"
#include "solvers/linalg/a_product.hpp"
#include "tests/perf/fem_grid.hpp"
#include "tests/perf/varied_vector.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <set>

using namespace cb;

namespace {

/// Every product of `op` against Eigen's on A: each y_i within a few roundings of |A||x| in row i
/// (the terms meet in another order), the fused and masked dots likewise.
void expect_sym_products_to_rounding(const AOperator& op, const SpMat& A, const std::string& what)
{
    SCOPED_TRACE(what);
    const Vec x = test::varied(A.cols(), 3), w = test::varied(A.cols(), 4);
    std::vector<char> skip(static_cast<size_t>(A.rows()));
    for (size_t i = 0; i < skip.size(); ++i) skip[i] = static_cast<char>(i % 5 == 1);
    const Vec oracle = A * x;
    const Vec size = A.cwiseAbs() * x.cwiseAbs();
    const double eps = 1e-14;
    const long before = a_product_count();
    Vec y, y2, y3;
    a_product(op, x, y);
    ASSERT_EQ(y.size(), A.rows());
    double xw = 0.0, xw_masked = 0.0;
    const double xy = a_product_dots(op, x, y2, w, xw);
    a_product_dots(op, x, y3, w, skip.data(), xw_masked);
    for (Eigen::Index i = 0; i < A.rows(); ++i) {
        ASSERT_LE(std::abs(y[i] - oracle[i]), eps * size[i]) << "row " << i;
        ASSERT_EQ(y2[i], y[i]) << "row " << i;  // the same sums with or without the dots
        ASSERT_EQ(y3[i], y[i]) << "row " << i;
    }
    double expected_masked = 0.0;
    for (Eigen::Index i = 0; i < A.rows(); ++i)
        if (!skip[static_cast<size_t>(i)]) expected_masked += x[i] * w[i];
    EXPECT_NEAR(xy, x.dot(oracle), eps * x.cwiseAbs().dot(size));
    EXPECT_NEAR(xw, x.dot(w), eps * x.cwiseAbs().dot(w.cwiseAbs()));
    EXPECT_NEAR(xw_masked, expected_masked, eps * x.cwiseAbs().dot(w.cwiseAbs()));
    EXPECT_EQ(a_product_count() - before, 3);  // each product counted once, whatever the storage
}

}  // namespace

TEST(SymBlockProduct, EqualsTheCsrProductToRoundingOnEverySyntheticFamily)
{
    for (const std::string& family : synthetic_families()) {
        const Qp qp = make_synthetic(family, nlohmann::json::object(), 7);
        AOperator op(qp.A), bsr(qp.A);
        const AFormat format = op.prepare(AFormat::SBSR);
        if (qp.n() % 3 == 0) {
            EXPECT_EQ(format, AFormat::SBSR) << family << ": " << op.why_csr();
            ASSERT_EQ(bsr.prepare(AFormat::BSR), AFormat::BSR) << family;
            // The upper block triangle: each off-diagonal block once, each diagonal block whole.
            EXPECT_EQ(2 * op.blocks().column.size(), bsr.blocks().column.size() + static_cast<size_t>(qp.n() / 3))
                << family;
            EXPECT_DOUBLE_EQ(op.fill(), 9.0 * static_cast<double>(op.blocks().column.size()) /
                                            static_cast<double>(qp.A.nonZeros()))
                << family;
            EXPECT_LT(op.matrix_bytes(), bsr.matrix_bytes()) << family;
        }
        expect_sym_products_to_rounding(op, qp.A, family);
    }
}

TEST(SymBlockProduct, EqualsTheCsrProductToRoundingOnEveryStressFamily)
{
    std::set<std::string> done;
    std::vector<std::string> csr;
    for (const StressCase& c : stress_cases()) {
        if (!done.insert(c.family).second) continue;  // the first case of each family
        const Qp qp = make_stress_qp(c);
        AOperator op(qp.A);
        if (op.prepare(AFormat::SBSR) == AFormat::CSR) csr.push_back(c.id + ": " + op.why_csr());
        expect_sym_products_to_rounding(op, qp.A, c.id);
    }
    EXPECT_GE(done.size(), 10u);
    EXPECT_EQ(csr, (std::vector<std::string>{}));  // every stress family's A is symmetric, of vertex blocks
}

TEST(SymBlockProduct, FallsBackToCsrWhenNIsNotAMultipleOfThree)
{
    const Qp qp = make_synthetic("plane", {{"nx", 2}, {"ny", 2}, {"nz", 2}}, 3);
    const Eigen::Index n = qp.n() - 1;
    const SpMat A = qp.A.topLeftCorner(n, n);
    AOperator op(A);
    EXPECT_EQ(op.prepare(AFormat::SBSR), AFormat::CSR);
    EXPECT_EQ(op.why_csr(), "the DOF count " + std::to_string(n) + " is not a positive multiple of 3");
    expect_sym_products_to_rounding(op, A, "n = " + std::to_string(n));
}

TEST(SymBlockProduct, FallsBackToCsrWhenANotSymmetric)
{
    Eigen::MatrixXd dense = Eigen::MatrixXd::Random(6, 6);
    dense = (dense * dense.transpose()).eval();
    {
        Eigen::MatrixXd off = dense;
        off(4, 0) = off(0, 4) * (1.0 + 1e-15) + 1e-300;  // below the diagonal block: one bit off
        const SpMat A = off.sparseView();
        AOperator op(A);
        EXPECT_EQ(op.prepare(AFormat::SBSR), AFormat::CSR);
        EXPECT_EQ(op.why_csr(), "A is not symmetric (entry (4, 0) differs from (0, 4))");
    }
    {
        Eigen::MatrixXd off = dense;
        off(1, 2) += 1.0;  // inside a diagonal block
        const SpMat A = off.sparseView();
        AOperator op(A);
        EXPECT_EQ(op.prepare(AFormat::SBSR), AFormat::CSR);
        EXPECT_EQ(op.why_csr(), "A is not symmetric (entry (1, 2) differs from (2, 1))");
    }
    {
        Eigen::MatrixXd off = dense;
        off(3, 1) = 0.0;  // the lower entry absent, the upper one not
        const SpMat A = off.sparseView();
        AOperator op(A);
        EXPECT_EQ(op.prepare(AFormat::SBSR), AFormat::CSR);
        EXPECT_EQ(op.why_csr(), "A is not symmetric (9 nonzeros above its block diagonal, 8 below)");
        expect_sym_products_to_rounding(op, A, "one-sided entry");
    }
    // The same A with its symmetry intact: SBSR, and its blocks are the upper ones only.
    const SpMat A = dense.sparseView();
    AOperator op(A);
    ASSERT_EQ(op.prepare(AFormat::SBSR), AFormat::SBSR) << op.why_csr();
    EXPECT_EQ(op.blocks().column, (std::vector<int>{0, 1, 1}));
    EXPECT_EQ(op.blocks().value[9 * 1 + 3 * 2 + 0], A.coeff(0, 5));  // block (0, 1), column-major
    EXPECT_DOUBLE_EQ(op.fill(), 27.0 / 36.0);
}

TEST(SymBlockProduct, RunsOnOneThreadWhateverThreadsAsks)
{
    const Qp qp = make_synthetic("plane", {{"nx", 24}, {"ny", 24}, {"nz", 24}}, 1);
    ASSERT_GT(qp.A.nonZeros(), 4 * MIN_NONZEROS_PER_PART);
    AOperator one(qp.A), four(qp.A);
    ASSERT_EQ(one.prepare(AFormat::SBSR, 1), AFormat::SBSR);
    ASSERT_EQ(four.prepare(AFormat::SBSR, 4), AFormat::SBSR);
    EXPECT_EQ(four.parts(), 1);
    EXPECT_EQ(four.part_start(), (std::vector<int>{0, static_cast<int>(qp.n() / 3)}));
    const Vec x = test::varied(qp.n(), 11), w = test::varied(qp.n(), 12);
    Vec y1, y4;
    double xw1 = 0.0, xw4 = 0.0;
    const double xy1 = a_product_dots(one, x, y1, w, xw1);
    const double xy4 = a_product_dots(four, x, y4, w, xw4);
    EXPECT_EQ((y1 - y4).lpNorm<Eigen::Infinity>(), 0.0);
    EXPECT_EQ(xy1, xy4);
    EXPECT_EQ(xw1, xw4);
}

// Several chunks of the AVX2 symmetric kernel (1024 block rows a chunk): both kernels give the same
// y and dots to the last bit (they sum in the same order), and both equal CSR's to rounding.
TEST(SymBlockProduct, BothKernelsGiveTheSameSumsToTheLastBitOnALargeGrid)
{
    const SpMat A = test::fem_grid(40, 22, 20);  // 19803 vertices
    const Vec x = test::varied(A.cols(), 21), w = test::varied(A.cols(), 22);
    std::vector<char> skip(static_cast<size_t>(A.rows()));
    for (size_t i = 0; i < skip.size(); ++i) skip[i] = static_cast<char>(i % 3 == 0);
    Vec y[2], y_dots[2], y_masked[2];
    double xy[2], xw[2], xy_masked[2], xw_masked[2];
    for (const int scalar : {0, 1}) {
        force_scalar_block_kernel(scalar == 1);
        AOperator op(A);
        ASSERT_EQ(op.prepare(AFormat::SBSR), AFormat::SBSR) << op.why_csr();
        expect_sym_products_to_rounding(op, A, scalar ? "scalar kernel" : "default kernel");
        a_product(op, x, y[scalar]);
        xy[scalar] = a_product_dots(op, x, y_dots[scalar], w, xw[scalar]);
        xy_masked[scalar] = a_product_dots(op, x, y_masked[scalar], w, skip.data(), xw_masked[scalar]);
    }
    force_scalar_block_kernel(false);
    long differing = 0;
    for (Eigen::Index i = 0; i < A.rows(); ++i)
        differing += (y[0][i] != y[1][i]) + (y_dots[0][i] != y[1][i]) + (y_masked[0][i] != y[1][i]);
    EXPECT_EQ(differing, 0);
    EXPECT_EQ(xy[0], xy[1]);
    EXPECT_EQ(xw[0], xw[1]);
    EXPECT_EQ(xy_masked[0], xy_masked[1]);
    EXPECT_EQ(xw_masked[0], xw_masked[1]);
}

// `a_format = auto` reads the upper blocks only on one thread and from AUTO_SYMMETRIC_MIN_NONZEROS on;
// below that it keeps BSR (CSR's sums to the bit), which a small symmetric A shows.
TEST(SymBlockProduct, AutoChoosesTheUpperBlocksOnlyForALargeAOnOneThread)
{
    EXPECT_FALSE(auto_prefers_upper_blocks(AUTO_SYMMETRIC_MIN_NONZEROS - 1, 1));
    EXPECT_TRUE(auto_prefers_upper_blocks(AUTO_SYMMETRIC_MIN_NONZEROS, 1));
    EXPECT_TRUE(auto_prefers_upper_blocks(AUTO_SYMMETRIC_MIN_NONZEROS, 0));  // threads <= 1: one thread
    EXPECT_FALSE(auto_prefers_upper_blocks(AUTO_SYMMETRIC_MIN_NONZEROS, 2));
    const Qp qp = make_synthetic("plane", {{"nx", 6}, {"ny", 6}, {"nz", 6}}, 1);
    ASSERT_LT(qp.A.nonZeros(), AUTO_SYMMETRIC_MIN_NONZEROS);
    AOperator op(qp.A);
    EXPECT_EQ(op.prepare(AFormat::AUTO, 1), AFormat::BSR);
}

// The CG step's next direction formed inside the product's pass (a_product_dots_next_direction)
// equals the pass of its own before the product, p = z - beta p then a_product_dots, to the last
// bit: p, y and both dots, on SBSR with either kernel (scaled blocks too) and on the formats that
// take the separate pass (BSR, CSR), with a grid of several chunks and a frontier that moves by
// blocks, not rows.
TEST(SymBlockProduct, NextDirectionInThePassEqualsTheSeparateUpdateToTheLastBit)
{
    const SpMat A = test::fem_grid(40, 22, 20);
    const Vec p0 = test::varied(A.cols(), 31), z = test::varied(A.cols(), 32), w = test::varied(A.cols(), 33);
    const Vec u = A.diagonal().cwiseSqrt().cwiseInverse();
    const double beta = 0.6180339887498949;
    struct Case {
        AFormat format;
        bool scalar, scaled;
    };
    const Case cases[] = {{AFormat::SBSR, false, false}, {AFormat::SBSR, true, false}, {AFormat::SBSR, false, true},
                          {AFormat::SBSR, true, true},   {AFormat::BSR, false, false}, {AFormat::CSR, false, false}};
    for (const Case& c : cases) {
        SCOPED_TRACE(std::string(to_string(c.format)) + (c.scalar ? " scalar" : "") + (c.scaled ? " scaled" : ""));
        force_scalar_block_kernel(c.scalar);
        AOperator op(A);
        ASSERT_EQ(op.prepare(c.format), c.format) << op.why_csr();
        if (c.scaled) op.scale_by(&u);
        Vec p_separate = p0, y_separate, p_fused = p0, y_fused;
        double pw_separate = 0.0, pw_fused = 0.0;
        p_separate = z - beta * p_separate;
        const double py_separate = a_product_dots(op, p_separate, y_separate, w, pw_separate);
        const long before = a_product_count();
        const double py_fused = a_product_dots_next_direction(op, p_fused, z, beta, y_fused, w, nullptr, pw_fused);
        EXPECT_EQ(a_product_count() - before, 1);
        long differing = 0;
        for (Eigen::Index i = 0; i < A.rows(); ++i)
            differing += (p_fused[i] != p_separate[i]) + (y_fused[i] != y_separate[i]);
        EXPECT_EQ(differing, 0);
        EXPECT_EQ(py_fused, py_separate);
        EXPECT_EQ(pw_fused, pw_separate);
        EXPECT_NE(p_fused[0], p0[0]);  // the update did happen
        // The masked dot (decoupled mprgp's p'g off its rows' DOFs) likewise.
        std::vector<char> skip(static_cast<size_t>(A.rows()));
        for (size_t i = 0; i < skip.size(); ++i) skip[i] = static_cast<char>(i % 7 == 2);
        Vec p_masked_separate = p0, y_masked_separate, p_masked_fused = p0, y_masked_fused;
        double pw_masked_separate = 0.0, pw_masked_fused = 0.0;
        p_masked_separate = z - beta * p_masked_separate;
        const double py_masked_separate =
            a_product_dots(op, p_masked_separate, y_masked_separate, w, skip.data(), pw_masked_separate);
        const double py_masked_fused =
            a_product_dots_next_direction(op, p_masked_fused, z, beta, y_masked_fused, w, skip.data(), pw_masked_fused);
        EXPECT_EQ((p_masked_fused - p_masked_separate).lpNorm<Eigen::Infinity>(), 0.0);
        EXPECT_EQ((y_masked_fused - y_masked_separate).lpNorm<Eigen::Infinity>(), 0.0);
        EXPECT_EQ(py_masked_fused, py_masked_separate);
        EXPECT_EQ(pw_masked_fused, pw_masked_separate);
        EXPECT_NE(pw_masked_fused, pw_fused);  // the mask did leave entries out
    }
    force_scalar_block_kernel(false);
}
