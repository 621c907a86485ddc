// An AOperator made from a QP whose reader established A = A' to the bit (Qp::a_symmetric): SBSR
// skips the mirror check and reads each row from its block diagonal on, and with a scaling it
// scales the blocks as it builds them; the blocks are those of the checked build, scaled after it,
// to the last bit.
#include "problems/synthetic.hpp"
#include "solvers/linalg/a_product.hpp"
#include "tests/perf/fem_grid.hpp"
#include "tests/perf/varied_vector.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <random>

using namespace cb;

namespace {

/// The QP view of A alone, its symmetry known or not.
struct KnownSymmetryView {
    Vec b, c, x0;
    SpMat J;
    QpView view(const SpMat& A, bool symmetric)
    {
        b = Vec::Zero(A.rows());
        x0 = Vec::Zero(A.rows());
        return QpView{A, b, J, c, x0, nullptr, nullptr, symmetric};
    }
};

/// Whether two operators store the same blocks, every value to the bit.
void expect_same_blocks(const AOperator& a, const AOperator& b, const std::string& what)
{
    EXPECT_EQ(a.blocks().start, b.blocks().start) << what;
    EXPECT_EQ(a.blocks().column, b.blocks().column) << what;
    ASSERT_EQ(a.blocks().value.size(), b.blocks().value.size()) << what;
    EXPECT_EQ(std::memcmp(a.blocks().value.data(), b.blocks().value.data(), a.blocks().value.size() * sizeof(double)),
              0)
        << what;
    EXPECT_EQ(a.blocks_scaled(), b.blocks_scaled()) << what;
}

/// A symmetric A of 3x3 blocks with about one entry in twenty absent (rows that are not whole
/// groups) and some stored zeros, one of them without a stored mirror.
SpMat scattered_symmetric(int blocks, unsigned seed)
{
    std::mt19937 rng(seed);
    std::uniform_int_distribution<int> block(0, blocks - 1), twentieth(0, 19);
    std::uniform_real_distribution<double> value(-1.0, 1.0);
    std::vector<Eigen::Triplet<double>> t;
    const int n = 3 * blocks;
    t.reserve(static_cast<size_t>(n) + 72 * static_cast<size_t>(blocks) + 1);
    for (int i = 0; i < n; ++i) t.emplace_back(i, i, 8.0 + value(rng));
    for (int e = 0; e < 4 * blocks; ++e) {
        const int I = block(rng), J = block(rng);
        if (I == J) continue;
        for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 3; ++c) {
                const int k = twentieth(rng);
                if (k == 0) continue;  // absent on both sides
                const double v = k == 1 ? 0.0 : value(rng);
                t.emplace_back(3 * I + r, 3 * J + c, v);
                t.emplace_back(3 * J + c, 3 * I + r, v);
            }
    }
    t.emplace_back(0, n - 1, 0.0);  // a stored zero above, none below
    SpMat A(n, n);
    A.setFromTriplets(t.begin(), t.end());
    A.makeCompressed();
    return A;
}

}  // namespace

TEST(AOperatorKnownSymmetry, BuildsTheCheckedBuildsBlocksWithoutTheMirrorCheck)
{
    std::vector<std::pair<std::string, SpMat>> cases;
    cases.emplace_back("fem grid", test::fem_grid(9, 7, 6));
    cases.emplace_back("scattered", scattered_symmetric(40, 3));
    for (const std::string& family : synthetic_families()) {
        const Qp qp = make_synthetic(family, nlohmann::json::object(), 7);
        if (qp.n() % 3 == 0) cases.emplace_back(family, qp.A);
    }
    for (const auto& [name, A] : cases) {
        SCOPED_TRACE(name);
        KnownSymmetryView v;
        const Vec u = A.diagonal().cwiseAbs().cwiseSqrt().cwiseInverse();
        AOperator checked(v.view(A, false)), known(v.view(A, true));
        ASSERT_EQ(checked.prepare(AFormat::SBSR), AFormat::SBSR) << checked.why_csr();
        ASSERT_EQ(known.prepare(AFormat::SBSR), AFormat::SBSR) << known.why_csr();
        EXPECT_TRUE(checked.mirror_checked());
        EXPECT_FALSE(known.mirror_checked());
        expect_same_blocks(checked, known, "unscaled");
        EXPECT_EQ(checked.fill(), known.fill());
        // Scaled in the build (the scaling known before prepare) against scaled after it.
        AOperator checked_scaled(v.view(A, false)), known_scaled(v.view(A, true));
        checked_scaled.scale_by(&u);
        known_scaled.scale_by(&u);
        ASSERT_EQ(checked_scaled.prepare(AFormat::SBSR), AFormat::SBSR);
        ASSERT_EQ(known_scaled.prepare(AFormat::SBSR), AFormat::SBSR);
        expect_same_blocks(checked_scaled, known_scaled, "scaled in the build");
        known.scale_by(&u);  // after prepare: the blocks scaled in place
        expect_same_blocks(known, known_scaled, "scaled after prepare");
        known_scaled.scale_by(nullptr);  // back to A's own blocks (rebuilt)
        expect_same_blocks(checked, known_scaled, "unscaled again");
        // The products read them alike.
        const Vec x = test::varied(A.cols(), 5);
        Vec y_checked, y_known;
        a_product(checked_scaled, x, y_checked);
        a_product(known, x, y_known);
        EXPECT_EQ((y_checked - y_known).lpNorm<Eigen::Infinity>(), 0.0);
    }
}

// The flag is trusted, not checked: it must come from code that made A symmetric (the readers).
// Without it an asymmetric A is still refused SBSR, and AUTO keeps BSR.
TEST(AOperatorKnownSymmetry, OnlyAnAOfUnknownSymmetryIsChecked)
{
    SpMat A = test::fem_grid(3, 3, 3);
    const int k = A.outerIndexPtr()[7];  // row 7's first entry, left of its diagonal block
    ASSERT_LT(A.innerIndexPtr()[k], 6);
    const std::string column = std::to_string(A.innerIndexPtr()[k]);
    A.valuePtr()[k] += 1.0;  // it no longer equals its mirror
    KnownSymmetryView v;
    AOperator checked(v.view(A, false)), from_csr(A), known(v.view(A, true));
    EXPECT_EQ(checked.prepare(AFormat::SBSR), AFormat::CSR);
    EXPECT_EQ(checked.why_csr(), "A is not symmetric (entry (7, " + column + ") differs from (" + column + ", 7))");
    EXPECT_TRUE(checked.mirror_checked());
    EXPECT_EQ(from_csr.prepare(AFormat::SBSR), AFormat::CSR);
    EXPECT_TRUE(from_csr.mirror_checked());
    EXPECT_EQ(known.prepare(AFormat::SBSR), AFormat::SBSR);  // what a wrong flag would do
    EXPECT_FALSE(known.mirror_checked());
    EXPECT_EQ(checked.prepare(AFormat::BSR), AFormat::BSR);
    EXPECT_FALSE(checked.mirror_checked());  // BSR reads all of A: nothing to check
}
