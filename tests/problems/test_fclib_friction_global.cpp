// Issue 48: FCLIB global problems solved with their friction. Every real global file of
// tests/data/fclib imports (sizes, mu, M symmetric positive definite); on each, Siconos' gfc3d
// NSN peer reaches the harness's global FCLIB error <= 1e-8 and our nsgs (on the reduced
// problem) <= 1e-6, except where stated below with the reason and the error reached (asserted,
// not skipped). Hostile global files end in exit 2 naming the field; friction-solve takes them.
#include "problems/fclib_io.hpp"
#include "solvers/friction_error.hpp"
#include "solvers/friction_global_nsgs.hpp"
#include "solvers/friction_global_reduction.hpp"
#include "solvers/peers/siconos_gfc3d.hpp"
#include "tests/harness/cli_test_util.hpp"
#include "tests/problems/hdf5_edit.hpp"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <filesystem>
#include <limits>

namespace {

namespace fs = std::filesystem;
using cb::test::run_captured;

const fs::path DATA = fs::path(CB_TEST_DATA_DIR) / "fclib";

struct GlobalFile {
    const char* name;
    Eigen::Index contacts, unknowns;
    double mu;
};

const GlobalFile FILES[] = {
    {"CubeH8.hdf5", 1, 162, 0.3},
    {"LMGC_GlobalFrictionContactProblem00046.hdf5", 9, 162, 0.3},
    {"LMGC_GFC3D-i00001-1-00000.hdf5", 1, 48, 0.3},
    {"LMGC_GFC3D-i00501-4-00000.hdf5", 4, 162, 0.3},
    {"Box_Stacks-i0122-82-5.hdf5", 82, 450, 0.3},
    {"spheres-in-a-box-98-i10000-256-10.hdf5", 256, 588, 0.1},
};

bool skip_without_fclib() { return cb::fclib_version().empty(); }

TEST(FclibFrictionGlobal, EveryRealGlobalFileImports)
{
    if (skip_without_fclib()) GTEST_SKIP() << "FCLIB import not built (libfclib-dev missing)";
    for (const GlobalFile& g : FILES) {
        const cb::FrictionGlobal p = cb::read_fclib_global_friction((DATA / g.name).string());
        EXPECT_EQ(p.contacts(), g.contacts) << g.name;
        EXPECT_EQ(p.unknowns(), g.unknowns) << g.name;
        EXPECT_EQ(p.H.rows(), g.unknowns) << g.name;
        EXPECT_EQ(p.H.cols(), 3 * g.contacts) << g.name;
        EXPECT_EQ(p.w.size(), 3 * g.contacts) << g.name;
        EXPECT_EQ(p.mu.minCoeff(), g.mu) << g.name;
        EXPECT_EQ(p.mu.maxCoeff(), g.mu) << g.name;
        // M mirrored when stored as one triangle, otherwise symmetric to rounding (the two LMGC_GFC3D
        // files: 3e-14 apart), and positive definite (the reduction factors it).
        EXPECT_LE(cb::SpMat(p.M - cb::SpMat(p.M.transpose())).norm(), 1e-12 * p.M.norm()) << g.name;
        EXPECT_NO_THROW(cb::GlobalReduction{p}) << g.name;
    }
}

TEST(FclibFrictionGlobal, SiconosNsnAndOurNsgsOnEveryRealGlobalFile)
{
    if (skip_without_fclib()) GTEST_SKIP() << "FCLIB import not built (libfclib-dev missing)";
    if (!cb::siconos_gfc3d_built()) GTEST_SKIP() << "Siconos numerics is not built";
    for (const GlobalFile& g : FILES) {
        const std::string name = g.name;
        const cb::FrictionGlobal p = cb::read_fclib_global_friction((DATA / g.name).string());
        const cb::GlobalReduction reduction(p);
        const bool redundant = name == "Box_Stacks-i0122-82-5.hdf5" || name == "spheres-in-a-box-98-i10000-256-10.hdf5";

        const cb::FrictionGlobalRun nsn = cb::siconos_gfc3d_solve(p, "nsn", 200, 1e-8, 120.0);
        EXPECT_EQ(nsn.run.error, cb::global_relative_error(p, nsn.run.r, nsn.v)) << name;  // the harness's number
        if (!redundant) {
            EXPECT_EQ(nsn.run.status, "converged") << name << " " << nsn.run.note;
            EXPECT_LE(nsn.run.error, 1e-8) << name;
        } else {
            // The exception: on these two files H has dependent columns (Box_Stacks: several
            // contacts per box face; spheres-in-a-box: 768 contact columns for 588 unknowns), so
            // the Newton Jacobian of Alart-Curnier's function is singular; Siconos' LU stops at
            // the first step (gfc3d_driver info 1) and returns its start, where the error is 1.
            const Eigen::MatrixXd H(p.H);
            EXPECT_LT(Eigen::ColPivHouseholderQR<Eigen::MatrixXd>(H).rank(), H.cols()) << name;
            EXPECT_EQ(nsn.run.status, "stalled") << name;
            EXPECT_EQ(nsn.run.iterations, 1) << name;
            EXPECT_EQ(nsn.run.note, "gfc3d_driver info 1") << name;
            EXPECT_NEAR(nsn.run.error, 1.0, 1e-12) << name;
        }

        cb::FrictionNsgsSettings s;
        s.tol = 1e-6;
        s.max_iterations = name == "spheres-in-a-box-98-i10000-256-10.hdf5" ? 1000 : 10000;
        const cb::FrictionGlobalRun nsgs = cb::friction_nsgs_global(p, reduction, s);
        EXPECT_EQ(nsgs.run.error, cb::global_relative_error(p, nsgs.run.r, nsgs.v)) << name;
        if (name != "spheres-in-a-box-98-i10000-256-10.hdf5") {
            EXPECT_EQ(nsgs.run.status, "converged") << name << " " << nsgs.run.note;
            EXPECT_LE(nsgs.run.error, 1e-6) << name;
        } else {
            // The exception: W = H' M^-1 H is singular here (rank <= 588 < 768) and NSGS creeps:
            // 1.5e-5 after 1000 sweeps, 1.0e-5 after 10000 (33 s; Siconos' NSGS the same), so the
            // test stops at 1000. Siconos' PROX (fc3d/gfc3d) converges here (docs/peers.md).
            EXPECT_EQ(nsgs.run.status, "max_iterations") << name;
            EXPECT_NEAR(nsgs.run.error, 1.528e-5, 0.005e-5) << name << " " << nsgs.run.note;
        }
    }
}

/// A copy of LMGC_GlobalFrictionContactProblem00046 with one dataset replaced, read by friction-solve.
struct Mutant {
    fs::path dir = cb::test::make_test_work_dir("fclib_friction_global");
    fs::path file = dir / "mutant.hdf5";
    template <typename Edit> cb::test::Output solve_after(Edit edit)
    {
        fs::copy_file(DATA / "LMGC_GlobalFrictionContactProblem00046.hdf5", file, fs::copy_options::overwrite_existing);
        {
            cb::test::Hdf5Edit f(file.string(), false);
            edit(f);
        }
        return run_captured(cb::test::contactbench_binary() + " friction-solve '" + file.string() + "' --solver nsgs",
                            dir);
    }
};

TEST(FclibFrictionGlobal, HostileGlobalFilesEndInExitTwoNamingTheField)
{
    if (skip_without_fclib()) GTEST_SKIP() << "FCLIB import not built (libfclib-dev missing)";
    Mutant m;
    const std::string e = "contactbench friction-solve: error: " + m.file.string() + ": ";
    auto expect = [&](const cb::test::Output& o, const std::string& message) {
        EXPECT_EQ(o.status, 2) << message;
        EXPECT_EQ(o.err, e + message + "\n");
        EXPECT_EQ(o.out, "");
    };
    std::vector<double> mu(9, 0.3);
    mu[4] = -0.25;
    expect(m.solve_after([&](auto& h) { h.put_reals("/fclib_global/vectors/mu", mu); }),
           "/fclib_global/vectors/mu: contact 4 has mu = -0.25 (a friction coefficient is finite and >= 0)");
    mu[4] = std::numeric_limits<double>::quiet_NaN();
    expect(m.solve_after([&](auto& h) { h.put_reals("/fclib_global/vectors/mu", mu); }),
           "/fclib_global/vectors/mu: contact 4 has mu = nan (a friction coefficient is finite and >= 0)");
    // one tangent per contact (spacedim 2)
    expect(m.solve_after([&](auto& h) { h.put_ints("/fclib_global/spacedim", {2}); }),
           "/fclib_global/spacedim: is 2 (one tangent per contact): only 3-D frictional problems (spacedim 3, two "
           "tangents) are solved");
    // frames of the wrong size: H's columns (H' rows) not 3 per contact, w or mu of another length
    expect(m.solve_after([&](auto& h) { h.put_ints("/fclib_global/H/n", {26}); }),
           "/fclib_global/H/n: 26 columns: not 3 per contact (a normal and two tangents)");
    expect(m.solve_after([&](auto& h) { h.put_reals("/fclib_global/vectors/w", std::vector<double>(26, 0.0)); }),
           "/fclib_global/vectors/w: holds 26 values, /fclib_global/H/n declares 27");
    expect(m.solve_after([&](auto& h) { h.put_reals("/fclib_global/vectors/mu", std::vector<double>(8, 0.3)); }),
           "/fclib_global/vectors/mu: holds 8 values, /fclib_global/H/n / 3 declares 9");
    expect(m.solve_after([&](auto& h) { h.put_reals("/fclib_global/vectors/f", std::vector<double>(161, 0.0)); }),
           "/fclib_global/vectors/f: holds 161 values, /fclib_global/M/m declares 162");
    expect(m.solve_after([&](auto& h) { h.put_ints("/fclib_global/H/m", {161}); }),
           "/fclib_global/H/m: 161 rows, but M has 162");
    expect(m.solve_after([&](auto& h) { h.put_ints("/fclib_global/M/n", {161}); }),
           "/fclib_global/M: not square: m = 162, n = 161");
}

TEST(FclibFrictionGlobal, FrictionSolveTakesAGlobalFile)
{
    if (skip_without_fclib()) GTEST_SKIP() << "FCLIB import not built (libfclib-dev missing)";
    const fs::path dir = cb::test::make_test_work_dir("friction_solve_global");
    const fs::path file = DATA / "LMGC_GFC3D-i00501-4-00000.hdf5";
    const cb::test::Output o = run_captured(cb::test::contactbench_binary() + " friction-solve '" + file.string() +
                                                "' --solver nsgs --json '" + (dir / "r.json").string() + "'",
                                            dir);
    ASSERT_EQ(o.status, 0) << o.err;
    EXPECT_EQ(o.out.substr(0, o.out.find('\n')),
              "solver         status             iters     time_s  fclib_error  reduced_err");
    const nlohmann::json j = nlohmann::json::parse(cb::test::slurp(dir / "r.json"));
    EXPECT_EQ(j["kind"], "fclib_global");
    EXPECT_EQ(j["contacts"], 4);
    EXPECT_EQ(j["unknowns"], 162);
    ASSERT_EQ(j["runs"].size(), 1u);
    EXPECT_EQ(j["runs"][0]["status"], "converged");
    EXPECT_LE(j["runs"][0]["fclib_error"].get<double>(), 1e-8);
    // The reduced problem's error is reported beside it, at the same r.
    const cb::FrictionGlobal p = cb::read_fclib_global_friction(file.string());
    const cb::GlobalReduction reduction(p);
    cb::FrictionNsgsSettings s;
    const cb::FrictionGlobalRun run = cb::friction_nsgs_global(p, reduction, s);
    EXPECT_EQ(j["runs"][0]["reduced_error"].get<double>(), cb::fclib_relative_error(reduction.local(), run.run.r));
    EXPECT_EQ(j["runs"][0]["fclib_error"].get<double>(), run.run.error);
}

}  // namespace
