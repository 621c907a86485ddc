// Issue 48: FCLIB local problems solved with their friction. On the two real local files of
// tests/data/fclib (Capsules-i125-1213: 286 contacts, mu = 0.7, W not symmetric; LMGC_100_PR_PerioBox:
// 60 contacts, mu 0.3-0.5), our nsgs and Siconos' fc3d NSGS and NSN, each judged by the FCLIB
// relative error the harness computes (/ ||q||). The one exception is stated with the number
// reached; hostile frictional files end in exit 2 naming the field.
#include "problems/fclib_io.hpp"
#include "solvers/friction/friction_nsgs.hpp"
#include "solvers/measure/friction_error.hpp"
#include "solvers/peers/siconos_fc3d.hpp"
#include "tests/harness/cli_test_util.hpp"
#include "tests/problems/hdf5_edit.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <limits>

namespace {

namespace fs = std::filesystem;
using cb::test::run_captured;

const fs::path DATA = fs::path(CB_TEST_DATA_DIR) / "fclib";
const fs::path CAPSULES = DATA / "Capsules-i125-1213.hdf5";
const fs::path LMGC = DATA / "LMGC_100_PR_PerioBox-i00361-60-03000.hdf5";

TEST(FclibFriction, ReadsTheRealLocalFilesWithTheirFriction)
{
    if (cb::fclib_version().empty()) GTEST_SKIP() << "FCLIB import not built (libfclib-dev missing)";
    const cb::FrictionLocal c = cb::read_fclib_local_friction(CAPSULES.string());
    EXPECT_EQ(c.contacts(), 286);
    EXPECT_EQ(c.W.rows(), 858);
    EXPECT_EQ(c.mu.minCoeff(), 0.7);
    EXPECT_EQ(c.mu.maxCoeff(), 0.7);
    const cb::FrictionLocal l = cb::read_fclib_local_friction(LMGC.string());
    EXPECT_EQ(l.contacts(), 60);
    EXPECT_EQ(l.mu.minCoeff(), 0.3);
    EXPECT_EQ(l.mu.maxCoeff(), 0.5);
}

TEST(FclibFriction, OurNsgsReachesTheFclibErrorOnBothFiles)
{
    if (cb::fclib_version().empty()) GTEST_SKIP() << "FCLIB import not built (libfclib-dev missing)";
    for (const fs::path& file : {CAPSULES, LMGC}) {
        const cb::FrictionLocal p = cb::read_fclib_local_friction(file.string());
        cb::FrictionNsgsSettings s;  // tol 1e-8 (the issue asks 1e-6 of nsgs)
        const cb::FrictionRun run = cb::friction_nsgs(p, s);
        EXPECT_EQ(run.status, "converged") << file;
        EXPECT_LE(run.error, 1e-8) << file;
        EXPECT_EQ(run.error, cb::fclib_relative_error(p, run.r)) << file;  // the harness's number
        // Measured: 2302 sweeps (Capsules), 866 (LMGC); deterministic, so pinned loosely.
        EXPECT_LT(run.iterations, 5000) << file;
    }
}

TEST(FclibFriction, SiconosPeersOnBothFiles)
{
    if (cb::fclib_version().empty()) GTEST_SKIP() << "FCLIB import not built (libfclib-dev missing)";
    if (!cb::siconos_fc3d_built()) GTEST_SKIP() << "Siconos numerics is not built";
    for (const fs::path& file : {CAPSULES, LMGC}) {
        const cb::FrictionLocal p = cb::read_fclib_local_friction(file.string());
        const cb::FrictionRun nsgs = cb::siconos_fc3d_solve(p, "nsgs", 10000, 1e-8, 120.0);
        EXPECT_EQ(nsgs.status, "converged") << file << " " << nsgs.note;
        EXPECT_LE(nsgs.error, 1e-8) << file;
    }
    const cb::FrictionLocal capsules = cb::read_fclib_local_friction(CAPSULES.string());
    const cb::FrictionRun nsn = cb::siconos_fc3d_solve(capsules, "nsn", 500, 1e-8, 120.0);
    EXPECT_EQ(nsn.status, "converged") << nsn.note;
    EXPECT_LE(nsn.error, 1e-8);
    // The exception: NSN on LMGC_100_PR_PerioBox stops where its own error (scaled by
    // max(||q||, ||u||, ||r||), and ||r|| is 6e5 ||q|| there: W ~ 1e-4) is 3.6e-9, at an FCLIB error
    // of 2.3e-3; called again from there with its tolerance scaled to FCLIB's (1.6e-14) it does
    // not converge (measured: 10000 Newton steps, FCLIB error 674), so the first round's r stands.
    const cb::FrictionLocal lmgc = cb::read_fclib_local_friction(LMGC.string());
    const cb::FrictionRun stuck = cb::siconos_fc3d_solve(lmgc, "nsn", 200, 1e-8, 120.0);
    EXPECT_NE(stuck.status, "converged");
    EXPECT_NEAR(stuck.error, 2.312e-3, 0.01e-3) << stuck.note;
    EXPECT_LE(cb::siconos_relative_error(lmgc, stuck.r), 1e-8);
}

TEST(FclibFriction, SiconosProximalPointAndAdmmPeersOnBothFiles)
{
    if (cb::fclib_version().empty()) GTEST_SKIP() << "FCLIB import not built (libfclib-dev missing)";
    if (!cb::siconos_fc3d_built()) GTEST_SKIP() << "Siconos numerics is not built";
    for (const fs::path& file : {CAPSULES, LMGC}) {
        const cb::FrictionLocal p = cb::read_fclib_local_friction(file.string());
        const cb::FrictionRun prox = cb::siconos_fc3d_solve(p, "prox", 1000, 1e-8, 120.0);
        EXPECT_EQ(prox.solver, "siconos-prox");
        EXPECT_EQ(prox.status, "converged") << file << " " << prox.note;
        EXPECT_LE(prox.error, 1e-8) << file;
        EXPECT_EQ(prox.error, cb::fclib_relative_error(p, prox.r)) << file;
    }
    const cb::FrictionLocal capsules = cb::read_fclib_local_friction(CAPSULES.string());
    const cb::FrictionRun admm = cb::siconos_fc3d_solve(capsules, "admm", 10000, 1e-8, 120.0);
    EXPECT_EQ(admm.status, "converged") << admm.note;
    EXPECT_LE(admm.error, 1e-8);
    // The exception: ADMM on LMGC_100_PR_PerioBox (||r|| ~ 6e5 ||q||) stays far from a solution:
    // FCLIB error 0.92 after 1000 iterations (0.89 after 10000), 2e-3 by Siconos' own scale.
    const cb::FrictionLocal lmgc = cb::read_fclib_local_friction(LMGC.string());
    const cb::FrictionRun stuck = cb::siconos_fc3d_solve(lmgc, "admm", 1000, 1e-8, 120.0);
    EXPECT_EQ(stuck.status, "max_iterations") << stuck.note;
    EXPECT_NEAR(stuck.error, 0.9237, 0.0005) << stuck.note;
}

/// A copy of LMGC_100_PR_PerioBox with one dataset replaced, read by friction-solve.
struct Mutant {
    fs::path dir = cb::test::make_test_work_dir("fclib_friction");
    fs::path file = dir / "mutant.hdf5";
    template <typename Edit> cb::test::Output solve_after(Edit edit)
    {
        fs::copy_file(LMGC, file, fs::copy_options::overwrite_existing);
        {
            cb::test::Hdf5Edit f(file.string(), false);
            edit(f);
        }
        return run_captured(cb::test::contactbench_binary() + " friction-solve '" + file.string() + "' --solver nsgs",
                            dir);
    }
};

TEST(FclibFriction, HostileFrictionalFilesEndInExitTwoNamingTheField)
{
    if (cb::fclib_version().empty()) GTEST_SKIP() << "FCLIB import not built (libfclib-dev missing)";
    Mutant m;
    const std::string f = m.file.string() + ": ";
    std::vector<double> mu(60, 0.3);
    mu[4] = -0.25;
    cb::test::Output o = m.solve_after([&](auto& h) { h.put_reals("/fclib_local/vectors/mu", mu); });
    EXPECT_EQ(o.status, 2);
    EXPECT_EQ(o.err,
              "contactbench friction-solve: error: " + f +
                  "/fclib_local/vectors/mu: contact 4 has mu = -0.25 (a friction coefficient is finite and >= 0)\n");
    EXPECT_EQ(o.out, "");
    mu[4] = std::numeric_limits<double>::quiet_NaN();
    o = m.solve_after([&](auto& h) { h.put_reals("/fclib_local/vectors/mu", mu); });
    EXPECT_EQ(o.status, 2);
    EXPECT_EQ(o.err,
              "contactbench friction-solve: error: " + f +
                  "/fclib_local/vectors/mu: contact 4 has mu = nan (a friction coefficient is finite and >= 0)\n");
    o = m.solve_after([&](auto& h) { h.put_ints("/fclib_local/spacedim", {2}); });
    EXPECT_EQ(o.status, 2);
    EXPECT_EQ(o.err, "contactbench friction-solve: error: " + f +
                         "/fclib_local/spacedim: is 2: only 3-D frictional problems (spacedim 3) are solved\n");
    o = m.solve_after([&](auto& h) { h.put_ints("/fclib_local/W/n", {179}); });
    EXPECT_EQ(o.status, 2);
    EXPECT_EQ(o.err, "contactbench friction-solve: error: " + f + "/fclib_local/W: not square: m = 180, n = 179\n");
    o = m.solve_after([&](auto& h) { h.put_reals("/fclib_local/vectors/q", std::vector<double>(179, 0.0)); });
    EXPECT_EQ(o.status, 2);
    EXPECT_EQ(o.err, "contactbench friction-solve: error: " + f +
                         "/fclib_local/vectors/q: holds 179 values, /fclib_local/W/m declares 180\n");
    // A global problem asked for as a local one is named as such (friction-solve takes both kinds:
    // tests/problems/test_fclib_friction_global.cpp).
    try {
        cb::read_fclib_local_friction((DATA / "CubeH8.hdf5").string());
        ADD_FAILURE() << "no error";
    } catch (const cb::InputError& e) {
        EXPECT_EQ(std::string(e.what()), (DATA / "CubeH8.hdf5").string() +
                                             ": /fclib_local: missing: this is an fclib_global problem, not an "
                                             "fclib_local one");
    }
}

TEST(FclibFriction, NsgsRefusesABlockThatIsNotPositiveDefiniteWithoutPartialOutput)
{
    if (cb::fclib_version().empty()) GTEST_SKIP() << "FCLIB import not built (libfclib-dev missing)";
    const fs::path dir = cb::test::make_test_work_dir("friction_not_pd");
    const fs::path file = dir / "one.hdf5";
    {
        cb::test::Hdf5Edit f(file.string(), true);  // one contact, W = diag(-1, 1, 1) as CSR
        f.put_ints("/fclib_local/spacedim", {3});
        f.put_ints("/fclib_local/W/nzmax", {3});
        f.put_ints("/fclib_local/W/m", {3});
        f.put_ints("/fclib_local/W/n", {3});
        f.put_ints("/fclib_local/W/nz", {-2});
        f.put_ints("/fclib_local/W/p", {0, 1, 2, 3});
        f.put_ints("/fclib_local/W/i", {0, 1, 2});
        f.put_reals("/fclib_local/W/x", {-1.0, 1.0, 1.0});
        f.put_reals("/fclib_local/vectors/q", {-1.0, 0.0, 0.0});
        f.put_reals("/fclib_local/vectors/mu", {0.5});
    }
    const cb::test::Output o =
        run_captured(cb::test::contactbench_binary() + " friction-solve '" + file.string() + "' --solver nsgs", dir);
    EXPECT_EQ(o.status, 2);
    EXPECT_EQ(o.out, "");
    EXPECT_EQ(o.err, "contactbench friction-solve: error: " + file.string() +
                         ": W: the diagonal block of contact 0 is not positive definite (smallest eigenvalue of its "
                         "symmetric part -1.000000): nsgs needs each one-contact problem to have a unique solution\n");
}

TEST(FclibFriction, CommandPrintsTheTableAndWritesJson)
{
    if (cb::fclib_version().empty()) GTEST_SKIP() << "FCLIB import not built (libfclib-dev missing)";
    const fs::path dir = cb::test::make_test_work_dir("friction_solve");
    const cb::test::Output o = run_captured(cb::test::contactbench_binary() + " friction-solve '" + LMGC.string() +
                                                "' --solver nsgs --tol 1e-6 --json '" + (dir / "r.json").string() + "'",
                                            dir);
    ASSERT_EQ(o.status, 0) << o.err;
    EXPECT_EQ(o.out.substr(0, o.out.find('\n')),
              "solver         status             iters     time_s  fclib_error  siconos_err");
    const nlohmann::json j = nlohmann::json::parse(cb::test::slurp(dir / "r.json"));
    ASSERT_EQ(j["runs"].size(), 1u);
    EXPECT_EQ(j["runs"][0]["solver"], "nsgs");
    EXPECT_EQ(j["runs"][0]["status"], "converged");
    EXPECT_LE(j["runs"][0]["fclib_error"].get<double>(), 1e-6);
    EXPECT_EQ(j["contacts"], 60);
    // A bad option value: exit 2, nothing written.
    const cb::test::Output bad =
        run_captured(cb::test::contactbench_binary() + " friction-solve '" + LMGC.string() + "' --solver pgs", dir);
    EXPECT_EQ(bad.status, 2);
    EXPECT_EQ(bad.err, "contactbench friction-solve: error: --solver: unknown frictional solver 'pgs' (nsgs, "
                       "mprgp-tresca-fp, mprgp+ica-friction, siconos-nsgs, siconos-nsn, siconos-prox, siconos-admm)\n");
}

}  // namespace
