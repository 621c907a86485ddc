// Finite-difference checks of the corotated FEM (forces, stiffness), rotation invariance,
// lumped mass, and the backward-Euler QP of one Newton step.
#include "sim/fem_corotated.hpp"
#include "sim/integrator.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/SparseCholesky>
#include <gtest/gtest.h>
#include <random>

using namespace cb;
using namespace cb::sim;

namespace {
TetMesh small_box() { return make_box_mesh(2, 1, 1, Vec3(0.1, 0.12, 0.09), Vec3(0.3, -0.2, 0.1)); }

Vec flat(const Positions& p) { return Eigen::Map<const Vec>(p.data(), p.size()); }

Vec random_perturbation(long n, double scale, unsigned seed)
{
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-1, 1);
    Vec d(n);
    for (long i = 0; i < n; ++i) d[i] = scale * u(rng);
    return d;
}
}  // namespace

TEST(FemCorotated, LumpedMassSumsToDensityTimesVolume)
{
    const TetMesh mesh = small_box();
    Material m;
    m.density = 1234.0;
    CorotatedFem fem(mesh.positions, mesh.tets, {m});
    const double volume = 0.2 * 0.12 * 0.09;
    EXPECT_NEAR(mesh_volume(mesh), volume, 1e-15);
    EXPECT_NEAR(fem.vertex_mass().sum(), 1234.0 * volume, 1e-12);
}

TEST(FemCorotated, ForceMatchesFiniteDifferenceOfEnergy)
{
    const TetMesh mesh = small_box();
    CorotatedFem fem(mesh.positions, mesh.tets, {Material{1e6, 0.35, 1000}});
    const Vec x = flat(mesh.positions) + random_perturbation(3 * mesh.vertices(), 0.02, 1);
    fem.update(x);
    const Vec g = fem.gradient();
    ASSERT_GT(g.norm(), 1.0);  // a real deformation, not the rest state
    const double eps = 1e-7;
    double worst = 0;
    for (long i = 0; i < x.size(); ++i) {
        Vec xp = x, xm = x;
        xp[i] += eps;
        xm[i] -= eps;
        const double fd = (fem.energy(xp) - fem.energy(xm)) / (2 * eps);
        worst = std::max(worst, std::abs(fd - g[i]));
    }
    EXPECT_LT(worst, 1e-5 * g.lpNorm<Eigen::Infinity>());
}

TEST(FemCorotated, StiffnessEqualsHessianAtRotatedRest)
{
    // At a rigidly rotated rest state the exact Hessian of the corotated energy equals R K0 R'.
    const TetMesh mesh = small_box();
    CorotatedFem fem(mesh.positions, mesh.tets, {Material{1e6, 0.3, 1000}});
    const Eigen::Matrix3d R = rotation_from_euler_deg(Vec3(30, -50, 70));
    Positions rotated = mesh.positions;
    transform_positions(rotated, 1.0, R, Vec3(0.1, 0.2, 0.3));
    const Vec x = flat(rotated);
    fem.update(x);
    EXPECT_LT(fem.gradient().norm(), 1e-8);
    SpMat K;
    fem.assemble(0.0, 1.0, K);
    const Eigen::MatrixXd Kd = Eigen::MatrixXd(K);
    const double eps = 1e-6;
    double worst = 0;
    for (long j = 0; j < x.size(); ++j) {
        Vec xp = x, xm = x;
        xp[j] += eps;
        xm[j] -= eps;
        fem.update(xp);
        const Vec gp = fem.gradient();
        fem.update(xm);
        const Vec gm = fem.gradient();
        worst = std::max(worst, ((gp - gm) / (2 * eps) - Kd.col(j)).lpNorm<Eigen::Infinity>());
    }
    EXPECT_LT(worst, 1e-5 * Kd.lpNorm<Eigen::Infinity>());
    EXPECT_LT((Kd - Kd.transpose()).lpNorm<Eigen::Infinity>(), 1e-9 * Kd.lpNorm<Eigen::Infinity>());
}

namespace {
/// The linear elastic energy with every tet's rotation held at R_t (the test's own, from the
/// mesh, not CorotatedFem's): sum vol (mu |sym(R' F(y)) - I|^2 + lambda/2 tr(R' F(y) - I)^2).
/// Its gradient is minus the fixed-rotation force, and its Hessian is K(x).
double fixed_rotation_energy(const TetMesh& mesh, const Material& m, const CorotatedFem& fem, const Vec& y)
{
    double e = 0;
    for (long t = 0; t < mesh.tet_count(); ++t) {
        Eigen::Matrix3d Dm, Ds;
        const auto v = [&](int k) { return static_cast<long>(mesh.tets(t, k)); };
        for (int k = 0; k < 3; ++k) {
            Dm.col(k) = (mesh.positions.row(v(k + 1)) - mesh.positions.row(v(0))).transpose();
            Ds.col(k) = y.segment<3>(3 * v(k + 1)) - y.segment<3>(3 * v(0));
        }
        const Eigen::Matrix3d G = fem.rotation(t).transpose() * Ds * Dm.inverse() - Eigen::Matrix3d::Identity();
        const Eigen::Matrix3d eps = 0.5 * (G + G.transpose());
        e += Dm.determinant() / 6.0 * (m.mu() * eps.squaredNorm() + 0.5 * m.lambda() * G.trace() * G.trace());
    }
    return e;
}

/// Central differences of fixed_rotation_energy: exact for a quadratic but for rounding.
Vec fixed_rotation_gradient(const TetMesh& mesh, const Material& m, const CorotatedFem& fem, const Vec& y)
{
    const double h = 1e-4;
    Vec g(y.size());
    for (long i = 0; i < y.size(); ++i) {
        Vec yp = y, ym = y;
        yp[i] += h;
        ym[i] -= h;
        g[i] = (fixed_rotation_energy(mesh, m, fem, yp) - fixed_rotation_energy(mesh, m, fem, ym)) / (2 * h);
    }
    return g;
}
}  // namespace

TEST(FemCorotated, StiffnessIsJacobianOfForceWithRotationsFixed)
{
    // Deformed state: with the rotations of x held fixed the elastic force is linear, grad_R(y) =
    // K y - f0, so finite differences of the fixed-rotation energy must give K (y - x) between two
    // states y and x, and grad E(x) at y = x; K is symmetric PSD with translations in its null space.
    const TetMesh mesh = small_box();
    const Material material{1e6, 0.4, 1000};
    CorotatedFem fem(mesh.positions, mesh.tets, {material});
    const Vec x = flat(mesh.positions) + random_perturbation(3 * mesh.vertices(), 0.03, 7);
    fem.update(x);
    SpMat K;
    fem.assemble(0.0, 1.0, K);
    const Eigen::MatrixXd Kd = Eigen::MatrixXd(K);
    const Vec gx = fixed_rotation_gradient(mesh, material, fem, x);
    const double scale = fem.gradient().lpNorm<Eigen::Infinity>();
    ASSERT_GT(scale, 1.0);  // a real deformation
    EXPECT_LT((gx - fem.gradient()).lpNorm<Eigen::Infinity>(), 1e-6 * scale);
    for (unsigned seed : {11u, 12u}) {
        const Vec d = random_perturbation(x.size(), 0.01, seed);
        const Vec force_change = fixed_rotation_gradient(mesh, material, fem, x + d) - gx;
        const Vec Kd_y = K * d;
        ASSERT_GT(Kd_y.lpNorm<Eigen::Infinity>(), 1.0);
        EXPECT_LT((force_change - Kd_y).lpNorm<Eigen::Infinity>(), 1e-6 * Kd_y.lpNorm<Eigen::Infinity>()) << seed;
    }
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(Kd);
    EXPECT_GT(es.eigenvalues().minCoeff(), -1e-8 * es.eigenvalues().maxCoeff());
    EXPECT_LT((Kd - Kd.transpose()).lpNorm<Eigen::Infinity>(), 1e-9 * Kd.lpNorm<Eigen::Infinity>());
    Vec t(x.size());
    for (long i = 0; i < mesh.vertices(); ++i) t.segment<3>(3 * i) = Vec3(1, -2, 0.5);
    EXPECT_LT((K * t).norm(), 1e-8 * Kd.norm());
}

TEST(FemCorotated, EnergyIsRotationInvariant)
{
    const TetMesh mesh = small_box();
    CorotatedFem fem(mesh.positions, mesh.tets, {Material{2e6, 0.45, 1000}});
    const Vec x = flat(mesh.positions) + random_perturbation(3 * mesh.vertices(), 0.03, 3);
    const double e = fem.energy(x);
    ASSERT_GT(e, 0);
    for (const Vec3& angles : {Vec3(90, 0, 0), Vec3(12, 34, 56), Vec3(-170, 80, 5)}) {
        const Eigen::Matrix3d R = rotation_from_euler_deg(angles);
        Vec y(x.size());
        for (long i = 0; i < mesh.vertices(); ++i) y.segment<3>(3 * i) = R * x.segment<3>(3 * i) + Vec3(1, 2, 3);
        EXPECT_NEAR(fem.energy(y), e, 1e-10 * e);
    }
    EXPECT_NEAR(fem.energy(flat(mesh.positions)), 0.0, 1e-20);
}

TEST(FemCorotated, InvertedTetIsFiniteAndPushesBack)
{
    Positions p(4, 3);
    p << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1;
    Tets t(1, 4);
    t << 0, 1, 2, 3;
    CorotatedFem fem(p, t, {Material{1e3, 0.3, 1}});
    Vec x = flat(p);
    x[11] = -0.5;  // vertex 3 through the opposite face
    fem.update(x);
    EXPECT_TRUE(fem.gradient().allFinite());
    EXPECT_LT(fem.gradient()[11], 0.0);  // force -grad points up (+z): restores the orientation
    EXPECT_NEAR(fem.rotation(0).determinant(), 1.0, 1e-12);
}

TEST(Integrator, FreeFallQpMatchesBackwardEuler)
{
    // Without stiffness effects (rest state) and damping: x = x_n + h v_n + h^2 g.
    const TetMesh mesh = small_box();
    CorotatedFem fem(mesh.positions, mesh.tets, {Material{1e6, 0.4, 1000}});
    StepParameters p;
    p.h = 0.01;
    const Vec x = flat(mesh.positions);
    Vec v(x.size());
    for (long i = 0; i < mesh.vertices(); ++i) v.segment<3>(3 * i) = Vec3(0.5, -1, 2);
    SpMat A;
    Vec b;
    assemble_newton_qp(fem, p, x, v, x, A, b);
    const SpMatCol Acol(A);
    Eigen::SimplicialLDLT<SpMatCol> ldlt(Acol);
    const Vec x1 = ldlt.solve(b);
    for (long i = 0; i < mesh.vertices(); ++i) {
        const Vec3 expect = x.segment<3>(3 * i) + p.h * Vec3(0.5, -1, 2) + p.h * p.h * p.gravity;
        EXPECT_LT((x1.segment<3>(3 * i) - expect).norm(), 1e-9);
    }
    // A = (1 + h a_M) M + (h^2 + h a_K) K: check the diagonal against the formula.
    p.a_M = 0.3;
    p.a_K = 0.02;
    assemble_newton_qp(fem, p, x, v, x, A, b);
    SpMat K;
    fem.assemble(0.0, 1.0, K);
    const double m0 = fem.vertex_mass()[0];
    EXPECT_NEAR(A.coeff(0, 0), (1 + p.h * p.a_M) * m0 + (p.h * p.h + p.h * p.a_K) * K.coeff(0, 0),
                1e-12 * A.coeff(0, 0));
}
