// The frictional registry entries beside nsgs-friction (solvers/friction/mprgp_tresca_entries.hpp,
// solvers/peers/siconos_friction.hpp) through the runner: converged on the frictional e of a snapshot
// where some contacts stick and some slide, FCLIB's error and x agreeing with nsgs-friction's; at
// mu = 0 mprgp-tresca-fp is mprgp-box on the normal block; `contactbench solve` runs each.
#include "../harness/cli_test_util.hpp"
#include "friction_test_qps.hpp"
#include "harness/runner.hpp"
#include "problems/qpsnap.hpp"
#include "problems/synthetic.hpp"
#include "solvers/core/registry.hpp"
#include "solvers/friction/friction_dual.hpp"
#include "solvers/friction/friction_nsgs.hpp"
#include "solvers/friction/friction_snapshot_solve.hpp"
#include "solvers/measure/accuracy.hpp"
#include "solvers/measure/friction_error.hpp"
#include "solvers/mprgp/mprgp_box.hpp"
#include "tests/solvers/max_abs.hpp"
#include "tests/solvers/quiet_run_options.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace cb {
namespace {

using test::contactbench_binary;
using test::make_test_work_dir;
using test::Output;
using test::run_captured;
using testing_qps::particles_on_a_plane;

const std::vector<std::string> NEW_ENTRIES = {"mprgp-tresca-fp", "mprgp+ica-friction", "siconos-fc3d-nsgs",
                                              "siconos-fc3d-nsn", "siconos-gfc3d-nsn"};
/// Siconos 4.4's global Newton fails at its first step on the stick-and-slide snapshot (its LU of the
/// Newton matrix: `friction-solve` on the same problem as FCLIB global says so too); the run must say so.
const std::string GFC3D_NSN_FAILS = "siconos-gfc3d-nsn";

bool is_peer(const std::string& name) { return name.rfind("siconos-", 0) == 0; }

/// The two frictional snapshots: a deformable body pushed sideways by 0.2 of its weight with mu = 0.5
/// (some contacts stick, some slide: tests/solvers/test_nsgs_friction.cpp counts them), and 12
/// particles half sticking, half sliding.
struct Snapshot {
    std::string name;
    Qp qp;
    RunOutcome reference;  ///< nsgs-friction far below the tolerance under test
};

const std::vector<Snapshot>& snapshots()
{
    static const std::vector<Snapshot> all = [] {
        std::vector<Snapshot> out;
        out.push_back({"pushed body", testing_qps::pushed_plane(0.2, 0.5), {}});
        out.push_back({"particles", particles_on_a_plane(12), {}});
        for (Snapshot& s : out)
            s.reference = run_solver(s.qp, "nsgs-friction", {{"tol", 1e-10}, {"max_iterations", 100000}},
                                     test::quiet_run_options());
        return out;
    }();
    return all;
}

class FrictionRegistry : public ::testing::TestWithParam<std::string> {};

TEST_P(FrictionRegistry, ConvergesOnTheFrictionalErrorAndAgreesWithNsgsFriction)
{
    const std::string name = GetParam();
    if (!builtin_registry().contains(name)) {
        ASSERT_TRUE(is_peer(name)) << name << " is built into every binary";
        GTEST_SKIP() << name << " is not built (Siconos numerics not found: CB_PEERS off or the package missing)";
    }
    for (const Snapshot& snapshot : snapshots()) {
        const std::string what = name + " on " + snapshot.name;
        const Qp& qp = snapshot.qp;
        ASSERT_TRUE(qp.frictional());
        const RunOutcome& ref = snapshot.reference;
        ASSERT_EQ(ref.status, "converged") << ref.result.message;
        const RunOutcome run = run_solver(qp, name, {{"tol", 1e-6}}, test::quiet_run_options());
        if (name == GFC3D_NSN_FAILS && snapshot.name == "pushed body") {
            EXPECT_EQ(run.status, "stalled") << run.result.message;
            EXPECT_NE(run.result.message.find("gfc3d_driver info 1"), std::string::npos) << run.result.message;
            EXPECT_GT(run.accuracy.max(), 1e-2);
            continue;
        }
        ASSERT_EQ(run.status, "converged") << what << ": " << run.result.message;
        EXPECT_LE(run.accuracy.max(), 1e-6) << what;
        EXPECT_TRUE(run.record["accuracy"].contains("friction")) << what;
        ASSERT_EQ(run.result.lambda_t.size(), 2 * qp.m());
        ASSERT_TRUE(run.record.contains("fclib_error"));
        const double fclib = run.record["fclib_error"].get<double>();
        EXPECT_LE(fclib, 1e-5) << what;
        if (name.rfind("siconos-gfc3d-", 0) != 0) {
            // x = A^-1 (b + H'r): the snapshot's FCLIB error is the local problem's, the native residual.
            EXPECT_NEAR(fclib, run.result.native_residual, 1e-9 * fclib + 1e-13) << what;
        }
        // The same point as nsgs-friction's: x to 1e-6 of the scene size, the forces to 5e-4 of the
        // largest normal force (measured at tol 1e-6: at most 7.6e-5, mprgp-tresca-fp's tangential ones).
        const double l = run.scale.length;
        EXPECT_LE(test::max_abs(run.result.x - ref.result.x) / l, 1e-6) << what;
        const double force = test::max_abs(ref.lambda_full);
        EXPECT_LE(test::max_abs(run.lambda_full - ref.lambda_full), 5e-4 * force) << what;
        EXPECT_LE(test::max_abs(run.result.lambda_t - ref.result.lambda_t), 5e-4 * force) << what;
    }
}

// The measure's scale is formed in the setup of every frictional solver that forms a local problem,
// as in the frictionless ones (a solve-time comparison would charge it to these alone otherwise), and
// the setup's parts sum to setup_s. On the frictional particles, where mprgp-staggered runs its own
// path (without friction it hands the QP to mprgp-coupled).
TEST(FrictionSetupPhases, TheMeasureScaleIsPartOfTheSetup)
{
    const Qp qp = particles_on_a_plane(12);
    ASSERT_TRUE(qp.frictional());
    std::vector<std::string> names = {"nsgs-friction", "mprgp-staggered", "mprgp-tresca-fp", "mprgp+ica-friction"};
    for (const char* peer : {"siconos-fc3d-nsgs", "siconos-fc3d-nsn"})
        if (builtin_registry().contains(peer)) names.emplace_back(peer);
    for (const std::string& name : names) {
        const SolverResult r = builtin_registry().create(name, {{"tol", 1e-6}})->solve(qp.view(), {});
        ASSERT_TRUE(r.info.contains("setup_phases_s")) << name << " reports no setup phases";
        const nlohmann::json& phases = r.info["setup_phases_s"];
        ASSERT_TRUE(phases.contains("measure_scale")) << name << ": " << phases.dump();
        double sum = 0.0;
        for (const auto& [key, value] : phases.items()) sum += value.get<double>();
        EXPECT_NEAR(sum, r.setup_s, 1e-9) << name;
        EXPECT_GT(r.solve_s, 0.0) << name;
    }
}

TEST_P(FrictionRegistry, RunsAtMuZeroWithAndWithoutFrictionFields)
{
    const std::string name = GetParam();
    if (!builtin_registry().contains(name)) GTEST_SKIP() << name << " is not built (Siconos numerics not found)";
    Qp qp = make_synthetic("plane", {{"nx", 3}, {"ny", 2}, {"nz", 3}}, 5);
    const RunOutcome exact = run_solver(qp, "active-set", {{"tol", 1e-12}}, test::quiet_run_options());
    ASSERT_EQ(exact.status, "converged");
    for (const bool with_fields : {false, true}) {
        if (with_fields) testing_qps::add_friction(qp, [](Eigen::Index) { return 0.0; });
        const std::string what = name + (with_fields ? " (mu = 0 given)" : " (no friction fields)");
        const RunOutcome run = run_solver(qp, name, {{"tol", 1e-6}}, test::quiet_run_options());
        ASSERT_EQ(run.status, "converged") << what << ": " << run.result.message;
        EXPECT_LE(run.accuracy.max(), 1e-6) << what;
        EXPECT_LE(test::max_abs(run.result.x - exact.result.x) / run.scale.length, 1e-5) << what;
        EXPECT_EQ(run.result.lambda_t.size(), with_fields ? 2 * qp.m() : 0) << what;
        // No tangential force at mu = 0 (Siconos' fc3d Newton leaves 1.8e-15 of rounding).
        EXPECT_LE(test::max_abs(run.result.lambda_t), 1e-12 * test::max_abs(exact.lambda_full)) << what;
    }
}

INSTANTIATE_TEST_SUITE_P(Entries, FrictionRegistry, ::testing::ValuesIn(NEW_ENTRIES),
                         [](const ::testing::TestParamInfo<std::string>& info) {
                             std::string s = info.param;
                             for (char& c : s)
                                 if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
                             return s;
                         });

/// Records every iterate's x.
struct FrictionIterates : Monitor {
    std::vector<Vec> x;
    bool on_iteration(const IterationInfo& info) override
    {
        if (info.x) x.push_back(*info.x);
        return true;
    }
};

TEST(FrictionRegistryMuZero, MprgpTrescaFpReturnsMprgpBoxsIterateOnTheNormalBlock)
{
    Qp qp = make_synthetic("plane", {{"nx", 3}, {"ny", 2}, {"nz", 3}}, 5);
    for (const bool with_fields : {false, true}) {
        if (with_fields) testing_qps::add_friction(qp, [](Eigen::Index) { return 0.0; });
        const std::string what = with_fields ? "mu = 0 given" : "no friction fields";
        // The local problem the entry forms, and mprgp-box on its normal block (W symmetrised as
        // mprgp-tresca-fp does), with mprgp-tresca-fp's power-method tolerance 1e-8 and stop.
        const Friction frame = with_fields ? qp.friction : frictionless_frame(qp.view());
        const QpView framed{qp.A, qp.b, qp.J, qp.c, qp.x0, nullptr, &frame};
        FrictionDual dual(framed, "test");
        const FrictionLocal& local = dual.local();
        const Eigen::Index m = qp.m();
        const Eigen::MatrixXd W = Eigen::MatrixXd(local.W);
        const Eigen::MatrixXd S = 0.5 * (W + W.transpose());
        Qp normal;
        Eigen::MatrixXd wnn(m, m);
        for (Eigen::Index i = 0; i < m; ++i)
            for (Eigen::Index j = 0; j < m; ++j) wnn(i, j) = S(3 * i, 3 * j);
        normal.A = wnn.sparseView();
        normal.b = Vec(m);
        for (Eigen::Index i = 0; i < m; ++i) normal.b[i] = -local.q[3 * i];
        normal.J = SpMat(m, m);
        normal.J.setIdentity();
        normal.c = Vec::Zero(m);
        normal.x0 = Vec::Zero(m);
        MprgpBoxSettings box_settings;
        box_settings.common.stop = StopRule::NATIVE;
        box_settings.common.tol = 1e-8;
        FrictionIterates box;
        SolveContext context;
        context.monitor = &box;
        const SolverResult box_run = MprgpBoxSolver(box_settings).solve(normal.view(), context);
        ASSERT_EQ(box_run.status, SolveStatus::CONVERGED) << what << ": " << box_run.message;
        // The entry with stop=native at the tolerance whose Tresca stop is mprgp-box's:
        // 0.5 tol ||q|| = 1e-8 (mprgp_tresca.hpp inner_fraction).
        const double tol = 2e-8 / local.q.norm();
        const SolverResult ours = builtin_registry()
                                      .create("mprgp-tresca-fp", {{"stop", "native"}, {"tol", tol}})
                                      ->solve(qp.view(), SolveContext{});
        ASSERT_EQ(ours.status, SolveStatus::CONVERGED) << what << ": " << ours.message;
        ASSERT_GT(ours.iterations, 5) << what;
        // Its r_n is mprgp-box's iterate of the same number (the stops may differ by a step or two:
        // Tresca's gradient includes the tangents' pinned components).
        EXPECT_LE(std::abs(ours.iterations - box_run.iterations), 2) << what;
        ASSERT_LT(static_cast<size_t>(ours.iterations), box.x.size()) << what;
        const Vec& same = box.x[static_cast<size_t>(ours.iterations)];
        EXPECT_LE((ours.lambda - same).norm(), 1e-12 * (1.0 + same.norm())) << what;
    }
}

TEST(FrictionRegistryCli, SolveRunsEachEntryOnAFrictionalSnapshot)
{
    const std::filesystem::path dir = make_test_work_dir("friction_registry");
    const std::string snap = (dir / "pushed.qpsnap").string();
    write_qpsnap(snap, snapshots().front().qp);
    for (const std::string& name : NEW_ENTRIES) {
        if (!builtin_registry().contains(name)) continue;  // the peers: not built (the tests above say so)
        const std::string json = (dir / (name + ".json")).string();
        std::string command = contactbench_binary();
        command += " solve " + snap;
        command += " --solver '" + name;
        command += "' --set tol=1e-6 --json " + json;
        const Output out = run_captured(command, dir);
        ASSERT_EQ(out.status, 0) << name << ": " << out.err;
        std::ifstream in(json);
        const nlohmann::json record = nlohmann::json::parse(in);
        EXPECT_EQ(record["solver"], name);
        if (name == GFC3D_NSN_FAILS) {
            EXPECT_EQ(record["status"], "stalled") << name;
            continue;
        }
        EXPECT_EQ(record["status"], "converged") << name;
        EXPECT_LE(record["fclib_error"].get<double>(), 1e-5) << name;
    }
}

}  // namespace
}  // namespace cb

namespace cb {
namespace {

/// solve_frictional_snapshot's rounds with a method whose point is off by `offset(tol)` times the
/// exact r* (relative): the verdict is e's, and a tighter own tolerance is asked for while e > tol.
SolverResult fake_method_run(const Qp& qp, const std::function<double(double)>& offset, std::vector<double>& asked)
{
    CommonSettings common;
    common.tol = 1e-6;
    SnapshotFrictionOptions options;
    return solve_frictional_snapshot("fake", qp.view(), common, SolveContext{}, options, [&](const QpView& framed) {
        auto dual = std::make_shared<FrictionDual>(framed, "fake");
        FrictionNsgsSettings exact;
        exact.tol = 1e-13;
        exact.max_iterations = 100000;
        const Vec r_star = friction_nsgs(dual->local(), exact).r;
        SnapshotFrictionMethod method;
        method.run = [dual, r_star, offset, &asked](double tol, long, double) {
            asked.push_back(tol);
            SnapshotFrictionRun one;
            one.run.r = r_star * (1.0 + offset(tol));
            one.run.error = fclib_relative_error(dual->local(), one.run.r);
            one.run.status = "converged";  // its own word, whatever e says
            one.run.iterations = 10;
            one.x = dual->primal(one.run.r);
            return one;
        };
        method.counters = [dual] { return dual->counters(); };
        return method;
    });
}

TEST(FrictionSnapshotSolve, TightensTheOwnToleranceWhileEIsNotMet)
{
    const Qp qp = particles_on_a_plane(12);
    std::vector<double> asked;
    const SolverResult r = fake_method_run(
        qp, [](double tol) { return 1e3 * tol; }, asked);
    ASSERT_EQ(r.status, SolveStatus::CONVERGED) << r.message;
    ASSERT_GE(asked.size(), 2u) << r.message;
    EXPECT_EQ(asked[0], 1e-6);
    for (size_t k = 1; k < asked.size(); ++k) EXPECT_LE(asked[k], 0.1 * asked[k - 1]);
    EXPECT_EQ(r.iterations, 10 * static_cast<long>(asked.size()));
    EXPECT_EQ(r.info["rounds"].size(), asked.size());
    EXPECT_LE(accuracy(qp.view(), r.x, r.lambda, &r.lambda_t).max(), 1e-6);
}

TEST(FrictionSnapshotSolve, AMethodThatClaimsConvergenceButDoesNotImproveIsStalled)
{
    const Qp qp = particles_on_a_plane(12);
    std::vector<double> asked;
    const SolverResult r = fake_method_run(
        qp, [](double) { return 1e-2; }, asked);
    EXPECT_EQ(r.status, SolveStatus::STALLED) << r.message;
    EXPECT_EQ(asked.size(), 2u);  // the second round did not lower e: the first point stands
    EXPECT_NE(r.message.find("the previous round's point is kept"), std::string::npos) << r.message;
    EXPECT_EQ(r.message.rfind("fake: the stop rule does not hold at the returned point: accuracy error ", 0), 0u)
        << r.message;
}

}  // namespace
}  // namespace cb
