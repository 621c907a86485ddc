// The harness-counted A-products: solvers/linalg/a_product computes y = A x and counts it, and run_solver
// records the products made during the solve as counters.a_products_harness beside the solver's
// own count (equal for every solver whose products all go through the counting operator).
#include "harness/runner.hpp"
#include "problems/synthetic.hpp"
#include "solvers/linalg/a_product.hpp"

#include <gtest/gtest.h>

using namespace cb;

TEST(AProduct, ComputesTheProductAndCountsEachCall)
{
    const Qp qp = make_synthetic("plane", {{"nx", 3}, {"ny", 2}, {"nz", 3}}, 5);
    const Vec x = Vec::LinSpaced(qp.n(), -1.0, 2.0);
    const long before = a_product_count();
    Vec y;
    a_product(qp.A, x, y);
    const Vec z = a_product(qp.A, x);
    EXPECT_EQ(a_product_count() - before, 2);
    const Vec expected = qp.A * x;
    ASSERT_EQ(y.size(), qp.n());
    EXPECT_EQ((y - expected).lpNorm<Eigen::Infinity>(), 0.0);
    EXPECT_EQ((z - expected).lpNorm<Eigen::Infinity>(), 0.0);
}

TEST(AProduct, FusedDotsAreTheProductsDotsAndOneCountedProduct)
{
    const Qp qp = make_synthetic("plane", {{"nx", 3}, {"ny", 2}, {"nz", 3}}, 5);
    const Vec x = Vec::LinSpaced(qp.n(), -1.0, 2.0);
    const Vec w = Vec::LinSpaced(qp.n(), 3.0, -0.5);
    const Vec expected = qp.A * x;
    SpMat uncompressed = qp.A;
    uncompressed.uncompress();  // the fallback path (the raw loop reads compressed storage only)
    const SpMat* matrices[] = {&qp.A, &uncompressed};
    for (const SpMat* A : matrices) {
        const long before = a_product_count();
        Vec y;
        double xw = 0.0;
        const double xy = a_product_dots(*A, x, y, w, xw);
        EXPECT_EQ(a_product_count() - before, 1);
        ASSERT_EQ(y.size(), qp.n());
        EXPECT_LE((y - expected).lpNorm<Eigen::Infinity>(), 1e-14 * expected.lpNorm<Eigen::Infinity>());
        EXPECT_NEAR(xy, x.dot(expected), 1e-12 * std::abs(x.dot(expected)));
        EXPECT_NEAR(xw, x.dot(w), 1e-12 * x.norm() * w.norm());
    }
}

TEST(AProduct, RunnerRecordsTheHarnessCountOfTheSolveOnly)
{
    const Qp qp = make_synthetic("plane", {{"nx", 4}, {"ny", 3}, {"nz", 4}}, 7);
    RunOptions options;
    options.repeat = 3;  // the count is the first solve's, not the sum of the repeats
    const RunOutcome cg = run_solver(qp, "cg", {{"tol", 1e-8}}, options);
    const auto& counters = cg.record["counters"];
    ASSERT_TRUE(counters.contains("a_products_harness"));
    EXPECT_GT(counters["a_products"].get<long>(), 2);
    EXPECT_EQ(counters["a_products_harness"].get<long>(), counters["a_products"].get<long>());

    // mprgp's CG steps' fused product (product and dot products in one pass over A) goes through
    // the counting operator too: both counts agree (before issue 47 the harness saw fewer).
    const RunOutcome mprgp = run_solver(qp, "mprgp", {{"tol", 1e-8}}, RunOptions{});
    const auto& m = mprgp.record["counters"];
    EXPECT_GT(m["a_products_harness"].get<long>(), 0);
    EXPECT_GT(m["cg_steps"].get<long>(), 0);
    EXPECT_EQ(m["a_products_harness"].get<long>(), m["a_products"].get<long>());

    // mprgp-coupled's fused CG product goes through the counting a_product_dots: both counts agree.
    const RunOutcome coupled = run_solver(qp, "mprgp-coupled", {{"tol", 1e-8}}, RunOptions{});
    const auto& c = coupled.record["counters"];
    EXPECT_GT(c["cg_steps"].get<long>(), 0);
    EXPECT_EQ(c["a_products_harness"].get<long>(), c["a_products"].get<long>());
}
