// Tests of the work unit (solvers/measure/work_units.hpp, docs/work.md): the flop counts CHOLMOD reports,
// their conversion to A-product equivalents, and the work each solver counts.
#include "solvers/core/registry.hpp"
#include "solvers/linalg/ichol.hpp"
#include "solvers/measure/work_units.hpp"
#include "tests/solvers/dual_test_problems.hpp"

#include <Eigen/CholmodSupport>
#include <gtest/gtest.h>

namespace cb {
namespace {

/// The n x n tridiagonal SPD matrix tridiag(-1, 4, -1): its Cholesky factor has no fill, so
/// nnz(L) = 2n - 1 and the column counts (diagonal included) are 2, ..., 2, 1.
SpMat tridiagonal(int n)
{
    std::vector<Triplet> t;
    for (int i = 0; i < n; ++i) {
        t.emplace_back(i, i, 4.0);
        if (i + 1 < n) {
            t.emplace_back(i, i + 1, -1.0);
            t.emplace_back(i + 1, i, -1.0);
        }
    }
    SpMat A(n, n);
    A.setFromTriplets(t.begin(), t.end());
    return A;
}

TEST(WorkUnits, OneUnitIsOneProductWithA)
{
    const SpMat A = tridiagonal(10);  // 28 nonzeros
    EXPECT_EQ(a_product_flops(A), 56.0);
    Counters c;
    c.a_products = 3;
    c.work_flops = 28.0;
    EXPECT_DOUBLE_EQ(work_units(c, A), 3.5);
    EXPECT_EQ(a_product_flops(SpMat(0, 0)), 1.0);  // an empty A divides safely
}

TEST(WorkUnits, CholmodReportsFlopsAndNonzerosOfTheFactor)
{
    const SpMat A = tridiagonal(10);
    Eigen::CholmodSupernodalLLT<SpMatCol, Eigen::Lower> llt;
    llt.compute(SpMatCol(A));
    ASSERT_EQ(llt.info(), Eigen::Success);
    EXPECT_EQ(llt.cholmod().lnz, 19.0);
    EXPECT_EQ(cholmod_factor_flops(llt.cholmod()), 9 * 2.0 * 2.0 + 1.0);  // sum of squared column counts
    EXPECT_EQ(cholmod_solve_flops(llt.cholmod(), 3), 3 * 4.0 * 19.0);
}

TEST(WorkUnits, DenseKernels)
{
    EXPECT_EQ(dense_matvec_flops(3, 5), 30.0);
    EXPECT_EQ(dense_triangular_solve_flops(7), 49.0);
    EXPECT_EQ(sparse_product_flops(11, 2), 44.0);
}

TEST(WorkUnits, SolversWithFactorisationsCountMoreThanTheirAProducts)
{
    const Qp qp = test::make_grid_qp(test::GridQpParams{});
    for (const char* name : {"pgs", "active-set"}) {
        const SolverResult r = builtin_registry().create(name, {})->solve(qp.view(), SolveContext{});
        ASSERT_EQ(r.status, SolveStatus::CONVERGED) << name << ": " << r.message;
        // At least the factorisation of A and one solve with it (the unconstrained minimiser).
        Eigen::CholmodSupernodalLLT<SpMatCol, Eigen::Lower> llt;
        llt.compute(SpMatCol(qp.A));
        const double floor = cholmod_factor_flops(llt.cholmod()) + cholmod_solve_flops(llt.cholmod());
        EXPECT_GE(r.counters.work_flops, floor) << name;
        EXPECT_GT(work_units(r.counters, qp.A), static_cast<double>(r.counters.a_products) + 1.0) << name;
    }
    // mprgp (Jacobi) does nothing but products with A and vector operations.
    const SolverResult m = builtin_registry().create("mprgp", {})->solve(qp.view(), SolveContext{});
    EXPECT_EQ(m.counters.work_flops, 0.0);
    EXPECT_EQ(work_units(m.counters, qp.A), static_cast<double>(m.counters.a_products));
}

TEST(WorkUnits, IncompleteCholeskyCountsItsFactorAndEveryApplication)
{
    const Qp qp = test::make_grid_qp(test::GridQpParams{});
    const SolverResult cg = builtin_registry().create("cg", {{"precond", "ichol"}})->solve(qp.view(), SolveContext{});
    IncompleteCholeskyPreconditioner ic;
    std::string error;
    ASSERT_TRUE(ic.factor(qp.A, error)) << error;
    ASSERT_EQ(cg.counters.precond_factorizations, 1);
    ASSERT_GT(cg.counters.precond_applications, 0);
    EXPECT_EQ(cg.counters.work_flops,
              ic.factor_flops() + static_cast<double>(cg.counters.precond_applications) * ic.apply_flops());
    // mprgp's face factors: at least one factorisation (plus forming its face matrix, 2 A-products)
    const SolverResult m = builtin_registry().create("mprgp", {{"precond", "ichol"}})->solve(qp.view(), SolveContext{});
    ASSERT_GE(m.counters.precond_factorizations, 1);
    EXPECT_GT(m.counters.work_flops, 2.0 * a_product_flops(qp.A));
}

TEST(WorkUnits, RepeatedSolvesCountTheSameWork)
{
    const Qp qp = test::make_grid_qp(test::GridQpParams{});
    for (const char* name : {"pgs", "active-set", "ica", "mprgp-coupled"}) {
        const double first = builtin_registry().create(name, {})->solve(qp.view(), SolveContext{}).counters.work_flops;
        const double again = builtin_registry().create(name, {})->solve(qp.view(), SolveContext{}).counters.work_flops;
        EXPECT_EQ(first, again) << name;
    }
}

}  // namespace
}  // namespace cb
