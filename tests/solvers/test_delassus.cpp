// Tests of the Delassus matrix W = H A^-1 H' (solvers/linalg/delassus.hpp): against a dense Cholesky
// computed here, its counters, the kept columns A^-1 H', the time-limit stop and the sparse form.
#include "solvers/linalg/delassus.hpp"

#include <gtest/gtest.h>

#include <random>

namespace cb {
namespace {

/// A random SPD A = B'B + n I (n x n, about 4 entries a row in B) and random rows H (k x n, 3 a row).
struct DelassusPair {
    SpMat A, H;
};

DelassusPair random_pair(int n, int k, unsigned seed)
{
    std::mt19937 rng(seed);
    std::uniform_int_distribution<int> col(0, n - 1);
    std::normal_distribution<double> g(0.0, 1.0);
    std::vector<Triplet> tb, th;
    for (int i = 0; i < n; ++i)
        for (int e = 0; e < 4; ++e) tb.emplace_back(i, col(rng), g(rng));
    for (int i = 0; i < k; ++i)
        for (int e = 0; e < 3; ++e) th.emplace_back(i, col(rng), g(rng));
    SpMat B(n, n), I(n, n), H(k, n);
    B.setFromTriplets(tb.begin(), tb.end());
    I.setIdentity();
    H.setFromTriplets(th.begin(), th.end());
    const SpMat BtB = SpMat(B.transpose()) * B;
    SpMat A = BtB + double(n) * I;
    return {A, H};
}

double max_abs_entry(const Eigen::MatrixXd& X) { return X.cwiseAbs().maxCoeff(); }

TEST(Delassus, DenseFormEqualsTheDenseCholeskyAndIsSymmetric)
{
    const DelassusPair p = random_pair(200, 150, 3);
    Delassus delassus;
    Counters counters;
    ASSERT_TRUE(delassus.factor(SpMatCol(p.A), counters));
    EXPECT_EQ(counters.cholmod_analyses, 1);
    EXPECT_EQ(counters.cholmod_factorizations, 1);
    Eigen::MatrixXd W, Y;
    DelassusForming forming;
    forming.columns = &Y;
    ASSERT_TRUE(delassus.form_dense(p.H, W, counters, forming));
    EXPECT_EQ(counters.cholmod_solves, 150);  // one per row of H, in blocks of 64

    const Eigen::MatrixXd A(p.A), H(p.H);
    const Eigen::LLT<Eigen::MatrixXd> llt(A);
    const Eigen::MatrixXd Y_ref = llt.solve(H.transpose());
    const Eigen::MatrixXd W_ref = H * Y_ref;
    EXPECT_LE(max_abs_entry(W - W_ref), 1e-13 * max_abs_entry(W_ref));
    EXPECT_LE(max_abs_entry(Y - Y_ref), 1e-13 * max_abs_entry(Y_ref));
    EXPECT_EQ(max_abs_entry(W - W.transpose()), 0.0);  // symmetrised exactly

    // Another block size solves the same columns: the same W to rounding.
    Eigen::MatrixXd W1;
    DelassusForming one_column;
    one_column.block = 1;
    ASSERT_TRUE(delassus.form_dense(p.H, W1, counters, one_column));
    EXPECT_LE(max_abs_entry(W1 - W), 1e-14 * max_abs_entry(W));
    EXPECT_EQ(counters.cholmod_solves, 300);
}

TEST(Delassus, SparseFormEqualsTheDenseForm)
{
    const DelassusPair p = random_pair(120, 90, 5);
    Delassus delassus;
    Counters counters;
    ASSERT_TRUE(delassus.factor(SpMatCol(p.A), counters));
    Eigen::MatrixXd W;
    ASSERT_TRUE(delassus.form_dense(p.H, W, counters));
    const Eigen::MatrixXd W_sparse(delassus.form_sparse(p.H, counters));
    EXPECT_LE(max_abs_entry(W_sparse - W), 1e-13 * max_abs_entry(W));
    EXPECT_EQ(counters.cholmod_solves, 180);
}

TEST(Delassus, BlockDiagonalAGivesABlockSparseW)
{
    // Two bodies that share no row: W's off-diagonal block is exactly empty.
    SpMat A(4, 4), H(2, 4);
    A.insert(0, 0) = 2.0, A.insert(0, 1) = 1.0, A.insert(1, 0) = 1.0, A.insert(1, 1) = 2.0;
    A.insert(2, 2) = 3.0, A.insert(3, 3) = 5.0;
    H.insert(0, 0) = 1.0, H.insert(0, 1) = 1.0, H.insert(1, 3) = 1.0;
    Delassus delassus;
    Counters counters;
    ASSERT_TRUE(delassus.factor(SpMatCol(A), counters));
    const SpMatCol W = delassus.form_sparse(H, counters);
    EXPECT_EQ(W.nonZeros(), 2);
    // (1,1) [2 1; 1 2]^-1 (1,1)' = 2/3; 1/5.
    EXPECT_NEAR(W.coeff(0, 0), 2.0 / 3.0, 1e-15);
    EXPECT_NEAR(W.coeff(1, 1), 0.2, 1e-15);
}

TEST(Delassus, TimeUpStopsAfterTheBlockFormed)
{
    const DelassusPair p = random_pair(100, 100, 7);
    Delassus delassus;
    Counters counters;
    ASSERT_TRUE(delassus.factor(SpMatCol(p.A), counters));
    Eigen::MatrixXd W;
    DelassusForming forming;
    forming.block = 16;
    int asked = 0;
    forming.time_up = [&] { return ++asked == 2; };
    EXPECT_FALSE(delassus.form_dense(p.H, W, counters, forming));
    EXPECT_EQ(asked, 2);
    EXPECT_EQ(counters.cholmod_solves, 32);
}

TEST(Delassus, IndefiniteAIsRefused)
{
    SpMat A(2, 2);
    A.insert(0, 0) = 1.0, A.insert(1, 1) = -1.0;
    Delassus delassus;
    Counters counters;
    EXPECT_FALSE(delassus.factor(SpMatCol(A), counters));
    EXPECT_EQ(counters.cholmod_factorizations, 1);
}

TEST(Delassus, SolveCountsOneSolve)
{
    const DelassusPair p = random_pair(50, 10, 9);
    Delassus delassus;
    Counters counters;
    ASSERT_TRUE(delassus.factor(SpMatCol(p.A), counters));
    const double factor_flops = counters.work_flops;
    const Vec b = Vec::LinSpaced(50, -1.0, 1.0);
    const Vec x = delassus.solve(b, counters);
    EXPECT_LE((p.A * x - b).norm(), 1e-13 * b.norm());
    EXPECT_EQ(counters.cholmod_solves, 1);
    EXPECT_GT(counters.work_flops, factor_flops);
}

}  // namespace
}  // namespace cb
