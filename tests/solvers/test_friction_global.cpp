// Issue 48, global frictional problems: the reduction to the local problem (W = H' M^-1 H,
// q = w + H' M^-1 f by a sparse Cholesky of M) equals a dense computation on every real global
// file of tests/data/fclib, and the harness's global error (solvers/measure/friction_error.hpp) equals
// Siconos' own gfc3d_compute_error to 1e-12 relative there: at r = 0, at random points and at
// solutions (ours and Siconos' NSN's), plus 1e-16 absolute where the error is of the order of the
// rounding of M v and H r.
#include "problems/fclib_io.hpp"
#include "solvers/friction/friction_global_nsgs.hpp"
#include "solvers/friction/friction_global_reduction.hpp"
#include "solvers/measure/friction_error.hpp"
#include "solvers/peers/siconos_gfc3d.hpp"
#include "tests/solvers/fclib_data.hpp"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <filesystem>
#include <random>

namespace {

const char* const GLOBAL_FILES[] = {"CubeH8.hdf5",
                                    "LMGC_GlobalFrictionContactProblem00046.hdf5",
                                    "LMGC_GFC3D-i00001-1-00000.hdf5",
                                    "LMGC_GFC3D-i00501-4-00000.hdf5",
                                    "Box_Stacks-i0122-82-5.hdf5",
                                    "spheres-in-a-box-98-i10000-256-10.hdf5"};

cb::Vec random_vector(Eigen::Index n, double scale, std::mt19937& rng)
{
    std::normal_distribution<double> g(0.0, scale);
    cb::Vec x(n);
    for (Eigen::Index k = 0; k < n; ++k) x[k] = g(rng);
    return x;
}

TEST(FrictionGlobal, ReductionEqualsTheDenseComputationOnTheRealFiles)
{
    if (cb::fclib_version().empty()) GTEST_SKIP() << "FCLIB import not built (libfclib-dev missing)";
    for (const char* name : GLOBAL_FILES) {
        const cb::FrictionGlobal p = cb::read_fclib_global_friction((cb::test::FCLIB_DATA / name).string());
        const cb::GlobalReduction reduction(p);
        const Eigen::MatrixXd M(p.M), H(p.H);
        const Eigen::LLT<Eigen::MatrixXd> llt(M);
        ASSERT_EQ(llt.info(), Eigen::Success) << name;
        const Eigen::MatrixXd W = H.transpose() * llt.solve(H);
        const cb::Vec q = p.w + H.transpose() * llt.solve(p.f);
        const Eigen::MatrixXd ours(reduction.local().W);
        EXPECT_LE((ours - W).cwiseAbs().maxCoeff(), 1e-12 * W.cwiseAbs().maxCoeff()) << name;
        EXPECT_LE((reduction.local().q - q).cwiseAbs().maxCoeff(), 1e-12 * q.cwiseAbs().maxCoeff()) << name;
        EXPECT_EQ(reduction.local().mu, p.mu) << name;
        // v = M^-1 (H r + f) solves the equation of motion, and then u = H'v + w = W r + q.
        std::mt19937 rng(7);
        const cb::Vec r = random_vector(3 * p.contacts(), 1.0, rng);
        const cb::Vec v = reduction.velocity(r);
        const cb::Vec rhs = p.H * r + p.f;
        EXPECT_LE((p.M * v - rhs).norm(), 1e-12 * rhs.norm()) << name;
        const cb::Vec u = p.H.transpose() * v + p.w, u_local = reduction.local().W * r + reduction.local().q;
        EXPECT_LE((u - u_local).norm(), 1e-10 * u.norm()) << name;
    }
}

TEST(FrictionGlobal, ReductionRefusesAnMThatIsNotPositiveDefinite)
{
    cb::FrictionGlobal p;
    p.M.resize(3, 3);
    p.M.insert(0, 0) = 1.0;
    p.M.insert(1, 1) = -1.0;
    p.M.insert(2, 2) = 1.0;
    p.H.resize(3, 3);
    p.H.setIdentity();
    p.f = cb::Vec::Ones(3);
    p.w = cb::Vec::Zero(3);
    p.mu = cb::Vec::Constant(1, 0.5);
    p.name = "made.hdf5";
    try {
        const cb::GlobalReduction reduction(p);
        FAIL() << "no error";
    } catch (const cb::InputError& e) {
        EXPECT_STREQ(e.what(), "made.hdf5: /fclib_global/M: not positive definite (its sparse Cholesky factorisation "
                               "failed): the global problem cannot be reduced to W = H' M^-1 H");
    }
}

void expect_same_global_error(const cb::FrictionGlobal& p, const cb::Vec& r, const cb::Vec& v, const std::string& where)
{
    const double ours = cb::global_relative_error(p, r, v), theirs = cb::siconos_gfc3d_error(p, r, v);
    EXPECT_NEAR(ours, theirs, 1e-12 * theirs + 1e-16) << where;
}

TEST(FrictionGlobal, ErrorMatchesSiconosGfc3dComputeErrorOnTheRealFiles)
{
    if (cb::fclib_version().empty()) GTEST_SKIP() << "FCLIB import not built (libfclib-dev missing)";
    if (!cb::siconos_gfc3d_built()) GTEST_SKIP() << "Siconos numerics is not built";
    std::mt19937 rng(48);
    for (const char* name : GLOBAL_FILES) {
        const cb::FrictionGlobal p = cb::read_fclib_global_friction((cb::test::FCLIB_DATA / name).string());
        const Eigen::Index m3 = 3 * p.contacts(), n = p.unknowns();
        expect_same_global_error(p, cb::Vec::Zero(m3), cb::Vec::Zero(n), std::string(name) + " at 0");
        const cb::GlobalReduction reduction(p);
        for (const double scale : {1e-6, 1e-2, 1.0, 1e3})
            for (int t = 0; t < 3; ++t) {
                const cb::Vec r = random_vector(m3, scale, rng);
                expect_same_global_error(p, r, random_vector(n, scale, rng), std::string(name) + " random");
                // v consistent with r: the equilibrium term is rounding, the natural map dominates
                expect_same_global_error(p, r, reduction.velocity(r), std::string(name) + " random, v(r)");
            }
        cb::FrictionNsgsSettings s;
        s.max_iterations = 300;
        const cb::FrictionGlobalRun nsgs = cb::friction_nsgs_global(p, reduction, s);
        expect_same_global_error(p, nsgs.run.r, nsgs.v, std::string(name) + " at nsgs's (r, v)");
        const cb::FrictionGlobalRun nsn = cb::siconos_gfc3d_solve(p, "nsn", 100, 1e-10, 60.0);
        expect_same_global_error(p, nsn.run.r, nsn.v, std::string(name) + " at Siconos NSN's (r, v)");
    }
}

}  // namespace
