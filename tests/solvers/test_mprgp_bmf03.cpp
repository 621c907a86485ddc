// Issue 45: `mprgp+bmf03`, frictionless mprgp-coupled then BMF03's Coulomb velocity update per
// contact, on particle-on-incline snapshots built here (a backward-Euler step of free particles on
// the plane y >= 0 under gravity tilted by 20 degrees towards +x, as tests/sim/test_friction_incline.cpp).
// For free particles the update is Coulomb's law exactly, so it must agree with nsgs-friction.
#include "solvers/core/registry.hpp"
#include "solvers/friction/mprgp_bmf03.hpp"
#include "solvers/measure/friction_snapshot_error.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace {

using cb::Vec;

constexpr double G = 9.81, H = 0.01, MASS = 0.5;
const double THETA = 20.0 * M_PI / 180.0;

struct Particle {
    double v0;  ///< start velocity along the incline (+x)
    double mu;
};

/// One step of particles resting on the plane y = 0 (particle p at x = p), each with its start
/// velocity and mu: A = m I, b = m (x_n + h v0) + h^2 m g, J: y >= 0, T: x and z, cT = T x_n.
/// `springs` couples neighbours in x by a spring of that stiffness times h^2 (0: free particles).
cb::Qp incline_step(const std::vector<Particle>& particles, double springs = 0.0)
{
    const int k = static_cast<int>(particles.size());
    const Eigen::Index n = 3 * k;
    const Eigen::Vector3d g(G * std::sin(THETA), -G * std::cos(THETA), 0.0);
    std::vector<Eigen::Triplet<double>> a, j, t;
    cb::Qp qp;
    qp.b.resize(n);
    qp.x0.resize(n);
    qp.friction.v0 = Vec::Zero(n);
    qp.friction.mu.resize(k);
    Vec x_n = Vec::Zero(n);
    for (int p = 0; p < k; ++p) {
        x_n[3 * p] = p;
        qp.friction.v0[3 * p] = particles[p].v0;
        qp.friction.mu[p] = particles[p].mu;
        for (int d = 0; d < 3; ++d) a.emplace_back(3 * p + d, 3 * p + d, MASS);
        if (springs > 0.0 && p + 1 < k) {
            const double s = springs * H * H;
            a.emplace_back(3 * p, 3 * p, s);
            a.emplace_back(3 * p + 3, 3 * p + 3, s);
            a.emplace_back(3 * p, 3 * p + 3, -s);
            a.emplace_back(3 * p + 3, 3 * p, -s);
        }
        j.emplace_back(p, 3 * p + 1, 1.0);
        t.emplace_back(2 * p, 3 * p, 1.0);
        t.emplace_back(2 * p + 1, 3 * p + 2, 1.0);
    }
    qp.A.resize(n, n);
    qp.A.setFromTriplets(a.begin(), a.end());
    const Vec inertial = x_n + H * qp.friction.v0;
    for (int p = 0; p < k; ++p) qp.b.segment<3>(3 * p) = MASS * (inertial.segment<3>(3 * p) + H * H * g);
    qp.b += (qp.A - MASS * cb::SpMat(Eigen::MatrixXd::Identity(n, n).sparseView())) * x_n;  // springs at rest
    qp.J.resize(k, n);
    qp.J.setFromTriplets(j.begin(), j.end());
    qp.c = Vec::Zero(k);
    qp.friction.T.resize(2 * k, n);
    qp.friction.T.setFromTriplets(t.begin(), t.end());
    qp.friction.cT = qp.friction.T * x_n;
    qp.friction.h = H;
    qp.x0 = inertial;
    return qp;
}

cb::SolverResult solve_named(const std::string& solver, const cb::Qp& qp, double tol = 1e-10)
{
    return cb::builtin_registry().create(solver, {{"tol", tol}})->solve(qp.view(), cb::SolveContext{});
}

/// Tangential velocity of particle p at the end of the step: (T_p x - cT_p) / h.
Eigen::Vector2d tangential_velocity(const cb::Qp& qp, const Vec& x, int p)
{
    return Eigen::Vector2d(x[3 * p] - qp.friction.cT[2 * p], x[3 * p + 2] - qp.friction.cT[2 * p + 1]) / H;
}

}  // namespace

TEST(MprgpBmf03, StickingParticleEndsWithZeroTangentialVelocity)
{
    // v_T before friction 0.01 + h g sin = 0.0436 m/s; mu dv_N = 0.8 h g cos = 0.0737 m/s: static.
    const cb::Qp qp = incline_step({{0.01, 0.8}});
    const cb::SolverResult r = solve_named("mprgp+bmf03", qp);
    ASSERT_EQ(r.status, cb::SolveStatus::CONVERGED) << r.message;
    EXPECT_LE(tangential_velocity(qp, r.x, 0).norm(), 1e-12);
    EXPECT_EQ(r.info["contacts"]["sticking"], 1);
    EXPECT_NEAR(r.x[1], 0.0, 1e-12);  // on the plane, not pushed off or into it
}

TEST(MprgpBmf03, SlidingParticleLosesExactlyMuDvNOfTangentialSpeed)
{
    const double mu = 0.3, v0 = 1.0;
    const cb::Qp qp = incline_step({{v0, mu}});
    const cb::SolverResult r = solve_named("mprgp+bmf03", qp);
    ASSERT_EQ(r.status, cb::SolveStatus::CONVERGED) << r.message;
    // Frictionless: v_T = v0 + h g sin; the plane took the normal velocity h g cos (dv_N).
    const double v_t = v0 + H * G * std::sin(THETA), dv_n = H * G * std::cos(THETA);
    const Eigen::Vector2d v = tangential_velocity(qp, r.x, 0);
    EXPECT_NEAR(v[0], v_t - mu * dv_n, 1e-12);
    EXPECT_NEAR(v[1], 0.0, 1e-12);
    EXPECT_EQ(r.info["contacts"]["sliding"], 1);
    // The reported multipliers lie on the cone's boundary, opposite the slip.
    EXPECT_NEAR(r.lambda_t[0], -mu * r.lambda[0], 1e-12 * r.lambda[0]);
}

TEST(MprgpBmf03, AtMuZeroItIsMprgpCoupled)
{
    cb::Qp qp = incline_step({{1.0, 0.0}, {0.01, 0.0}, {0.3, 0.0}}, 50.0);
    const cb::SolverResult bmf = solve_named("mprgp+bmf03", qp), coupled = solve_named("mprgp-coupled", qp);
    ASSERT_EQ(bmf.status, cb::SolveStatus::CONVERGED) << bmf.message;
    EXPECT_EQ(bmf.x, coupled.x);
    EXPECT_EQ(bmf.lambda, coupled.lambda);
    EXPECT_EQ(bmf.iterations, coupled.iterations);
    EXPECT_EQ(bmf.message.substr(0, 24), "mprgp+bmf03: converged: ");
}

TEST(MprgpBmf03, AgreesWithNsgsFrictionOnFreeParticles)
{
    // Each particle alone on the plane: BMF03's update is Coulomb's law, two independent solvers.
    const cb::Qp qp = incline_step({{0.01, 0.8}, {1.0, 0.3}, {0.02, 0.9}, {-0.5, 0.2}, {0.0, 0.36}});
    const cb::SolverResult bmf = solve_named("mprgp+bmf03", qp), nsgs = solve_named("nsgs-friction", qp);
    ASSERT_EQ(bmf.status, cb::SolveStatus::CONVERGED) << bmf.message;
    ASSERT_EQ(nsgs.status, cb::SolveStatus::CONVERGED) << nsgs.message;
    EXPECT_LE((bmf.x - nsgs.x).lpNorm<Eigen::Infinity>(), 1e-9);
    EXPECT_LE(bmf.native_residual, 1e-12);  // FCLIB's error at the updated point
    EXPECT_EQ(bmf.info["contacts"]["sticking"], 2);
    EXPECT_EQ(bmf.info["contacts"]["sliding"], 3);
}

TEST(MprgpBmf03, CoupledParticlesEndStalledWithTheErrorsInItsMessage)
{
    // Springs between the particles: the local update ignores them, so the point is not Coulomb's.
    const cb::Qp qp = incline_step({{0.01, 0.8}, {1.0, 0.3}, {0.2, 0.5}, {-0.5, 0.2}}, 500.0);
    const cb::SolverResult r = solve_named("mprgp+bmf03", qp, 1e-8);
    ASSERT_EQ(r.status, cb::SolveStatus::STALLED) << r.message;
    EXPECT_EQ(r.message.substr(0, 63), "mprgp+bmf03: the stop rule does not hold at the returned point:");
    EXPECT_NE(r.message.find("one BMF03 velocity update after mprgp-coupled"), std::string::npos) << r.message;
    EXPECT_GT(r.native_residual, 1e-6);
    EXPECT_EQ(r.lambda_t.size(), 8);
}

TEST(MprgpBmf03, WithoutStepOrStartVelocitiesItIsNotApplicable)
{
    cb::Qp qp = incline_step({{1.0, 0.3}});
    qp.friction.h = 0.0;
    cb::SolverResult r = solve_named("mprgp+bmf03", qp);
    EXPECT_EQ(r.status, cb::SolveStatus::NOT_APPLICABLE);
    EXPECT_EQ(r.message,
              "mprgp+bmf03: a velocity update needs a simulator's frictional step (qpsnap version 2 with h and "
              "v0); this problem has no time step h");
    qp.friction.v0.resize(0);
    r = solve_named("mprgp+bmf03", qp);
    EXPECT_EQ(r.status, cb::SolveStatus::NOT_APPLICABLE);
    EXPECT_NE(r.message.find("no time step h and no start velocities v0"), std::string::npos) << r.message;
    EXPECT_EQ(r.x.size(), qp.n());
}
