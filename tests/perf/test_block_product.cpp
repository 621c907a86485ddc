// The block product (solvers/linalg/a_product, AFormat::BSR) against Eigen's CSR product, the oracle:
// the same y, x'y and x'w on every synthetic family and every stress family, and an honest CSR
// fallback when A has no 3x3 block structure (n not a multiple of 3, scattered nonzeros).
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

/// Every product of `op` against Eigen's on A: y, the fused dots and the masked dots.
void expect_same_products(const AOperator& op, const SpMat& A, const std::string& what)
{
    SCOPED_TRACE(what);
    const Vec x = test::varied(A.cols(), 3), w = test::varied(A.cols(), 4);
    std::vector<char> skip(static_cast<size_t>(A.rows()));
    for (size_t i = 0; i < skip.size(); ++i) skip[i] = static_cast<char>(i % 5 == 1);
    const Vec oracle = A * x;
    // The block sums follow the CSR sums' order and add exact zeros: equal to the last bit.
    const double tol = 0.0;
    const long before = a_product_count();
    Vec y;
    a_product(op, x, y);
    ASSERT_EQ(y.size(), A.rows());
    EXPECT_LE((y - oracle).lpNorm<Eigen::Infinity>(), tol);
    double xw = 0.0;
    Vec y2;
    const double xy = a_product_dots(op, x, y2, w, xw);
    EXPECT_LE((y2 - oracle).lpNorm<Eigen::Infinity>(), tol);
    EXPECT_NEAR(xy, x.dot(oracle), 1e-13 * x.cwiseAbs().dot(A.cwiseAbs() * x.cwiseAbs()));
    EXPECT_NEAR(xw, x.dot(w), 1e-13 * x.cwiseAbs().dot(w.cwiseAbs()));
    double xw_masked = 0.0, expected_masked = 0.0;
    for (Eigen::Index i = 0; i < A.rows(); ++i)
        if (!skip[static_cast<size_t>(i)]) expected_masked += x[i] * w[i];
    Vec y3;
    a_product_dots(op, x, y3, w, skip.data(), xw_masked);
    EXPECT_LE((y3 - oracle).lpNorm<Eigen::Infinity>(), tol);
    EXPECT_NEAR(xw_masked, expected_masked, 1e-13 * x.cwiseAbs().dot(w.cwiseAbs()));
    EXPECT_EQ(a_product_count() - before, 3);  // each product counted once, whatever the storage
}

}  // namespace

TEST(BlockProduct, EqualsTheCsrProductOnEverySyntheticFamily)
{
    for (const std::string& family : synthetic_families()) {
        const Qp qp = make_synthetic(family, nlohmann::json::object(), 7);
        AOperator op(qp.A);
        const AFormat format = op.prepare(AFormat::BSR);
        if (qp.n() % 3 == 0) {
            EXPECT_EQ(format, AFormat::BSR) << family << ": " << op.why_csr();
            EXPECT_LE(op.fill(), 1.25) << family;
            EXPECT_LT(op.matrix_bytes(), static_cast<double>(qp.A.nonZeros()) * 12.0) << family;
        }
        expect_same_products(op, qp.A, family);
    }
}

TEST(BlockProduct, EqualsTheCsrProductOnEveryStressFamily)
{
    std::set<std::string> done;
    std::vector<std::string> csr;
    for (const StressCase& c : stress_cases()) {
        if (!done.insert(c.family).second) continue;  // the first case of each family
        const Qp qp = make_stress_qp(c);
        AOperator op(qp.A);
        if (op.prepare(AFormat::BSR) == AFormat::CSR) csr.push_back(c.id + ": " + op.why_csr());
        expect_same_products(op, qp.A, c.id);
    }
    EXPECT_GE(done.size(), 10u);
    // Every stress family's A is made of vertex blocks: none falls back to CSR.
    EXPECT_EQ(csr, (std::vector<std::string>{}));
}

// Large enough for several chunks of the AVX2 kernel's row pairs (4096 block rows a chunk), with an
// odd block row count; both kernels (AVX2 where the CPU has it, and the scalar loop) are compared.
TEST(BlockProduct, BothKernelsEqualTheCsrProductOnALargeGrid)
{
    const SpMat A = test::fem_grid(40, 22, 20);  // 41 * 23 * 21 = 19803 vertices: an odd count of block rows
    ASSERT_EQ(A.rows() / 3 % 2, 1);
    for (const bool scalar : {false, true}) {
        force_scalar_block_kernel(scalar);
        AOperator op(A);
        ASSERT_EQ(op.prepare(AFormat::BSR), AFormat::BSR) << op.why_csr();
        expect_same_products(op, A, scalar ? "scalar kernel" : "default kernel");
        AOperator two(A);  // two row ranges (threads = 2): y to the last bit (the dots sum by range)
        ASSERT_EQ(two.prepare(AFormat::BSR, 2), AFormat::BSR);
        ASSERT_EQ(two.parts(), 2);
        const Vec x = test::varied(A.cols(), 5);
        Vec y;
        a_product(two, x, y);
        EXPECT_EQ((y - A * x).cwiseAbs().maxCoeff(), 0.0) << (scalar ? "scalar" : "default");
    }
    force_scalar_block_kernel(false);
}

TEST(BlockProduct, FallsBackToCsrWhenNIsNotAMultipleOfThree)
{
    const Qp qp = make_synthetic("plane", {{"nx", 2}, {"ny", 2}, {"nz", 2}}, 3);
    const Eigen::Index n = qp.n() - 1;  // drop the last DOF: n is no longer a multiple of 3
    const SpMat A = qp.A.topLeftCorner(n, n);
    AOperator op(A);
    EXPECT_EQ(op.prepare(AFormat::BSR), AFormat::CSR);
    EXPECT_EQ(op.why_csr(), "the DOF count " + std::to_string(n) + " is not a positive multiple of 3");
    EXPECT_EQ(op.fill(), 0.0);
    expect_same_products(op, A, "n = " + std::to_string(n));
}

TEST(BlockProduct, FallsBackToCsrWhenTheNonzerosFormNoBlocks)
{
    // A diagonal A stores one entry per 3x3 block: blocks would read 3x its values.
    const Eigen::Index n = 30;
    SpMat A(n, n);
    for (Eigen::Index i = 0; i < n; ++i) A.insert(i, i) = 1.0 + static_cast<double>(i);
    A.makeCompressed();
    AOperator op(A);
    EXPECT_EQ(op.prepare(AFormat::BSR), AFormat::CSR);
    EXPECT_EQ(op.why_csr(), "A's nonzeros do not form 3x3 blocks (3.000000 stored entries per nonzero)");
    expect_same_products(op, A, "diagonal");
    // CSR asked for: no block copy.
    AOperator csr(A);
    EXPECT_EQ(csr.prepare(AFormat::CSR), AFormat::CSR);
    EXPECT_TRUE(csr.why_csr().empty());
    EXPECT_TRUE(csr.blocks().value.empty());
}

TEST(BlockProduct, StoresPartlyFilledBlocksWithZerosAndSumsInColumnOrder)
{
    // A 6x6 with one entry missing from each off-diagonal block: the blocks store zeros there,
    // and every y entry equals the CSR sum bit for bit.
    Eigen::MatrixXd dense = Eigen::MatrixXd::Random(6, 6);
    dense = (dense * dense.transpose()).eval();
    dense(0, 4) = dense(4, 0) = 0.0;
    const SpMat A = dense.sparseView();
    AOperator op(A);
    ASSERT_EQ(op.prepare(AFormat::BSR), AFormat::BSR);
    EXPECT_EQ(op.blocks().column, (std::vector<int>{0, 1, 0, 1}));
    EXPECT_DOUBLE_EQ(op.fill(), 36.0 / 34.0);
    EXPECT_EQ(op.blocks().value[9 * 1 + 3 * 1 + 0], 0.0);            // block (0, 1), entry (0, 4)
    EXPECT_EQ(op.blocks().value[9 * 1 + 3 * 0 + 1], A.coeff(1, 3));  // column-major within the block
    const Vec x = test::varied(6, 9);
    Vec y;
    a_product(op, x, y);
    const Vec oracle = A * x;
    for (Eigen::Index i = 0; i < 6; ++i) EXPECT_EQ(y[i], oracle[i]) << i;
}

// A FEM matrix's block rows have three rows with the same columns in whole groups 3J .. 3J + 2: the
// build copies their values straight into the blocks. Those blocks must hold A's entries where the
// merge put them (value (r, c) of block (I, J) at 9k + 3c + r), for all blocks and the upper ones,
// also when some rows (here: one entry dropped) take the merge beside them.
TEST(BlockProduct, BlocksCopiedFromWholeColumnGroupsHoldTheEntriesOfA)
{
    SpMat A = test::fem_grid(6, 5, 4);
    SpMat gapped = A;
    gapped.coeffRef(4, 1) = 0.0;
    gapped.prune(0.0);  // block row 1 now has rows of different patterns: the merge's path
    gapped.makeCompressed();
    ASSERT_LT(gapped.nonZeros(), A.nonZeros());
    for (const SpMat* M : {&A, &gapped}) {
        const Eigen::MatrixXd dense(*M);
        for (const bool upper : {false, true}) {
            BlockRows B;
            double fill = 0.0;
            std::string why;
            ASSERT_TRUE(upper ? build_upper_block_rows(*M, B, 1.25, fill, why)
                              : build_block_rows(*M, B, 1.25, fill, why))
                << why;
            long blocks = 0, mismatched = 0, entries = 0;
            for (size_t I = 0; I + 1 < B.start.size(); ++I)
                for (int k = B.start[I]; k < B.start[I + 1]; ++k, ++blocks) {
                    const int J = B.column[static_cast<size_t>(k)];
                    if (upper) {
                        EXPECT_GE(J, static_cast<int>(I));
                    }
                    for (int r = 0; r < 3; ++r)
                        for (int c = 0; c < 3; ++c) {
                            const double v = B.value[9 * static_cast<size_t>(k) + static_cast<size_t>(3 * c + r)];
                            mismatched += v != dense(3 * static_cast<Eigen::Index>(I) + r, 3 * J + c);
                            entries += v != 0.0;
                        }
                }
            EXPECT_EQ(mismatched, 0) << (upper ? "upper" : "all");
            // Every nonzero of A (of its upper block triangle) is in some block.
            long expected = 0;
            for (Eigen::Index i = 0; i < dense.rows(); ++i)
                for (Eigen::Index j = upper ? i / 3 * 3 : 0; j < dense.cols(); ++j) expected += dense(i, j) != 0.0;
            EXPECT_EQ(entries, expected) << (upper ? "upper" : "all");
            EXPECT_EQ(B.value.size(), 9 * static_cast<size_t>(blocks) + 1);
        }
    }
}
