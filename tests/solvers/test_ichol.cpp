// Tests of precond = ichol (solvers/linalg/ichol.hpp): the face matrix and the face preconditioner on
// decoupled rows, and cg / mprgp with it (counters, convergence on a stiff case).
#include "harness/stress_families.hpp"
#include "problems/synthetic.hpp"
#include "solvers/core/registry.hpp"
#include "solvers/linalg/ichol.hpp"
#include "solvers/measure/accuracy.hpp"
#include "tests/solvers/dual_test_problems.hpp"

#include <Eigen/SparseCholesky>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

namespace {

using cb::Qp;
using cb::SolveStatus;
using cb::Vec;

/// A stiff body on the ground with every other row of J active at x0 (x0 moved onto them).
struct FaceFixture {
    Qp qp;
    cb::DecoupledRows rows;
    std::vector<char> active;
    FaceFixture()
    {
        qp = cb::make_synthetic("plane", {{"youngs", 1e10}}, 1);
        rows = cb::make_decoupled_rows(qp.J, Vec::Ones(qp.n()));
        active.assign(static_cast<size_t>(qp.m()), 0);
        for (Eigen::Index i = 0; i < qp.m(); i += 2) active[static_cast<size_t>(i)] = 1;
    }
    double row_dot(Eigen::Index i, const Vec& v) const { return cb::row_dot(qp.J, i, v); }
};

TEST(IcholFace, FaceMatrixInverseKeepsTheFaceAndInvertsQAQOnIt)
{
    FaceFixture f;
    ASSERT_GT(f.qp.m(), 4);
    const cb::SpMat B = cb::face_matrix(f.qp.A, f.qp.J, f.rows, f.active);
    EXPECT_LE((cb::SpMat(B.transpose()) - B).norm(), 1e-12 * B.norm());
    // phi = Q g for a random g; B^-1 phi must lie in the face and solve (Q A Q) w = phi there.
    Vec g = Vec::LinSpaced(f.qp.n(), -1.0, 2.0);
    Vec phi;
    cb::free_gradient(f.qp.J, f.rows, f.active, g, phi);
    const cb::SpMatCol B_col(B);
    Eigen::SimplicialLDLT<cb::SpMatCol> ldlt(B_col);
    ASSERT_EQ(ldlt.info(), Eigen::Success);
    const Vec w = ldlt.solve(phi);
    for (Eigen::Index i = 0; i < f.qp.m(); ++i)
        if (f.active[static_cast<size_t>(i)]) {
            EXPECT_LE(std::abs(f.row_dot(i, w)), 1e-9 * w.norm()) << "row " << i;
        }
    Vec Aw = f.qp.A * w, QAw;
    cb::free_gradient(f.qp.J, f.rows, f.active, Aw, QAw);
    EXPECT_LE((QAw - phi).norm(), 1e-8 * phi.norm());
}

TEST(IcholFace, PreconditionedDirectionStaysOnTheFaceAndDescends)
{
    FaceFixture f;
    cb::IncompleteCholeskyPreconditioner ic;
    std::string error;
    ASSERT_TRUE(ic.factor(cb::face_matrix(f.qp.A, f.qp.J, f.rows, f.active), error)) << error;
    EXPECT_GT(ic.factor_nonzeros(), f.qp.n());
    const Vec g = f.qp.A * f.qp.x0 - f.qp.b;
    Vec work(f.qp.n()), z;
    cb::ichol_face_precondition(ic, f.qp.J, f.rows, f.active, g, work, z);
    for (Eigen::Index i = 0; i < f.qp.m(); ++i)
        if (f.active[static_cast<size_t>(i)]) {
            EXPECT_LE(std::abs(f.row_dot(i, z)), 1e-12 * z.norm()) << "row " << i;
        }
    EXPECT_GT(z.dot(g), 0.0);  // a descent direction: Q M^-1 Q is positive definite on the face
}

TEST(IcholCg, CountsOneFactorizationOfAsManyNonzerosAsTheLowerTriangle)
{
    const Qp qp = cb::make_synthetic("plane", {{"youngs", 1e10}}, 1);
    auto run = [&](const std::string& precond) {
        return cb::builtin_registry()
            .create("cg", {{"precond", precond}, {"tol", 1e-8}, {"start", "zero"}, {"max_iterations", 20000}})
            ->solve(qp.view(), {});
    };
    const cb::SolverResult jacobi = run("jacobi");
    const cb::SolverResult ichol = run("ichol");
    ASSERT_EQ(jacobi.status, SolveStatus::CONVERGED) << jacobi.message;
    ASSERT_EQ(ichol.status, SolveStatus::CONVERGED) << ichol.message;
    EXPECT_EQ(ichol.counters.precond_factorizations, 1);
    EXPECT_EQ(jacobi.counters.precond_factorizations, 0);
    EXPECT_GE(ichol.counters.precond_applications, ichol.iterations + 1);
    // Eigen's IC keeps as many entries per column as A's lower triangle has: memory = that of A's half.
    EXPECT_EQ(ichol.info["ichol"]["factor_nonzeros"].get<long>(), (qp.A.nonZeros() + qp.n()) / 2);
}

/// The Done-when of issue 17 on the stiff synthetic family: mprgp with ichol reaches 1e-8
/// (today's relative KKT) in at most 2x the iterations cg with ichol needs on the same A
/// (from x = 0, its own relative residual), with an honest status.
class IcholStiffFamily : public ::testing::TestWithParam<const char*> {};

TEST_P(IcholStiffFamily, MprgpWithinTwiceCg)
{
    const auto cases = cb::select_stress_cases(cb::stress_cases(false), {GetParam()});
    const Qp qp = cb::make_stress_qp(cases.at(0));
    const cb::SolverResult cg =
        cb::builtin_registry()
            .create("cg", {{"precond", "ichol"}, {"tol", 1e-8}, {"start", "zero"}, {"max_iterations", 20000}})
            ->solve(qp.view(), {});
    const cb::SolverResult mp = cb::builtin_registry()
                                    .create("mprgp", {{"precond", "ichol"}, {"tol", 1e-8}, {"max_iterations", 20000}})
                                    ->solve(qp.view(), {});
    ASSERT_EQ(cg.status, SolveStatus::CONVERGED) << cg.message;
    ASSERT_EQ(mp.status, SolveStatus::CONVERGED) << mp.message;
    EXPECT_LE(cb::test::relative_kkt(qp, mp.x, mp.lambda), 1e-8);
    EXPECT_LE(mp.iterations, 2 * cg.iterations) << "mprgp " << mp.iterations << ", cg " << cg.iterations;
    EXPECT_GE(mp.counters.precond_factorizations, 1);
    std::printf(
        "%s: cg ichol %ld iterations, mprgp ichol %ld (%ld factorizations, %ld expansions, %ld proportionings)\n",
        GetParam(), cg.iterations, mp.iterations, mp.counters.precond_factorizations, mp.counters.expansion_steps,
        mp.counters.proportioning_steps);
}

INSTANTIATE_TEST_SUITE_P(Stiffness, IcholStiffFamily,
                         ::testing::Values("stiffness-1e4", "stiffness-1e8", "stiffness-1e10", "stiffness-1e12",
                                           "slab-stiff-1e10", "slab-stiff-1e12"));

TEST(IcholReproducer, SlabIsAtTheSnapshotsScale)
{
    const Qp qp = cb::make_stress_qp(cb::select_stress_cases(cb::stress_cases(false), {"slab-stiff-1e10"}).at(0));
    EXPECT_EQ(qp.n(), 4335);  // 1445 vertices
    EXPECT_EQ(qp.m(), 289);   // the bottom face's vertex-plane rows
    EXPECT_GT(cb::max_violation(qp.view(), qp.x0), 0.0);
}

}  // namespace
