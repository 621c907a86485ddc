// DenseSetFactor (solvers/linalg/dense_set_factor.hpp): after any sequence of sets, reached by row
// appends, deletions at any position or a fresh factor, its solve equals a dense LLT solve on
// S(set, set); sets above the capacity and non-positive pivots are refused.
#include "set_solve_check.hpp"
#include "solvers/linalg/dense_set_factor.hpp"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <random>

namespace {

using cb::SpMatCol;
using cb::Vec;
using cb::set_solve_check::random_gram;
using cb::set_solve_check::solve_error;

TEST(DenseSetFactor, AppendedDeletedAndFreshFactorsSolveAsDenseOnEverySet)
{
    std::mt19937 rng(7);
    const int k = 200;
    const SpMatCol S = random_gram(k, rng);
    cb::DenseSetFactor f(S, 64);
    cb::Counters cnt;
    std::vector<char> mask(static_cast<size_t>(k), 0);
    std::uniform_int_distribution<int> row(0, k - 1);
    int in = 0;
    for (int step = 0; step < 80; ++step) {
        // A few rows in or out per step (appends and deletions anywhere in the factor's order),
        // every twentieth step a new set (a fresh factor); sets stay within the capacity.
        const int flips = step % 20 == 19 ? 60 : 1 + step % 4;
        for (int e = 0; e < flips; ++e) {
            const auto r = static_cast<size_t>(row(rng));
            if (!mask[r] && in >= 60) continue;
            in += mask[r] ? -1 : 1;
            mask[r] ^= 1;
        }
        ASSERT_TRUE(f.set_mask(mask, cnt)) << "step " << step;
        EXPECT_EQ(f.size(), in);
        EXPECT_LE(solve_error(f, S, mask, rng), 1e-10) << "step " << step;
    }
    EXPECT_GT(f.appends(), 100);
    EXPECT_GT(f.removals(), 50);
    EXPECT_GE(f.rebuilds(), 1);
}

TEST(DenseSetFactor, RefusesSetsAboveItsCapacityAndNonPositivePivots)
{
    std::mt19937 rng(9);
    const SpMatCol S = random_gram(40, rng);
    cb::DenseSetFactor f(S, 10);
    cb::Counters cnt;
    std::vector<char> mask(40, 0);
    for (int i = 0; i < 11; ++i) mask[static_cast<size_t>(i)] = 1;
    EXPECT_FALSE(f.set_mask(mask, cnt));  // 11 rows, capacity 10
    mask[10] = 0;
    ASSERT_TRUE(f.set_mask(mask, cnt));
    EXPECT_LE(solve_error(f, S, mask, rng), 1e-10);
    // Rows 0 and 1 equal without a shift: S(set, set) singular, the second one's pivot is 0.
    Eigen::MatrixXd d = Eigen::MatrixXd(S);
    d.row(1) = d.row(0);
    d.col(1) = d.col(0);
    const SpMatCol singular = d.sparseView();
    cb::DenseSetFactor g(singular, 10);
    std::vector<char> pair(40, 0);
    pair[0] = pair[1] = 1;
    EXPECT_FALSE(g.set_mask(pair, cnt));
    pair[1] = 0;
    ASSERT_TRUE(g.set_mask(pair, cnt));  // a refused set leaves nothing half-factored
    EXPECT_EQ(g.size(), 1);
    EXPECT_LE(solve_error(g, singular, pair, rng), 1e-12);
}

}  // namespace
