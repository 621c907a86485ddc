// sorted_rows_diagonal (solvers/linalg/row_search.hpp), precond = scaled's diag(A), against Eigen's
// A.diagonal(): the same values to the bit, absent diagonal entries 0, on matrices shorter and
// longer than the prefetch distance, uncompressed and non-square ones.
#include "problems/synthetic.hpp"
#include "solvers/linalg/row_search.hpp"

#include <gtest/gtest.h>

#include <random>

using namespace cb;

namespace {

/// A random sparse rows x cols matrix with sorted rows; some diagonal entries absent, one stored 0.
SpMat row_search_random_matrix(int rows, int cols, unsigned seed)
{
    std::mt19937 rng(seed);
    std::uniform_int_distribution<int> col(0, cols - 1);
    std::uniform_real_distribution<double> value(-2.0, 2.0);
    std::vector<Eigen::Triplet<double>> t;
    for (int i = 0; i < rows; ++i) {
        if (i % 5 != 3 && i < cols) t.emplace_back(i, i, i % 7 == 2 ? 0.0 : value(rng));
        for (int e = 0; e < 6; ++e) t.emplace_back(i, col(rng), value(rng));
    }
    SpMat A(rows, cols);
    A.setFromTriplets(t.begin(), t.end());
    A.makeCompressed();
    return A;
}

void expect_row_search_diagonal(const SpMat& A, const std::string& what)
{
    const Vec expected = A.diagonal();
    const Vec got = sorted_rows_diagonal(A);
    ASSERT_EQ(got.size(), expected.size()) << what;
    long differing = 0;
    for (Eigen::Index i = 0; i < got.size(); ++i) differing += got[i] != expected[i];
    EXPECT_EQ(differing, 0) << what;
}

}  // namespace

TEST(SortedRowsDiagonal, EqualsEigensDiagonalToTheBit)
{
    for (const std::string& family : synthetic_families())
        expect_row_search_diagonal(make_synthetic(family, nlohmann::json::object(), 7).A, family);
    for (const int n : {5, 16, 17, 200}) {
        const SpMat A = row_search_random_matrix(n, n, static_cast<unsigned>(n));
        expect_row_search_diagonal(A, "random n = " + std::to_string(n));
    }
}

TEST(SortedRowsDiagonal, HandlesAbsentEntriesUncompressedAndNonSquareMatrices)
{
    const SpMat A = row_search_random_matrix(40, 40, 3);
    ASSERT_EQ(A.coeff(3, 3), 0.0);  // absent
    EXPECT_EQ(sorted_rows_diagonal(A)[3], 0.0);
    SpMat uncompressed = A;
    uncompressed.coeffRef(8, 1) = 9.0;  // an insertion leaves it uncompressed
    ASSERT_FALSE(uncompressed.isCompressed());
    expect_row_search_diagonal(uncompressed, "uncompressed");
    expect_row_search_diagonal(row_search_random_matrix(30, 50, 4), "wide");
    expect_row_search_diagonal(row_search_random_matrix(50, 30, 5), "tall");
}
