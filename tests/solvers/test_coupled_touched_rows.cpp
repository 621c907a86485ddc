// TouchedRowsOfA (solvers/mprgp/coupled_touched_rows.hpp): d'Ad and g += A d over a sparse d's DOFs read
// from A's 3x3 blocks give the CSR rows' results to the last bit (the blocks' stored zeros add exact
// zeros), with and without the scaling U, and both equal the dense products to rounding.
#include "solvers/linalg/a_product.hpp"
#include "solvers/mprgp/coupled_touched_rows.hpp"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <random>
#include <vector>

namespace coupled_touched_rows_test {

using cb::SpMat;
using cb::Vec;

/// A random symmetric positive definite A of nb x nb blocks of 3x3 (diagonally dominant), a share
/// of the stored blocks' entries left out of the CSR (the blocks then hold zeros there).
SpMat random_block_spd(int nb, std::mt19937& rng, double absent_share = 0.1)
{
    std::uniform_real_distribution<double> value(-1.0, 1.0);
    std::uniform_int_distribution<int> block(0, nb - 1);
    std::bernoulli_distribution absent(absent_share);
    const int n = 3 * nb;
    Eigen::MatrixXd dense = Eigen::MatrixXd::Zero(n, n);
    for (int I = 0; I < nb; ++I)
        for (int e = 0; e < 4; ++e) {
            const int K = block(rng);
            for (int r = 0; r < 3; ++r)
                for (int c = 0; c < 3; ++c) {
                    if (absent(rng)) continue;
                    const double v = value(rng);
                    dense(3 * I + r, 3 * K + c) += v;
                    dense(3 * K + c, 3 * I + r) += v;
                }
        }
    for (int i = 0; i < n; ++i) dense(i, i) = dense.row(i).cwiseAbs().sum() + 1.0;
    SpMat A = dense.sparseView();
    A.makeCompressed();
    return A;
}

/// A DOF list and a d that is zero off it (DOFs in no particular order, as a J'lam gathers them).
void random_correction(int n, std::mt19937& rng, std::vector<int>& touched, Vec& d)
{
    std::uniform_real_distribution<double> value(-2.0, 2.0);
    touched.clear();
    d = Vec::Zero(n);
    for (int j = 0; j < n; ++j)
        if (rng() % 4 == 0) touched.push_back(j);
    std::shuffle(touched.begin(), touched.end(), rng);
    for (int j : touched) d[j] = value(rng);
}

TEST(CoupledTouchedRows, BlockRowsGiveTheCsrRowsResultsToTheLastBit)
{
    std::mt19937 rng(47);
    for (int trial = 0; trial < 4; ++trial) {
        const SpMat A = random_block_spd(40 + 17 * trial, rng);
        const int n = static_cast<int>(A.rows());
        cb::AOperator blocks(A), csr(A);
        ASSERT_EQ(blocks.prepare(cb::AFormat::BSR), cb::AFormat::BSR) << blocks.why_csr();
        ASSERT_EQ(csr.prepare(cb::AFormat::CSR), cb::AFormat::CSR);
        ASSERT_GT(blocks.fill(), 1.0);  // some stored zeros, the case the claim is about
        const Vec u = Vec::Random(n).cwiseAbs() + Vec::Constant(n, 0.5);
        for (const Vec* scale : {static_cast<const Vec*>(nullptr), &u}) {
            const cb::TouchedRowsOfA from_blocks(blocks, scale), from_csr(csr, scale);
            ASSERT_TRUE(from_blocks.reads_blocks());
            ASSERT_FALSE(from_csr.reads_blocks());
            std::vector<int> touched;
            Vec d;
            random_correction(n, rng, touched, d);
            const Eigen::MatrixXd dense = Eigen::MatrixXd(A);
            const Vec sd = scale != nullptr ? Vec(scale->cwiseProduct(d)) : d;
            const Vec ad = scale != nullptr ? Vec(scale->cwiseProduct(dense * sd)) : Vec(dense * sd);

            const double dad = from_blocks.d_a_d(touched, d);
            EXPECT_EQ(dad, from_csr.d_a_d(touched, d)) << "trial " << trial << (scale ? " scaled" : "");
            EXPECT_NEAR(dad, d.dot(ad), 1e-12 * std::abs(d.dot(ad)));

            const Vec g0 = Vec::Random(n);
            Vec g_blocks = g0, g_csr = g0;
            from_blocks.add_a_d(touched, d, g_blocks);
            from_csr.add_a_d(touched, d, g_csr);
            for (int i = 0; i < n; ++i) EXPECT_EQ(g_blocks[i], g_csr[i]) << "trial " << trial << " row " << i;
            EXPECT_LE((g_blocks - (g0 + ad)).lpNorm<Eigen::Infinity>(), 1e-12 * (1.0 + ad.lpNorm<Eigen::Infinity>()));
        }
    }
}

TEST(CoupledTouchedRows, UpperBlocksGiveTheCsrRowsResultsToRounding)
{
    // SBSR's upper blocks: the part of a row left of the diagonal comes from the blocks above it (the
    // column index), d's own block rows along the rows; scaled in place (U A U) or with U applied here.
    std::mt19937 rng(4747);
    for (int trial = 0; trial < 4; ++trial) {
        const SpMat A = random_block_spd(40 + 17 * trial, rng, 0.02);  // SBSR takes at most 25% stored zeros
        const int n = static_cast<int>(A.rows());
        const Vec u = Vec::Random(n).cwiseAbs() + Vec::Constant(n, 0.5);
        cb::AOperator upper(A), upper_scaled(A), csr(A);
        ASSERT_EQ(upper.prepare(cb::AFormat::SBSR), cb::AFormat::SBSR) << upper.why_csr();
        upper_scaled.scale_by(&u);
        ASSERT_EQ(upper_scaled.prepare(cb::AFormat::SBSR), cb::AFormat::SBSR);
        ASSERT_TRUE(upper_scaled.blocks_scaled());
        ASSERT_EQ(csr.prepare(cb::AFormat::CSR), cb::AFormat::CSR);
        struct Case {
            const cb::AOperator& op;
            const Vec* scale;
        };
        for (const Case& c : {Case{upper, nullptr}, Case{upper, &u}, Case{upper_scaled, &u}}) {
            const cb::TouchedRowsOfA from_upper(c.op, c.scale), from_csr(csr, c.scale);
            ASSERT_TRUE(from_upper.reads_upper_blocks());
            for (int draw = 0; draw < 3; ++draw) {
                std::vector<int> touched;
                Vec d;
                random_correction(n, rng, touched, d);
                const double want = from_csr.d_a_d(touched, d);
                EXPECT_NEAR(from_upper.d_a_d(touched, d), want, 1e-13 * std::abs(want)) << "trial " << trial;

                const Vec g0 = Vec::Random(n);
                Vec g_upper = g0, g_csr = g0;
                from_upper.add_a_d(touched, d, g_upper);
                from_csr.add_a_d(touched, d, g_csr);
                const double scale = 1.0 + (g_csr - g0).lpNorm<Eigen::Infinity>();
                for (int i = 0; i < n; ++i)
                    EXPECT_NEAR(g_upper[i], g_csr[i], 1e-13 * scale) << "trial " << trial << " row " << i;
            }
        }
    }
}

TEST(CoupledTouchedRows, ColumnIndexOfTheRowsDofsGivesTheWholeIndexBits)
{
    // The index restricted to the block columns of J's DOFs: the same g and d'Ad to the bit for a d on
    // those DOFs (J'lam), and for a d off them too (the search stands in for the missing columns).
    std::mt19937 rng(4748);
    const SpMat A = random_block_spd(60, rng, 0.02);
    const int n = static_cast<int>(A.rows());
    SpMat J(5, n);
    std::vector<Eigen::Triplet<double>> entries;
    for (int i = 0; i < 5; ++i)
        for (int e = 0; e < 3; ++e) entries.emplace_back(i, static_cast<int>(rng() % n), 1.0 + i + e);
    J.setFromTriplets(entries.begin(), entries.end());
    J.makeCompressed();
    cb::AOperator upper(A);
    ASSERT_EQ(upper.prepare(cb::AFormat::SBSR), cb::AFormat::SBSR) << upper.why_csr();
    const Vec u = Vec::Random(n).cwiseAbs() + Vec::Constant(n, 0.5);
    const cb::TouchedRowsOfA whole(upper, &u), of_rows(upper, &u, &J);
    std::vector<int> on_rows;
    for (int k = 0; k < J.outerSize(); ++k)
        for (SpMat::InnerIterator it(J, k); it; ++it) on_rows.push_back(static_cast<int>(it.col()));
    std::sort(on_rows.begin(), on_rows.end());
    on_rows.erase(std::unique(on_rows.begin(), on_rows.end()), on_rows.end());
    std::vector<int> anywhere;
    Vec d_anywhere;
    random_correction(n, rng, anywhere, d_anywhere);
    Vec d_on_rows = Vec::Zero(n);
    for (int j : on_rows) d_on_rows[j] = 0.5 + j % 7;
    for (const auto& [touched, d] : {std::pair{on_rows, d_on_rows}, std::pair{anywhere, d_anywhere}}) {
        const Vec g0 = Vec::Random(n);
        Vec g_whole = g0, g_rows = g0;
        whole.add_a_d(touched, d, g_whole);
        of_rows.add_a_d(touched, d, g_rows);
        EXPECT_GT((g_whole - g0).lpNorm<Eigen::Infinity>(), 0.0);
        long differing = 0;
        for (int i = 0; i < n; ++i) differing += g_whole[i] != g_rows[i];
        EXPECT_EQ(differing, 0) << touched.size() << " DOFs";
        EXPECT_EQ(whole.d_a_d(touched, d), of_rows.d_a_d(touched, d));
    }
}

}  // namespace coupled_touched_rows_test
