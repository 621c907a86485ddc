// Synthetic families: symmetric SPD A, the promised row structure, seeded reproducibility.
#include "problems/qpsnap.hpp"
#include "problems/synthetic.hpp"
#include "tests/problems/file_bytes.hpp"

#include <Eigen/Dense>
#include <Eigen/SparseCholesky>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <set>
#include <unistd.h>

namespace cb {
namespace {

std::string synthetic_temp_path(const std::string& name)
{
    const auto dir = std::filesystem::temp_directory_path() / ("cb_test_synthetic_" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir);
    return (dir / name).string();
}

/// Largest |A(i,j) - A(j,i)| (exact comparison: 0 for an exactly symmetric matrix).
double asymmetry(const SpMat& A)
{
    const SpMat At = A.transpose();
    const SpMat D = A - At;
    return D.nonZeros() ? D.coeffs().cwiseAbs().maxCoeff() : 0.0;
}

bool is_spd(const SpMat& A)
{
    const SpMatCol Ac = A;
    Eigen::SimplicialLLT<SpMatCol> llt(Ac);
    return llt.info() == Eigen::Success;
}

Vec unconstrained_minimiser(const Qp& qp)
{
    const SpMatCol Ac = qp.A;
    Eigen::SimplicialLLT<SpMatCol> llt(Ac);
    return llt.solve(qp.b);
}

long count_violated(const Qp& qp, const Vec& x, double slack = 0.0)
{
    const Vec r = qp.J * x - qp.c;
    return long((r.array() < -slack).count());
}

TEST(FemLikeMatrix, SizeStencilSymmetryAndSpd)
{
    FemGridParams p;
    p.nx = 3, p.ny = 2, p.nz = 4;
    const SpMat A = fem_like_matrix(p);
    ASSERT_EQ(A.rows(), 3 * 4 * 3 * 5);
    ASSERT_EQ(A.cols(), A.rows());
    EXPECT_TRUE(A.isCompressed());
    EXPECT_EQ(asymmetry(A), 0.0);
    EXPECT_TRUE(is_spd(A));
    // An interior vertex (1,1,1) touches 15 vertices (Kuhn stencil): 45 nonzeros per row.
    const int v = 1 + 4 * (1 + 3 * 1);
    EXPECT_EQ(A.outerIndexPtr()[3 * v + 1] - A.outerIndexPtr()[3 * v], 45);
    // Rigid translation: K t = 0, so A t = M t; the total mass is density * volume.
    Vec t = Vec::Zero(A.rows());
    for (Eigen::Index i = 0; i < t.size(); i += 3) t[i] = 1.0;
    const double total_mass = t.dot(A * t);
    EXPECT_NEAR(total_mass, p.density * 3 * 2 * 4 * std::pow(p.spacing, 3), 1e-9);
}

TEST(FemLikeMatrix, StiffMaterialStaysSpd)
{
    FemGridParams p;
    p.nx = p.ny = p.nz = 3;
    p.youngs = 1e12;
    const SpMat A = fem_like_matrix(p);
    EXPECT_EQ(asymmetry(A), 0.0);
    EXPECT_TRUE(is_spd(A));
}

TEST(FemLikeMatrix, BadParameterIsInputError)
{
    FemGridParams p;
    p.poisson = 0.5;
    try {
        fem_like_matrix(p);
        FAIL() << "no error";
    } catch (const InputError& e) {
        EXPECT_STREQ(e.what(), "fem_like_matrix: poisson: expected a value in (-1, 0.5), got 0.5");
    }
}

TEST(Synthetic, FamiliesSortedWithHelp)
{
    const auto f = synthetic_families();
    EXPECT_TRUE(std::is_sorted(f.begin(), f.end()));
    for (const char* name : {"unconstrained", "plane", "box", "coupled", "random-spd", "infeasible", "duplicate-rows",
                             "scaled-rows", "zero-rows"})
        EXPECT_NE(std::find(f.begin(), f.end(), name), f.end()) << name;
    EXPECT_NE(synthetic_family_help("plane").find("tilt_deg"), std::string::npos);
}

TEST(Synthetic, UnknownFamilyAndParameter)
{
    try {
        make_synthetic("planar", {}, 1);
        FAIL();
    } catch (const InputError& e) {
        EXPECT_EQ(std::string(e.what()).rfind("synthetic: family: unknown family 'planar'; known: box, coupled", 0), 0u)
            << e.what();
    }
    try {
        make_synthetic("box", {{"tilt_deg", 3}}, 1);
        FAIL();
    } catch (const InputError& e) {
        EXPECT_EQ(
            std::string(e.what()).rfind("synthetic family 'box': params.tilt_deg: unknown parameter; known: nx, ny", 0),
            0u)
            << e.what();
    }
    try {
        make_synthetic("plane", {{"nx", 2.5}}, 1);
        FAIL();
    } catch (const InputError& e) {
        EXPECT_STREQ(e.what(), "synthetic family 'plane': params.nx: expected an integer, got 2.5");
    }
}

TEST(Synthetic, UnconstrainedHasNoRows)
{
    const Qp qp = make_synthetic("unconstrained", {{"nx", 2}, {"ny", 2}, {"nz", 2}}, 3);
    EXPECT_EQ(qp.m(), 0);
    EXPECT_EQ(qp.J.cols(), qp.n());
    EXPECT_EQ(qp.c.size(), 0);
    EXPECT_TRUE(qp.contacts.empty());
    EXPECT_EQ(asymmetry(qp.A), 0.0);
    EXPECT_TRUE(is_spd(qp.A));
}

TEST(Synthetic, PlaneIsARealisticContactQp)
{
    const Qp qp = make_synthetic("plane", {}, 7);
    ASSERT_EQ(qp.n(), 3 * 125);
    EXPECT_EQ(asymmetry(qp.A), 0.0);
    EXPECT_TRUE(is_spd(qp.A));
    // Two vertex layers within the margin, the bottom 25 vertices penetrating at x0.
    EXPECT_EQ(qp.m(), 50);
    EXPECT_EQ(count_violated(qp, qp.x0), 25);
    // The unconstrained minimiser penetrates too (gravity and momentum push the body down).
    EXPECT_EQ(count_violated(qp, unconstrained_minimiser(qp)), 25);
    // Decoupled: 3 nnz per row, no DOF in two rows; contact data of size m.
    std::set<int> cols;
    for (Eigen::Index r = 0; r < qp.m(); ++r) {
        EXPECT_EQ(qp.J.outerIndexPtr()[r + 1] - qp.J.outerIndexPtr()[r], 3);
        for (SpMat::InnerIterator it(qp.J, r); it; ++it) EXPECT_TRUE(cols.insert(int(it.col())).second);
        EXPECT_EQ(qp.contacts.kind[r], std::int64_t(ContactKind::PLANE));
        EXPECT_EQ(qp.contacts.vertex[4 * r + 1], -1);
        EXPECT_EQ(qp.J.coeff(r, 3 * qp.contacts.vertex[4 * r] + 1), 1.0);
    }
    ASSERT_EQ(qp.contacts.depth.size(), size_t(qp.m()));
    EXPECT_GT(*std::max_element(qp.contacts.depth.begin(), qp.contacts.depth.end()), 0.005);
    EXPECT_EQ(qp.meta["generator"]["family"], "plane");
    EXPECT_EQ(qp.meta["units"], "SI");
}

TEST(Synthetic, TiltedPlaneHasUnitNormals)
{
    const Qp qp = make_synthetic("plane", {{"tilt_deg", 20}}, 1);
    ASSERT_GT(qp.m(), 0);
    for (Eigen::Index r = 0; r < qp.m(); ++r) EXPECT_NEAR(qp.J.row(r).norm(), 1.0, 1e-15);
    EXPECT_GT(count_violated(qp, qp.x0), 0);
}

TEST(Synthetic, BoxRowsAreSignedUnitVectors)
{
    const Qp qp = make_synthetic("box", {{"nx", 3}, {"ny", 3}, {"nz", 3}}, 5);
    ASSERT_GT(qp.m(), 10);
    for (Eigen::Index r = 0; r < qp.m(); ++r) {
        ASSERT_EQ(qp.J.outerIndexPtr()[r + 1] - qp.J.outerIndexPtr()[r], 1);
        EXPECT_EQ(std::abs(qp.J.valuePtr()[qp.J.outerIndexPtr()[r]]), 1.0);
    }
    const long violated = count_violated(qp, unconstrained_minimiser(qp), 1e-9);
    EXPECT_GT(violated, qp.m() / 4);
    EXPECT_LT(violated, 3 * qp.m() / 4);
}

TEST(Synthetic, CoupledRowsHaveTwelveNonzerosAndShareVertices)
{
    const Qp qp = make_synthetic("coupled", {}, 11);
    EXPECT_EQ(asymmetry(qp.A), 0.0);
    EXPECT_TRUE(is_spd(qp.A));
    ASSERT_EQ(qp.m(), 25);
    EXPECT_EQ(qp.c.cwiseAbs().maxCoeff(), 0.0);
    std::map<std::int64_t, int> uses;
    for (Eigen::Index r = 0; r < qp.m(); ++r) {
        EXPECT_EQ(qp.J.outerIndexPtr()[r + 1] - qp.J.outerIndexPtr()[r], 12);
        EXPECT_EQ(qp.contacts.kind[r], std::int64_t(ContactKind::INTER_BODY));
        // n'(x_i - sum w x): the weights sum to one, so J annihilates rigid translations.
        Vec t = Vec::Zero(qp.n());
        for (Eigen::Index i = 0; i < t.size(); i += 3) t[i] = 1.0, t[i + 1] = 2.0, t[i + 2] = -0.5;
        EXPECT_NEAR(qp.J.row(r).dot(t.transpose()), 0.0, 1e-14);
        for (int k = 0; k < 4; ++k) ++uses[qp.contacts.vertex[4 * r + k]];
    }
    int shared = 0;
    for (const auto& kv : uses) shared += kv.second > 1;
    EXPECT_GT(shared, 5);
    EXPECT_GT(count_violated(qp, qp.x0), 10);
}

TEST(Synthetic, RandomSpdHasTheRequestedCondition)
{
    const Qp qp = make_synthetic("random-spd", {{"n", 40}, {"m", 10}, {"condition", 1e6}}, 2);
    EXPECT_EQ(asymmetry(qp.A), 0.0);
    const Eigen::MatrixXd D(qp.A);
    const Vec eig = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(D).eigenvalues();
    EXPECT_NEAR(eig.maxCoeff() / eig.minCoeff(), 1e6, 1e6 * 1e-6);
    EXPECT_EQ(qp.m(), 10);
}

TEST(Synthetic, InfeasibleHasContradictoryPair)
{
    const Qp qp = make_synthetic("infeasible", {{"nx", 2}, {"ny", 2}, {"nz", 2}}, 4);
    const Eigen::Index m = qp.m();
    ASSERT_GE(m, 2);
    const SpMat J = qp.J;
    ASSERT_EQ(J.row(m - 2).nonZeros(), 1);
    ASSERT_EQ(J.row(m - 1).nonZeros(), 1);
    const int col = J.innerIndexPtr()[J.outerIndexPtr()[m - 2]];
    EXPECT_EQ(J.innerIndexPtr()[J.outerIndexPtr()[m - 1]], col);
    EXPECT_EQ(J.coeff(m - 2, col), 1.0);
    EXPECT_EQ(qp.c[m - 2], 1.0);
    EXPECT_EQ(J.coeff(m - 1, col), -1.0);
    EXPECT_EQ(qp.c[m - 1], 0.0);
}

TEST(Synthetic, RowVariants)
{
    const nlohmann::json small = {{"nx", 3}, {"ny", 2}, {"nz", 3}};
    const Qp plane = make_synthetic("plane", small, 9);
    const Qp dup = make_synthetic("duplicate-rows", small, 9);
    EXPECT_GT(dup.m(), plane.m());
    int repeats = 0;
    for (Eigen::Index r = 1; r < dup.m(); ++r)
        repeats +=
            Vec(dup.J.row(r).transpose()).isApprox(Vec(dup.J.row(r - 1).transpose()), 0.0) && dup.c[r] == dup.c[r - 1];
    EXPECT_EQ(repeats, dup.m() - plane.m());
    nlohmann::json zero = small;
    zero["count"] = 4;
    const Qp z = make_synthetic("zero-rows", zero, 9);
    EXPECT_EQ(z.m(), plane.m() + 4);
    int empty = 0;
    for (Eigen::Index r = 0; r < z.m(); ++r) empty += z.J.outerIndexPtr()[r + 1] == z.J.outerIndexPtr()[r];
    EXPECT_EQ(empty, 4);
    nlohmann::json sc = small;
    sc["row_scale"] = 1e4;
    const Qp s = make_synthetic("scaled-rows", sc, 9);
    ASSERT_EQ(s.m(), plane.m());
    double lo = 1e300, hi = 0;
    for (Eigen::Index r = 0; r < s.m(); ++r) lo = std::min(lo, s.J.row(r).norm()), hi = std::max(hi, s.J.row(r).norm());
    EXPECT_GT(hi / lo, 100.0);
    EXPECT_LE(hi, 1e4 * (1 + 1e-12));
    EXPECT_GE(lo, 1e-4 * (1 - 1e-12));
}

TEST(Synthetic, UnitScalesChangeNumbersNotTheSolution)
{
    const nlohmann::json si = {{"nx", 2}, {"ny", 2}, {"nz", 2}};
    nlohmann::json mm = si;
    mm["length_scale"] = 1e-3;
    mm["mass_scale"] = 1e-3;
    const Qp a = make_synthetic("plane", si, 3), b = make_synthetic("plane", mm, 3);
    EXPECT_NEAR((b.x0 - 1e3 * a.x0).cwiseAbs().maxCoeff(), 0.0, 1e-9);
    const Vec xa = unconstrained_minimiser(a), xb = unconstrained_minimiser(b);
    EXPECT_LT((xb - 1e3 * xa).cwiseAbs().maxCoeff(), 1e-8);
    EXPECT_EQ(b.meta["units"]["length_m"], 1e-3);
}

TEST(Synthetic, SameSeedSameBytesOtherSeedOtherBytes)
{
    for (const char* family : {"plane", "coupled", "box", "random-spd"}) {
        const std::string p1 = synthetic_temp_path(std::string(family) + "_1.qpsnap");
        const std::string p2 = synthetic_temp_path(std::string(family) + "_2.qpsnap");
        const std::string p3 = synthetic_temp_path(std::string(family) + "_3.qpsnap");
        write_qpsnap(p1, make_synthetic(family, {}, 42));
        write_qpsnap(p2, make_synthetic(family, {}, 42));
        write_qpsnap(p3, make_synthetic(family, {}, 43));
        EXPECT_EQ(test::file_bytes(p1), test::file_bytes(p2)) << family;
        EXPECT_NE(test::file_bytes(p1), test::file_bytes(p3)) << family;
        const Qp back = read_qpsnap(p1);  // every family passes the reader's validation
        EXPECT_EQ(back.meta["generator"]["seed"], 42);
    }
}

}  // namespace
}  // namespace cb
