// Issue 45, the snapshot (primal) form: a frictional QP (solvers/core/qp.hpp, Friction: J normal rows,
// T tangent rows, mu) made local through W = H A^-1 H' (solvers/friction/friction_dual.hpp) and solved by
// mprgp-tresca-fp; checked against nsgs on the same W and against the primal x = A^-1 (b + H'r).
#include "friction_test_qps.hpp"
#include "solvers/friction/friction_dual.hpp"
#include "solvers/friction/friction_nsgs.hpp"
#include "solvers/friction/mprgp_tresca.hpp"
#include "solvers/measure/friction_error.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace {

using cb::Vec;
using cb::testing_qps::particles_on_a_plane;

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
