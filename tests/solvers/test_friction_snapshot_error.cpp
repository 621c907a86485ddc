// FCLIB's relative error of a frictional snapshot (solvers/measure/friction_snapshot_error.hpp) against the
// local form's (solvers/measure/friction_error.hpp) on the local problem formed explicitly: W = J_all A^-1
// J_all', q = J_all A^-1 b - c_all, at a point whose x comes from r by stationarity.
#include "friction_test_qps.hpp"
#include "solvers/measure/friction_error.hpp"
#include "solvers/measure/friction_snapshot_error.hpp"

#include <Eigen/Dense>
#include <gtest/gtest.h>
#include <cmath>

namespace cb {
namespace {

TEST(FrictionSnapshotError, EqualsTheLocalFormsErrorWhereStationarityHolds)
{
    const Qp qp = testing_qps::pushed_plane(0.3, 0.4);
    const Eigen::Index m = qp.m();
    Vec c_all;
    const SpMat rows = contact_frame_rows(qp.view(), &c_all);
    ASSERT_EQ(rows.rows(), 3 * m);
    // Row 3i is J_i, rows 3i+1, 3i+2 are T_2i, T_2i+1.
    EXPECT_EQ(Vec(rows.row(3).transpose()), Vec(qp.J.row(1).transpose()));
    EXPECT_EQ(Vec(rows.row(5).transpose()), Vec(qp.friction.T.row(3).transpose()));
    EXPECT_EQ(c_all[4], qp.friction.cT[2]);
    // The local problem, densely (an independent route: Eigen's dense LLT of A).
    const Eigen::MatrixXd A = Eigen::MatrixXd(qp.A);
    const Eigen::LLT<Eigen::MatrixXd> llt(A);
    const Eigen::MatrixXd Rt = Eigen::MatrixXd(SpMat(rows.transpose()));
    FrictionLocal local;
    local.W = (Eigen::MatrixXd(rows) * llt.solve(Rt)).sparseView();
    local.q = rows * llt.solve(qp.b) - c_all;
    local.mu = qp.friction.mu;
    // A reaction of every kind (inside, outside and on the cone), x from it by stationarity.
    Vec r(3 * m);
    for (Eigen::Index k = 0; k < r.size(); ++k) r[k] = std::sin(1.7 * static_cast<double>(k) + 0.3);
    for (Eigen::Index i = 0; i < m; ++i) r[3 * i] = std::abs(r[3 * i]) * 4.0;
    const Vec x = llt.solve(Vec(qp.b + rows.transpose() * r));
    Vec lambda(m), lambda_t(2 * m);
    for (Eigen::Index i = 0; i < m; ++i) {
        lambda[i] = r[3 * i];
        lambda_t[2 * i] = r[3 * i + 1];
        lambda_t[2 * i + 1] = r[3 * i + 2];
    }
    const double expected = fclib_relative_error(local, r);
    ASSERT_GT(expected, 1e-3);  // far from a solution: the agreement is not 0 = 0
    const double norm_q = friction_local_q_norm(qp.view());
    EXPECT_NEAR(norm_q, local.q.norm(), 1e-12 * local.q.norm());
    EXPECT_NEAR(friction_snapshot_error(qp.view(), x, lambda, lambda_t, norm_q), expected, 1e-12 * expected);
}

TEST(FrictionSnapshotError, NotANumberWithoutFriction)
{
    const Qp qp = make_synthetic("plane", {{"nx", 2}, {"ny", 2}, {"nz", 2}}, 1);
    EXPECT_TRUE(std::isnan(friction_local_q_norm(qp.view())));
    EXPECT_TRUE(std::isnan(friction_natural_map_norm(qp.view(), qp.x0, Vec(), Vec())));
}

}  // namespace
}  // namespace cb
