// Tests of the rigid half of the accuracy measure's stationarity (solvers/measure/body_motion.*): a stiff
// body in free fall, where one Jacobi step misreads the start's error by the stiffness, two
// bodies judged apart, rotations, and the one-mode reading when n is not a multiple of 3.
#include "solvers/measure/accuracy.hpp"
#include "solvers/measure/body_motion.hpp"
#include "tests/solvers/tiny_qps.hpp"

#include <gtest/gtest.h>
#include <cmath>
#include <limits>

namespace {

using cb::Qp;
using cb::Vec;

/// A chain of `vertices` points 1 apart along x, joined by springs of stiffness k along every
/// axis (K = k L (x) I3, L the path graph's Laplacian: no resistance to a translation), lumped mass
/// `mass`: A = M + h^2 K. Bodies are offset by `offset` along y, `bodies` of them.
Eigen::MatrixXd chain_matrix(int vertices, int bodies, double mass, double h2k)
{
    const int nv = vertices * bodies;
    Eigen::MatrixXd A = Eigen::MatrixXd::Zero(3 * nv, 3 * nv);
    for (int b = 0; b < bodies; ++b)
        for (int v = 0; v < vertices; ++v) {
            const int i = b * vertices + v;
            for (int a = 0; a < 3; ++a) A(3 * i + a, 3 * i + a) += mass;
            if (v + 1 == vertices) continue;
            for (int a = 0; a < 3; ++a) {
                const int p = 3 * i + a, q = 3 * (i + 1) + a;
                A(p, p) += h2k;
                A(q, q) += h2k;
                A(p, q) -= h2k;
                A(q, p) -= h2k;
            }
        }
    return A;
}

Vec chain_positions(int vertices, int bodies)
{
    Vec x(3 * vertices * bodies);
    for (int b = 0; b < bodies; ++b)
        for (int v = 0; v < vertices; ++v) x.segment<3>(3 * (b * vertices + v)) = Eigen::Vector3d(v, 3.0 * b, 0.0);
    return x;
}

/// The bodies' motion under a residual force r at the start: b = A x0 - r, so that A x0 - b = r.
double motion_under(const Eigen::MatrixXd& A, const Vec& x0, const Vec& r, double length, int* bodies = nullptr)
{
    const Qp qp = cb::testing_qps::dense_qp(A, A * x0 - r, Eigen::MatrixXd(0, A.cols()), Vec(0), x0);
    const cb::BodyMotion motion(qp.view(), length);
    if (bodies) *bodies = motion.bodies();
    return motion.displacement(x0, Vec(0));
}

}  // namespace

// Free fall: x0 at rest, b = A x0 + h^2 M g, so x* = x0 + h^2 g on every vertex. At x0 the residual
// is -h^2 M g: a Jacobi step reads h^2 g M / (M + 2 h^2 k), the body really moves h^2 g.
TEST(BodyMotion, StiffBodyInFreeFallIsJudgedByItsFall)
{
    const int vertices = 10;
    const double mass = 1.0, h2k = 1e4, h2g = 2.5e-4;
    const Eigen::MatrixXd A = chain_matrix(vertices, 1, mass, h2k);
    const Vec x0 = chain_positions(vertices, 1);
    Vec fall = Vec::Zero(x0.size());
    for (int v = 0; v < vertices; ++v) fall[3 * v + 1] = -h2g;
    const Vec b = A * x0 + A * fall;  // A (h^2 g on every vertex) = M h^2 g: K ignores the translation
    const Qp qp = cb::testing_qps::dense_qp(A, b, Eigen::MatrixXd(0, A.cols()), Vec(0), x0);
    const cb::AccuracyScale s = cb::accuracy_scale(qp.view());
    ASSERT_DOUBLE_EQ(s.length, 9.0);
    EXPECT_EQ(s.bodies.bodies(), 1);

    const cb::AccuracyParts at_start = cb::accuracy(qp.view(), s, x0, Vec(0));
    EXPECT_NEAR(at_start.stationarity, h2g / 9.0, 1e-12 * h2g);
    // The Jacobi half alone: the end vertices have D = 1 + 1e4, the inner ones 1 + 2e4.
    const Vec r = A * x0 - b;
    double jacobi = 0.0;
    for (Eigen::Index j = 0; j < r.size(); ++j) jacobi = std::max(jacobi, std::abs(r[j]) / A(j, j));
    EXPECT_NEAR(jacobi, h2g / (1.0 + h2k), 1e-15);
    EXPECT_GT(at_start.stationarity, 1000.0 * jacobi / 9.0);

    const cb::AccuracyParts at_solution = cb::accuracy(qp.view(), s, x0 + fall, Vec(0));
    EXPECT_LE(at_solution.stationarity, 1e-12);
}

// Two bodies: a residual on the second moves only the second; each body's motion is its own.
TEST(BodyMotion, BodiesAreJudgedApart)
{
    const int vertices = 4;
    const Eigen::MatrixXd A = chain_matrix(vertices, 2, 2.0, 50.0);
    const Vec x0 = chain_positions(vertices, 2);
    // A force 1 along z on every vertex of body 2: total 4 on mass 8 -> 0.5 along z.
    Vec r = Vec::Zero(x0.size());
    for (int v = vertices; v < 2 * vertices; ++v) r[3 * v + 2] = 1.0;
    int bodies = 0;
    EXPECT_NEAR(motion_under(A, x0, r, 6.0, &bodies), 0.5, 1e-12);
    EXPECT_EQ(bodies, 2);
    // Not finite -> infinite.
    const Qp qp = cb::testing_qps::dense_qp(A, A * x0 - r, Eigen::MatrixXd(0, A.cols()), Vec(0), x0);
    Vec x = x0;
    x[0] = std::numeric_limits<double>::quiet_NaN();
    EXPECT_EQ(cb::BodyMotion(qp.view(), 6.0).displacement(x, Vec(0)), std::numeric_limits<double>::infinity());
}

// A torque on a stiff chain turns the whole body; without springs each vertex is its own body.
TEST(BodyMotion, TorqueTurnsTheBody)
{
    const int vertices = 3;  // x = 0, 1, 2; centroid 1: offsets -1, 0, 1
    const Eigen::MatrixXd A = chain_matrix(vertices, 1, 1.0, 1e6);
    const Vec x0 = chain_positions(vertices, 1);
    Vec r = Vec::Zero(x0.size());
    r[1] = -1.0;  // vertex 0 (offset -1) pushed along -y, vertex 2 (offset +1) along +y: torque 2 about z
    r[3 * 2 + 1] = 1.0;
    // Rotation about z: the mode (0, d_x, 0) / l has M-energy 2 / l^2 and, since K = k L (x) I3
    // resists every relative motion, spring energy h^2k * 2 / l^2: it turns by 2 / (2 + 2e6) at the ends.
    EXPECT_NEAR(motion_under(A, x0, r, 2.0), 2.0 / (2.0 + 2e6), 1e-12);
    int bodies = 0;
    EXPECT_NEAR(motion_under(chain_matrix(vertices, 1, 1.0, 0.0), x0, r, 2.0, &bodies), 1.0, 1e-12);
    EXPECT_EQ(bodies, 3);
}

// The contact force balances: a row's multiplier enters V'r through (JV)'lambda.
TEST(BodyMotion, ContactForcesEnterThroughTheRows)
{
    const int vertices = 4;
    const Eigen::MatrixXd A = chain_matrix(vertices, 1, 1.0, 1e4);
    const Vec x0 = chain_positions(vertices, 1);
    Vec r = Vec::Zero(x0.size());
    for (int v = 0; v < vertices; ++v) r[3 * v + 1] = 0.25;  // weight 1 along +y in total
    Eigen::MatrixXd J = Eigen::MatrixXd::Zero(2, A.cols());
    J(0, 1) = 1.0;  // rows on vertex 0 and vertex 3 along y: lambda 0.5 each balances the weight
    J(1, 3 * 3 + 1) = 1.0;
    const Qp qp = cb::testing_qps::dense_qp(A, A * x0 - r, J, Eigen::Vector2d(-1, -1), x0);
    const cb::BodyMotion motion(qp.view(), 3.0);
    EXPECT_NEAR(motion.displacement(x0, Vec(0)), 0.25, 1e-12);  // 1 over the mass 4
    EXPECT_LE(motion.displacement(x0, Eigen::Vector2d(0.5, 0.5)), 1e-15);
    EXPECT_GT(motion.displacement(x0, Eigen::Vector2d(1.0, 0.0)), 1e-6);  // balanced force, unbalanced torque
}

// n not a multiple of 3: one constant mode per connected component of A's DOF graph.
TEST(BodyMotion, OneModePerComponentWithoutThreeDimensions)
{
    Eigen::MatrixXd A(4, 4);
    A << 3, -1, 0, 0, -1, 3, 0, 0, 0, 0, 5, 0, 0, 0, 0, 2;
    int bodies = 0;
    // r = (1, 1, 0, 0): the pair's constant mode has 1'A1 = 4, 1'r = 2 -> 0.5.
    EXPECT_NEAR(motion_under(A, Vec::Zero(4), Eigen::Vector4d(1, 1, 0, 0), 1.0, &bodies), 0.5, 1e-15);
    EXPECT_EQ(bodies, 3);
    // r on the loose DOF 3: 1 / 2.
    EXPECT_NEAR(motion_under(A, Vec::Zero(4), Eigen::Vector4d(0, 0, 0, 1), 1.0), 0.5, 1e-15);
    EXPECT_EQ(cb::BodyMotion().displacement(Vec(0), Vec(0)), 0.0);
}
