// The accuracy scale handed to a solver on its view (QpView::scale, solvers/measure/accuracy.hpp):
// accuracy_scale() on such a view gives the bits a fresh build gives, for the same rows, the rows
// without their friction and a decoupled subset of rows, and shares the body modes (n x 6 doubles)
// instead of holding a second copy; a view of other start values or another scene size builds
// its own.
#include "solvers/measure/accuracy.hpp"
#include "tests/solvers/friction_test_qps.hpp"

#include <gtest/gtest.h>
#include <random>

namespace {

using cb::AccuracyScale;
using cb::Qp;
using cb::QpView;
using cb::Vec;

/// Every number of the two scales, and their stationarity at (x, lambda, lambda_t), to the bit.
void scale_sharing_expect_same(const AccuracyScale& got, const AccuracyScale& fresh, const Vec& x, const Vec& lambda,
                               const Vec& lambda_t)
{
    EXPECT_EQ(got.inv_diag, fresh.inv_diag);
    EXPECT_EQ(got.inv_row_norm, fresh.inv_row_norm);
    EXPECT_EQ(got.length_per_multiplier, fresh.length_per_multiplier);
    EXPECT_EQ(got.length, fresh.length);
    EXPECT_EQ(got.length_source, fresh.length_source);
    EXPECT_EQ(got.stiffness, fresh.stiffness);
    EXPECT_EQ(got.inv_energy, fresh.inv_energy);
    EXPECT_EQ(got.a_products, fresh.a_products);
    EXPECT_EQ(got.bodies.bodies(), fresh.bodies.bodies());
    const double motion = fresh.body_motion(x, lambda, lambda_t);
    EXPECT_GT(motion, 0.0);  // the comparison below is on a number that is there
    EXPECT_EQ(got.body_motion(x, lambda, lambda_t), motion);
}

struct ScaleSharingCase {
    Qp qp;
    Vec x, lambda, lambda_t;
};

ScaleSharingCase scale_sharing_case()
{
    ScaleSharingCase c;
    c.qp = cb::make_synthetic("plane", {{"nx", 3}, {"ny", 2}, {"nz", 3}}, 5);
    cb::testing_qps::add_friction(c.qp, [](Eigen::Index i) { return 0.1 + 0.05 * double(i % 4); });
    std::mt19937_64 rng(11);
    std::uniform_real_distribution<double> u(-1e-3, 1e-3);
    c.x = c.qp.x0;
    for (Eigen::Index j = 0; j < c.x.size(); ++j) c.x[j] += u(rng);
    c.lambda = Vec(c.qp.m());
    c.lambda_t = Vec(2 * c.qp.m());
    for (Eigen::Index i = 0; i < c.lambda.size(); ++i) c.lambda[i] = 1.0 + u(rng);
    for (Eigen::Index i = 0; i < c.lambda_t.size(); ++i) c.lambda_t[i] = 1e2 * u(rng);
    return c;
}

TEST(AccuracyScaleSharing, SameViewSharesTheBodyModesAndGivesTheSameBits)
{
    const ScaleSharingCase c = scale_sharing_case();
    ASSERT_GT(c.qp.m(), 2);
    const AccuracyScale shared = cb::accuracy_scale(c.qp.view());
    QpView view = c.qp.view();
    view.scale = &shared;
    const AccuracyScale got = cb::accuracy_scale(view);
    EXPECT_TRUE(got.bodies.shares_modes_with(shared.bodies));
    scale_sharing_expect_same(got, cb::accuracy_scale(c.qp.view()), c.x, c.lambda, c.lambda_t);
    // A copy shares them too (the harness's record and monitor hold copies).
    const AccuracyScale copy = shared;
    EXPECT_TRUE(copy.bodies.shares_modes_with(shared.bodies));
}

TEST(AccuracyScaleSharing, ViewWithoutFrictionOrWithFewerRowsGivesTheFreshBits)
{
    const ScaleSharingCase c = scale_sharing_case();
    const AccuracyScale shared = cb::accuracy_scale(c.qp.view());

    // A frictionless solver's view: the same rows without their tangent rows.
    QpView frictionless = c.qp.view();
    frictionless.friction = nullptr;
    const AccuracyScale fresh_frictionless = cb::accuracy_scale(frictionless);
    frictionless.scale = &shared;
    const AccuracyScale got_frictionless = cb::accuracy_scale(frictionless);
    EXPECT_TRUE(got_frictionless.bodies.shares_modes_with(shared.bodies));
    scale_sharing_expect_same(got_frictionless, fresh_frictionless, c.x, c.lambda, Vec());

    // A decoupled solver's view: every other row of J.
    std::vector<Eigen::Triplet<double>> t;
    Vec c_kept(0);
    Eigen::Index kept = 0;
    for (Eigen::Index i = 0; i < c.qp.m(); i += 2, ++kept) {
        for (cb::SpMat::InnerIterator it(c.qp.J, i); it; ++it) t.emplace_back(int(kept), int(it.col()), it.value());
        c_kept.conservativeResize(kept + 1);
        c_kept[kept] = c.qp.c[i];
    }
    cb::SpMat J_kept(kept, c.qp.n());
    J_kept.setFromTriplets(t.begin(), t.end());
    J_kept.makeCompressed();
    const QpView decoupled{c.qp.A, c.qp.b, J_kept, c_kept, c.qp.x0, &c.qp.length, nullptr};
    const AccuracyScale fresh_decoupled = cb::accuracy_scale(decoupled);
    const QpView decoupled_given{c.qp.A, c.qp.b, J_kept, c_kept, c.qp.x0, &c.qp.length, nullptr, &shared};
    const AccuracyScale got_decoupled = cb::accuracy_scale(decoupled_given);
    EXPECT_TRUE(got_decoupled.bodies.shares_modes_with(shared.bodies));
    ASSERT_EQ(got_decoupled.inv_row_norm.size(), kept);
    scale_sharing_expect_same(got_decoupled, fresh_decoupled, c.x, Vec(c.lambda.head(kept)), Vec());
}

TEST(AccuracyScaleSharing, OtherStartOrSceneSizeBuildsItsOwn)
{
    const ScaleSharingCase c = scale_sharing_case();
    const AccuracyScale shared = cb::accuracy_scale(c.qp.view());

    // The same values in another vector: not known to be the same start, so built afresh.
    const Vec x0_copy = c.qp.x0;
    const QpView other_start{c.qp.A, c.qp.b, c.qp.J, c.qp.c, x0_copy, &c.qp.length, &c.qp.friction, &shared};
    const AccuracyScale got_start = cb::accuracy_scale(other_start);
    EXPECT_FALSE(got_start.bodies.shares_modes_with(shared.bodies));
    scale_sharing_expect_same(got_start, shared, c.x, c.lambda, c.lambda_t);

    // A scene size fixed on the view: its own rotation modes (scaled by 1 / l).
    const cb::FixedLength fixed{2.5, "given"};
    QpView other_length = c.qp.view();
    other_length.length = &fixed;
    const AccuracyScale fresh_length = cb::accuracy_scale(other_length);
    other_length.scale = &shared;
    const AccuracyScale got_length = cb::accuracy_scale(other_length);
    EXPECT_FALSE(got_length.bodies.shares_modes_with(shared.bodies));
    EXPECT_EQ(got_length.length, 2.5);
    scale_sharing_expect_same(got_length, fresh_length, c.x, c.lambda, c.lambda_t);
}

}  // namespace
