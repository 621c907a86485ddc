// MaskedGramFactor (solvers/linalg/masked_gram_factor.hpp): after any sequence of masks, reached by row
// modifications or by refactorisation, its solve equals a dense solve on S(mask, mask).
#include "set_solve_check.hpp"
#include "solvers/linalg/masked_gram_factor.hpp"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <random>

namespace {

using cb::SpMatCol;
using cb::Vec;
using cb::set_solve_check::random_gram;
using cb::set_solve_check::solve_error;

TEST(MaskedGramFactor, ModifiedAndRefactoredSolvesMatchDenseOnEveryMask)
{
    std::mt19937 rng(11);
    const int k = 150;
    const SpMatCol S = random_gram(k, rng);
    cb::MaskedGramFactor f(S, 8);
    cb::Counters cnt;
    std::vector<char> mask(static_cast<size_t>(k), 0);
    std::uniform_int_distribution<int> row(0, k - 1);
    for (int step = 0; step < 60; ++step) {
        // Mostly a few rows in or out (row modifications), every tenth step many (a refactorisation).
        const int flips = step % 10 == 9 ? 40 : 1 + step % 5;
        for (int e = 0; e < flips; ++e) mask[static_cast<size_t>(row(rng))] ^= 1;
        ASSERT_TRUE(f.set_mask(mask, cnt)) << "step " << step;
        EXPECT_LE(solve_error(f, S, mask, rng), 1e-10) << "step " << step;
    }
    EXPECT_GT(f.tally().row_additions, 30);
    EXPECT_GT(f.tally().row_deletions, 30);
    EXPECT_GE(f.tally().refactorizations, 6);  // the first mask and the many-row steps
    ASSERT_TRUE(f.set_mask(mask, cnt));
    EXPECT_EQ(f.tally().reuses, 1);
}

TEST(MaskedGramFactor, ADonorsFactorIsCopiedInsteadOfARefactorisationAndSolvesTheSame)
{
    // The mask jumps by 60 rows (max_updates 8: a refactorisation without donors) to within 3 rows
    // of the donor's mask: the donor's factor is copied and modified; a donor farther than
    // max_updates is not used; the solve matches the dense one either way.
    std::mt19937 rng(5);
    const int k = 120;
    const SpMatCol S = random_gram(k, rng);
    cb::MaskedGramFactor donor(S, 8), f(S, 8), far(S, 8);
    cb::Counters cnt;
    std::vector<char> donor_mask(static_cast<size_t>(k), 0), mask(static_cast<size_t>(k), 0);
    for (int i = 0; i < 80; ++i) donor_mask[static_cast<size_t>(i)] = 1;
    for (int i = 60; i < 90; ++i) mask[static_cast<size_t>(i)] = 1;
    ASSERT_TRUE(donor.set_mask(donor_mask, cnt));
    ASSERT_TRUE(f.set_mask(mask, cnt));
    EXPECT_EQ(donor.distance(donor_mask), 0);
    const std::vector<const cb::MaskedGramFactor*> donors{&donor, &far};
    std::vector<char> near = donor_mask;
    near[3] = 0;
    near[100] = near[101] = 1;
    ASSERT_TRUE(f.set_mask(near, cnt, &donors));
    EXPECT_EQ(f.tally().copies, 1);
    EXPECT_EQ(f.tally().refactorizations, 1);  // only the first mask
    EXPECT_EQ(f.tally().row_additions, 2);
    EXPECT_EQ(f.tally().row_deletions, 1);
    EXPECT_LE(solve_error(f, S, near, rng), 1e-10);
    EXPECT_LE(solve_error(donor, S, donor_mask, rng), 1e-10);  // the donor is untouched
    std::vector<char> away(static_cast<size_t>(k), 0);
    for (int i = 0; i < 30; ++i) away[static_cast<size_t>(i)] = 1;
    ASSERT_TRUE(f.set_mask(away, cnt, &donors));  // 53 rows from the donor: refactored
    EXPECT_EQ(f.tally().copies, 1);
    EXPECT_EQ(f.tally().refactorizations, 2);
    EXPECT_LE(solve_error(f, S, away, rng), 1e-10);
}

TEST(MaskedGramFactor, DuplicatedRowsStaySolvableWithTheShift)
{
    // Rows 0 and 1 equal: S(mask, mask) singular but for the shift 1e-12 (as mprgp-coupled adds);
    // the solve splits the multiplier and S lam = b holds to the shift's size.
    std::mt19937 rng(3);
    SpMatCol S = random_gram(20, rng);
    Eigen::MatrixXd d = Eigen::MatrixXd(S);
    d.row(1) = d.row(0);
    d.col(1) = d.col(0);
    d.diagonal().array() += 1e-12;
    S = d.sparseView();
    cb::MaskedGramFactor f(S, 4);
    cb::Counters cnt;
    std::vector<char> mask(20, 1);
    mask[0] = 0;
    ASSERT_TRUE(f.set_mask(mask, cnt));
    mask[0] = 1;  // the duplicate enters by a row addition
    ASSERT_TRUE(f.set_mask(mask, cnt));
    EXPECT_EQ(f.tally().row_additions, 1);
    Vec b = Vec::Zero(20);
    b[0] = b[1] = 1.0;
    b[5] = -0.5;
    const Vec rhs = b;
    f.solve(b.data(), cnt);
    EXPECT_LE((d * b - rhs).lpNorm<Eigen::Infinity>(), 1e-6);
    // The determined part: lam_0 + lam_1 and the other rows equal the solve without the duplicate.
    std::vector<int> keep;
    for (int i = 0; i < 20; ++i)
        if (i != 1) keep.push_back(i);
    Eigen::MatrixXd reduced(19, 19);
    Vec reduced_rhs(19);
    for (int r = 0; r < 19; ++r) {
        reduced_rhs[r] = rhs[keep[static_cast<size_t>(r)]];
        for (int c = 0; c < 19; ++c) reduced(r, c) = d(keep[static_cast<size_t>(r)], keep[static_cast<size_t>(c)]);
    }
    const Vec ref = reduced.llt().solve(reduced_rhs);
    EXPECT_NEAR(b[0] + b[1], ref[0], 1e-6 * std::abs(ref[0]));
    for (int r = 1; r < 19; ++r)
        EXPECT_NEAR(b[keep[static_cast<size_t>(r)]], ref[r], 1e-6) << "row " << keep[static_cast<size_t>(r)];
}

}  // namespace

TEST(MaskedGramFactor, ATwinWithTheCopiedAnalysisSolvesBitForBitAsAFreshFactor)
{
    // LargeBlock analyses its Gram matrix once and copies the analysis to its other factors: the same
    // masks, reached by refactorisations and row changes, give the same solves to the last bit.
    std::mt19937 rng(21);
    const int k = 140;
    const SpMatCol S = random_gram(k, rng);
    cb::MaskedGramFactor fresh(S, 8);
    cb::MaskedGramFactor twin(fresh, 8);
    cb::Counters cnt;
    std::vector<char> mask(static_cast<size_t>(k), 0);
    std::uniform_int_distribution<int> row(0, k - 1);
    std::normal_distribution<double> n01;
    for (int step = 0; step < 30; ++step) {
        const int flips = step % 6 == 5 ? 30 : 1 + step % 3;
        for (int e = 0; e < flips; ++e) mask[static_cast<size_t>(row(rng))] ^= 1;
        ASSERT_TRUE(fresh.set_mask(mask, cnt)) << "step " << step;
        ASSERT_TRUE(twin.set_mask(mask, cnt)) << "step " << step;
        std::vector<double> a(static_cast<size_t>(k), 0.0);
        for (int j = 0; j < k; ++j)
            if (mask[static_cast<size_t>(j)]) a[static_cast<size_t>(j)] = n01(rng);
        std::vector<double> b = a;
        fresh.solve(a.data(), cnt);
        twin.solve(b.data(), cnt);
        for (int j = 0; j < k; ++j) ASSERT_EQ(a[static_cast<size_t>(j)], b[static_cast<size_t>(j)]) << "step " << step;
        EXPECT_LE(solve_error(twin, S, mask, rng), 1e-10) << "step " << step;
    }
    EXPECT_GT(twin.tally().row_additions, 5);
    EXPECT_GT(twin.tally().refactorizations, 2);
    EXPECT_THROW(cb::MaskedGramFactor late(fresh, 8), std::logic_error);  // a factored twin is refused
}
