// The `threads` setting (solvers/linalg/a_product, docs/a_product.md): products split into fixed row
// ranges give Eigen's y bit for bit and its dots to rounding; the same settings give the same
// iterates on every run; small A stays on one range; `run` warns when jobs x threads exceed the cores.
#include "harness/process_pool.hpp"
#include "problems/synthetic.hpp"
#include "solvers/core/registry.hpp"
#include "solvers/core/settings.hpp"
#include "solvers/linalg/a_product.hpp"
#include "tests/perf/varied_vector.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

using namespace cb;

namespace {

/// A plane large enough for several ranges of MIN_NONZEROS_PER_PART nonzeros.
Qp large_plane() { return make_synthetic("plane", {{"nx", 10}, {"ny", 10}, {"nz", 10}}, 5); }

/// y exact, x'y and x'w (all and masked) within 1e-14 of the sums of |terms|.
void expect_threaded_products_to_rounding(const AOperator& op, const SpMat& A)
{
    const Vec x = test::varied(A.cols(), 3), w = test::varied(A.cols(), 4);
    std::vector<char> skip(static_cast<size_t>(A.rows()));
    for (size_t i = 0; i < skip.size(); ++i) skip[i] = static_cast<char>(i % 5 == 1);
    const Vec oracle = A * x;
    const double xy_scale = x.cwiseAbs().dot(A.cwiseAbs() * x.cwiseAbs()), xw_scale = x.cwiseAbs().dot(w.cwiseAbs());
    Vec y, y2, y3;
    a_product(op, x, y);
    EXPECT_EQ((y - oracle).lpNorm<Eigen::Infinity>(), 0.0);  // each row summed as Eigen sums it
    double xw = 0.0, xw_masked = 0.0, expected_masked = 0.0;
    const double xy = a_product_dots(op, x, y2, w, xw);
    EXPECT_EQ((y2 - oracle).lpNorm<Eigen::Infinity>(), 0.0);
    EXPECT_LE(std::abs(xy - x.dot(oracle)), 1e-14 * xy_scale);
    EXPECT_LE(std::abs(xw - x.dot(w)), 1e-14 * xw_scale);
    for (Eigen::Index i = 0; i < A.rows(); ++i)
        if (!skip[static_cast<size_t>(i)]) expected_masked += x[i] * w[i];
    a_product_dots(op, x, y3, w, skip.data(), xw_masked);
    EXPECT_EQ((y3 - oracle).lpNorm<Eigen::Infinity>(), 0.0);
    EXPECT_LE(std::abs(xw_masked - expected_masked), 1e-14 * xw_scale);
}

}  // namespace

TEST(ThreadedProduct, RangesCoverTheRowsWithAboutEqualNonzeros)
{
    const Qp qp = large_plane();
    ASSERT_GE(qp.A.nonZeros(), 4 * MIN_NONZEROS_PER_PART);
    for (const AFormat format : {AFormat::CSR, AFormat::BSR}) {
        for (const int threads : {2, 3, 4}) {
            AOperator op(qp.A);
            ASSERT_EQ(op.prepare(format, threads), format);
            ASSERT_EQ(op.parts(), threads);
            const std::vector<int>& bound = op.part_start();
            const Eigen::Index rows = format == AFormat::BSR ? qp.n() / 3 : qp.n();
            EXPECT_EQ(bound.front(), 0);
            EXPECT_EQ(bound.back(), rows);
            const int* start = format == AFormat::BSR ? op.blocks().start.data() : qp.A.outerIndexPtr();
            const double each = static_cast<double>(start[rows]) / threads;
            for (int p = 0; p < threads; ++p) {
                EXPECT_LT(bound[static_cast<size_t>(p)], bound[static_cast<size_t>(p) + 1]);
                const double work = start[bound[static_cast<size_t>(p) + 1]] - start[bound[static_cast<size_t>(p)]];
                EXPECT_NEAR(work, each, 0.02 * each) << "range " << p << " of " << threads;
            }
        }
    }
}

TEST(ThreadedProduct, TwoAndThreeThreadsGiveTheCsrProductAndItsDotsToRounding)
{
    const Qp qp = large_plane();
    for (const AFormat format : {AFormat::CSR, AFormat::BSR})
        for (const int threads : {2, 3}) {
            SCOPED_TRACE(std::string(format == AFormat::BSR ? "BSR" : "CSR") + ", threads " + std::to_string(threads));
            AOperator op(qp.A);
            op.prepare(format, threads);
            ASSERT_EQ(op.parts(), threads);
            const long before = a_product_count();
            expect_threaded_products_to_rounding(op, qp.A);
            EXPECT_EQ(a_product_count() - before, 3);  // one count per product, whatever the threads
        }
}

TEST(ThreadedProduct, SmallAOrUncompressedAKeepsOneRange)
{
    const Qp small = make_synthetic("plane", {{"nx", 2}, {"ny", 2}, {"nz", 2}}, 3);
    ASSERT_LT(small.A.nonZeros(), 2 * MIN_NONZEROS_PER_PART);
    AOperator op(small.A);
    op.prepare(AFormat::BSR, 8);
    EXPECT_EQ(op.parts(), 1);
    Qp large = large_plane();
    SpMat loose = large.A;
    loose.uncompress();
    AOperator raw(loose);
    raw.prepare(AFormat::CSR, 2);
    EXPECT_EQ(raw.parts(), 1);  // Eigen's product, one thread
    expect_threaded_products_to_rounding(raw, large.A);
}

TEST(ThreadedProduct, SameSettingsGiveTheSameIteratesOnEveryRun)
{
    const Qp qp = large_plane();
    ASSERT_GT(qp.m(), 0);
    for (const char* solver : {"mprgp", "mprgp-coupled", "cg"}) {
        if (!builtin_registry().contains(solver)) continue;
        SCOPED_TRACE(solver);
        const nlohmann::json settings = {{"threads", 2}, {"tol", 1e-9}};
        const SolverResult a = builtin_registry().create(solver, settings)->solve(qp.view(), {});
        const SolverResult b = builtin_registry().create(solver, settings)->solve(qp.view(), {});
        EXPECT_EQ(a.iterations, b.iterations);
        EXPECT_EQ(a.counters.a_products, b.counters.a_products);
        EXPECT_EQ(a.status, b.status);
        ASSERT_EQ(a.x.size(), b.x.size());
        EXPECT_EQ((a.x - b.x).lpNorm<Eigen::Infinity>(), 0.0);  // bit for bit
        // One thread reaches the same solution to the tolerance (its dots may round differently).
        const SolverResult one = builtin_registry().create(solver, {{"tol", 1e-9}})->solve(qp.view(), {});
        EXPECT_EQ(one.status, a.status);
        EXPECT_LE((one.x - a.x).lpNorm<Eigen::Infinity>(), 1e-6 * std::max(1.0, one.x.lpNorm<Eigen::Infinity>()));
    }
}

TEST(ThreadedProduct, ThreadsIsACommonSettingRecordedAndChecked)
{
    EXPECT_EQ(CommonSettings{}.threads, 1);
    EXPECT_EQ(CommonSettings{}.to_json()["threads"], 1);
    const auto solver = builtin_registry().create("cg", {{"threads", 2}});
    EXPECT_EQ(solver->settings()["threads"], 2);
    try {
        builtin_registry().create("cg", {{"threads", 0}});
        ADD_FAILURE() << "threads 0 accepted";
    } catch (const InputError& e) {
        EXPECT_STREQ(e.what(), "cg: /threads: must be >= 1, got 0");
    }
}

TEST(ThreadedProduct, RunWarnsWhenJobsTimesThreadsExceedTheCores)
{
    EXPECT_EQ(oversubscription_warning(1, 2, 2), "");
    EXPECT_EQ(oversubscription_warning(2, 1, 2), "");
    EXPECT_EQ(oversubscription_warning(4, 4, 0), "");  // cores unknown
    EXPECT_EQ(oversubscription_warning(2, 2, 2),
              "warning: 2 job(s) at a time x 2 thread(s) = 4 threads on 2 core(s): runs share cores, so their "
              "times are slower than on a machine to themselves");
}
