// Issue 45, the snapshot (primal) form: a frictional QP (solvers/core/qp.hpp, Friction: J normal rows,
// T tangent rows, mu) made local through W = H A^-1 H' (solvers/friction/friction_dual.hpp) and solved by
// mprgp-tresca-fp; checked against nsgs on the same W and against the primal x = A^-1 (b + H'r).
#include "solvers/friction/friction_dual.hpp"
#include "solvers/friction/friction_nsgs.hpp"
#include "solvers/friction/mprgp_tresca.hpp"
#include "solvers/measure/friction_error.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace {

using cb::Vec;

/// k particles in a chain of weak springs on the plane z >= 0, pushed down and sideways: the first
/// half by 0.1 of the push, the second by 2 (mu = 0.5): the first half sticks, the second slides.
cb::Qp particles_on_a_plane(int k)
{
    const Eigen::Index n = 3 * k;
    std::vector<Eigen::Triplet<double>> a;
    for (Eigen::Index j = 0; j < n; ++j) a.emplace_back(int(j), int(j), 1.0);  // masses
    for (int p = 0; p + 1 < k; ++p)                                            // springs of stiffness 0.02
        for (int d = 0; d < 3; ++d) {
            const int i = 3 * p + d, j = 3 * (p + 1) + d;
            a.emplace_back(i, i, 0.02);
            a.emplace_back(j, j, 0.02);
            a.emplace_back(i, j, -0.02);
            a.emplace_back(j, i, -0.02);
        }
    cb::Qp qp;
    qp.A.resize(n, n);
    qp.A.setFromTriplets(a.begin(), a.end());
    qp.b = Vec::Zero(n);
    qp.J.resize(k, n);
    qp.friction.T.resize(2 * k, n);
    std::vector<Eigen::Triplet<double>> j, t;
    for (int p = 0; p < k; ++p) {
        j.emplace_back(p, 3 * p + 2, 1.0);
        t.emplace_back(2 * p, 3 * p, 1.0);
        t.emplace_back(2 * p + 1, 3 * p + 1, 1.0);
        qp.b[3 * p + 2] = -1.0;
        qp.b[3 * p] = 2 * p < k ? 0.1 : 2.0;
        qp.b[3 * p + 1] = 0.05 * ((p % 3) - 1);
    }
    qp.J.setFromTriplets(j.begin(), j.end());
    qp.friction.T.setFromTriplets(t.begin(), t.end());
    qp.c = Vec::Zero(k);
    qp.x0 = Vec::Zero(n);
    qp.friction.mu = Vec::Constant(k, 0.5);
    return qp;
}

TEST(MprgpTrescaSnapshot, SolvesTheLocalProblemOfAFrictionalQp)
{
    const cb::Qp qp = particles_on_a_plane(12);
    cb::FrictionDual dual(qp.view(), "particles");
    const cb::FrictionLocal& local = dual.local();
    ASSERT_EQ(local.W.rows(), 36);
    const cb::MprgpTrescaRun fp = cb::mprgp_tresca_fp(local, {});
    ASSERT_EQ(fp.run.status, "converged") << fp.run.note;
    EXPECT_LE(fp.run.error, 1e-8);
    const cb::FrictionRun nsgs = cb::friction_nsgs(local, {});
    ASSERT_EQ(nsgs.status, "converged");
    EXPECT_LE((nsgs.r - fp.run.r).norm(), 1e-6 * nsgs.r.norm());
    // The primal point: u from x = A^-1 (b + H'r) is W r + q, and no contact penetrates.
    const Vec x = dual.primal(fp.run.r);
    int sticking = 0, sliding = 0;
    for (Eigen::Index i = 0; i < 12; ++i) {
        const double un = x[3 * i + 2], ut0 = x[3 * i], ut1 = x[3 * i + 1];
        EXPECT_NEAR(un, fp.run.u[3 * i], 1e-10);
        EXPECT_NEAR(ut0, fp.run.u[3 * i + 1], 1e-10);
        EXPECT_NEAR(ut1, fp.run.u[3 * i + 2], 1e-10);
        EXPECT_GE(un, -1e-10);
        const double rn = fp.run.r[3 * i], rt = std::hypot(fp.run.r[3 * i + 1], fp.run.r[3 * i + 2]);
        sticking += std::hypot(ut0, ut1) <= 1e-8;
        sliding += std::hypot(ut0, ut1) > 1e-6 && std::abs(rt - 0.5 * rn) <= 1e-8 * (1.0 + rn);
    }
    EXPECT_GT(sticking, 0);
    EXPECT_GT(sliding, 0);
}

TEST(MprgpTrescaSnapshot, AFrictionlessQpIsRefusedByName)
{
    cb::Qp qp = particles_on_a_plane(3);
    qp.friction = cb::Friction{};
    try {
        cb::FrictionDual dual(qp.view(), "plain.qpsnap");
        ADD_FAILURE() << "a QP without friction was taken";
    } catch (const cb::InputError& e) {
        EXPECT_STREQ(e.what(),
                     "plain.qpsnap: mu: missing: a frictional snapshot has a friction coefficient per contact row");
    }
}

}  // namespace
