// The simulator with Coulomb friction (issue 48 item 5): a stiff box on a 20-degree incline sticks
// with mu = 0.5 and slides with acceleration g (sin theta - mu cos theta) with mu = 0.2; the
// frictional step with a vanishing mu meets the frictionless QP's solution; scene validation.
//
// The incline is a tilted gravity on a flat plane: the procedural box is axis-aligned, so it rests
// flat on an axis-aligned plane, and tilting gravity instead of the plane is the same physics in
// the incline's frame, with the slide along one axis (x).
#include "harness/sim_step_solver.hpp"
#include "problems/qpsnap.hpp"
#include "sim/chains.hpp"
#include "sim/simulator.hpp"
#include "solvers/core/registry.hpp"
#include "solvers/friction/friction_nsgs.hpp"
#include "solvers/peers/siconos_fc3d.hpp"
#include "tests/sim/harness_step_options.hpp"

#include <gtest/gtest.h>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <unistd.h>

using namespace cb;
using namespace cb::sim;
using nlohmann::json;

namespace {

constexpr double G = 9.81;
constexpr double SIZE = 0.1;  // m, the box's edge
const double THETA = 20.0 * M_PI / 180.0;

/// A stiff 0.1 m box (2 x 2 x 2 cubes, 27 vertices) resting on the plane y = 0 under gravity tilted
/// by 20 degrees towards +x. a_M = 0: mass damping would brake the slide itself.
json incline_scene(double mu, const std::string& solver = "siconos-nsn")
{
    json j = {{"name", "incline"},
              {"h", 0.01},
              {"frames", 100},
              {"gravity", {G * std::sin(THETA), -G * std::cos(THETA), 0.0}},
              {"a_M", 0.0},
              {"a_K", 0.001},
              {"solver", "active-set"},
              {"detection", {{"margin", 0.002}}},
              {"bodies",
               {{{"box", {{"cells", {2, 2, 2}}, {"size", {SIZE, SIZE, SIZE}}}},
                 {"material", {{"youngs", 1e8}, {"poisson", 0.3}, {"density", 1000}}},
                 {"translate", {0.0, SIZE / 2, 0.0}}}}},
              {"obstacles", {{{"type", "plane"}, {"normal", {0, 1, 0}}, {"point", {0, 0, 0}}}}}};
    if (mu != 0.0) {
        j["mu"] = mu;
        j["friction_settings"] = {{"solver", solver}};
    }
    return j;
}

/// The physics checks step with Siconos' non-smooth Newton: our NSGS needs 18,000-28,000 sweeps per
/// step on this box's 9 contacts (W of a stiff body is ill-conditioned), which is minutes for 1 s.
/// NSGS is checked against it on the first steps (NsgsAndSiconosNsnStepAlike).
#define REQUIRE_SICONOS()                                                                                              \
    if (!siconos_fc3d_built()) GTEST_SKIP() << "contactbench is built without Siconos numerics (siconos-nsn)"

Vec3 mean_of(const Vec& v)
{
    Vec3 s = Vec3::Zero();
    for (Eigen::Index i = 0; i < v.size() / 3; ++i) s += v.segment<3>(3 * i);
    return s / double(v.size() / 3);
}

std::string scene_error_of(const json& j)
{
    try {
        load_scene_json(j, "s.json", PathRoots{});
    } catch (const InputError& e) {
        return e.what();
    }
    return "(no error)";
}

}  // namespace

TEST(FrictionIncline, BoxWithMu05StaysWithin1e3OfItsSizeFor1s)
{
    REQUIRE_SICONOS();
    ASSERT_LT(std::tan(THETA), 0.5);  // the static case: friction can hold the box
    Simulator sim(load_scene_json(incline_scene(0.5), "incline.json", PathRoots{}), test::harness_step_options());
    const Vec3 start = mean_of(sim.positions());
    double drift = 0;
    for (int s = 0; s < 100; ++s) {  // 1 s
        const auto recs = sim.step();
        ASSERT_EQ(recs.size(), 1u);
        EXPECT_EQ(recs[0].solver, "siconos-nsn");
        EXPECT_EQ(recs[0].status, "converged") << "step " << s << ": FCLIB error " << recs[0].accuracy;
        EXPECT_LE(recs[0].accuracy, 1e-10);
        EXPECT_GT(recs[0].rows, 0);
        drift = std::max(drift, (mean_of(sim.positions()) - start).norm());
    }
    std::cout << "mu 0.5: largest centroid drift over 1 s " << drift / SIZE << " of the box's size\n";
    EXPECT_LE(drift, 1e-3 * SIZE);
    EXPECT_GT(sim.last_frictional_step().sticking, 0);  // (edge contacts may sit on the cone's boundary)
}

TEST(FrictionIncline, BoxWithMu02SlidesWithAccelerationWithin5Percent)
{
    REQUIRE_SICONOS();
    const double mu = 0.2;
    Simulator sim(load_scene_json(incline_scene(mu), "incline.json", PathRoots{}), test::harness_step_options());
    const double expected = G * (std::sin(THETA) - mu * std::cos(THETA));
    // Backward Euler gains h a per step exactly under a constant force, so the velocity's change
    // over [0.5 s, 1 s] gives the acceleration without the bias of a position fit.
    double v_half = 0;
    for (int s = 0; s < 100; ++s) {
        const auto recs = sim.step();
        ASSERT_EQ(recs.size(), 1u);
        EXPECT_EQ(recs[0].status, "converged") << "step " << s << ": FCLIB error " << recs[0].accuracy;
        if (s == 49) v_half = mean_of(sim.velocities()).x();
    }
    const Vec3 v = mean_of(sim.velocities());
    const double measured = (v.x() - v_half) / 0.5;
    std::cout << "mu 0.2: acceleration " << measured << " m/s^2, g (sin - mu cos) = " << expected << "\n";
    EXPECT_NEAR(measured, expected, 0.05 * expected) << "expected g (sin - mu cos) = " << expected;
    EXPECT_LE(std::abs(v.z()), 1e-6 * v.x());  // no sideways slip
    EXPECT_GT(sim.last_frictional_step().sliding, 0);
    EXPECT_EQ(sim.last_frictional_step().sticking, 0);
}

TEST(FrictionIncline, VanishingMuMeetsTheFrictionlessQpStep)
{
    // Two independent solvers of the same contact problem: active-set on the QP (mu = 0) and the
    // frictional path (local problem + NSGS) with mu = 1e-12, whose friction force is below rounding.
    Simulator qp(load_scene_json(incline_scene(0.0), "incline.json", PathRoots{}), test::harness_step_options());
    Simulator fr(load_scene_json(incline_scene(1e-12, "nsgs"), "incline.json", PathRoots{}),
                 test::harness_step_options());
    for (int s = 0; s < 3; ++s) {  // NSGS needs ~10 s a step here (see REQUIRE_SICONOS)
        const auto a = qp.step(), b = fr.step();
        ASSERT_EQ(a[0].solver, "active-set");
        ASSERT_EQ(b[0].solver, "nsgs");
        ASSERT_EQ(b[0].status, "converged");
        EXPECT_LE((qp.positions() - fr.positions()).lpNorm<Eigen::Infinity>(), 1e-9 * SIZE) << "step " << s;
    }
    EXPECT_GT(
        (qp.positions() -
         load_scene_json(incline_scene(0.0), "i.json", PathRoots{}).bodies[0].mesh.positions.transpose().reshaped())
            .norm(),
        1e-3);  // and the box did slide (the comparison is not of two boxes at rest)
}

TEST(FrictionIncline, NsgsAndSiconosNsnStepAlike)
{
    // The first steps of the sticking box with our NSGS and with Siconos' NSN: two independent
    // solvers of each step's local problem, each to FCLIB error 1e-10.
    REQUIRE_SICONOS();
    Simulator a(load_scene_json(incline_scene(0.5, "nsgs"), "incline.json", PathRoots{}), test::harness_step_options());
    Simulator b(load_scene_json(incline_scene(0.5, "siconos-nsn"), "incline.json", PathRoots{}),
                test::harness_step_options());
    for (int s = 0; s < 3; ++s) {
        const auto ra = a.step(), rb = b.step();
        ASSERT_EQ(ra[0].solver, "nsgs");
        ASSERT_EQ(ra[0].status, "converged");
        ASSERT_EQ(rb[0].status, "converged");
        EXPECT_LE((a.positions() - b.positions()).lpNorm<Eigen::Infinity>(), 1e-9 * SIZE) << "step " << s;
    }
}

TEST(FrictionIncline, TangentFrameIsOrthonormalAndRightHanded)
{
    for (const Vec3& n : {Vec3(0, 1, 0), Vec3(1, 0, 0), Vec3(0, 0, -1), Vec3(1, 2, 3).normalized()}) {
        Vec3 t1, t2;
        tangent_frame(n, t1, t2);
        EXPECT_NEAR(t1.norm(), 1.0, 1e-15);
        EXPECT_NEAR(t2.norm(), 1.0, 1e-15);
        EXPECT_NEAR(t1.dot(n), 0.0, 1e-15);
        EXPECT_NEAR(t2.dot(n), 0.0, 1e-15);
        EXPECT_NEAR(t1.dot(t2), 0.0, 1e-15);
        EXPECT_NEAR(n.cross(t1).dot(t2), 1.0, 1e-15);
    }
}

TEST(FrictionIncline, SceneFrictionKeysAreChecked)
{
    json j = incline_scene(-0.1);
    EXPECT_EQ(scene_error_of(j), "s.json: /mu: must be in (-1e-300, 1e+06], got -0.1");
    j = incline_scene(0.0);
    j["friction_settings"] = {{"tol", 1e-8}};
    EXPECT_EQ(scene_error_of(j), "s.json: /friction_settings: applies only to a frictional scene (\"mu\" > 0)");
    j = incline_scene(0.3);
    j["friction_settings"] = {{"solver", "pgs"}};
    EXPECT_EQ(scene_error_of(j),
              "s.json: /friction_settings/solver: must be one of nsgs, siconos-nsn, siconos-nsgs, got 'pgs'");
    j["friction_settings"] = {{"tolerance", 1e-8}};
    EXPECT_EQ(scene_error_of(j),
              "s.json: /friction_settings/tolerance: unknown key (see scenes/README.md for the keys of "
              "this object)");
    j["friction_settings"] = {{"tol", 1e-8}, {"max_iterations", 50}};
    const Scene s = load_scene_json(j, "s.json", PathRoots{});
    EXPECT_EQ(s.friction.mu, 0.3);
    EXPECT_EQ(s.friction.tol, 1e-8);
    EXPECT_EQ(s.friction.max_iterations, 50);
    EXPECT_EQ(s.friction.solver, "nsgs");
    EXPECT_EQ(load_scene_json(incline_scene(0.0), "s.json", PathRoots{}).friction.mu, 0.0);
}

TEST(FrictionIncline, ChainsRefuseAFrictionalStepChainOnAFrictionlessScene)
{
    // Frictional scenes are chains' too (tests/sim/test_friction_chains.cpp); the frictional step
    // needs a mu > 0 to step with.
    ChainOptions opt;
    opt.out_dir = "/nonexistent/never-written";
    ChainSpec exact{"exact", "nsgs", json::object(), "none"};
    exact.friction_step = true;
    opt.chains = {exact};
    opt.reference = opt.render_chain = "exact";
    opt.solve_step = harness_step_solver();
    const auto load = [] { return load_scene_json(incline_scene(0.0), "incline.json", PathRoots{}); };
    std::string error = "(no error)";
    try {
        run_chains(load, opt);
    } catch (const InputError& e) {
        error = e.what();
    }
    EXPECT_EQ(
        error,
        "incline.json: /mu: chain 'exact' steps with the frictional step, but the scene has no friction (mu = 0)");
}

TEST(FrictionIncline, AStepMissingItsToleranceIsReported)
{
    // One NSGS sweep cannot reach 1e-10 on the stiff box: the step goes on and says so everywhere.
    json j = incline_scene(0.5, "nsgs");
    j["friction_settings"]["max_iterations"] = 1;
    j["frames"] = 2;
    j["output"] = {{"snapshots", false}, {"strip_frames", 0}};
    const char* tmp = std::getenv("TMPDIR");
    SimulatorOptions opt = test::harness_step_options();
    opt.out_dir = std::string(tmp ? tmp : "/tmp") + "/cb_test_friction_" + std::to_string(::getpid());
    opt.fresh = true;
    std::ostringstream log;
    opt.progress = &log;
    Simulator sim(load_scene_json(j, "incline.json", PathRoots{}), opt);
    ASSERT_TRUE(sim.run());
    EXPECT_EQ(sim.frictional_steps_unsolved(), 2);
    EXPECT_NE(log.str().find("nsgs mu 0.5 max_iterations  it 1  e "), std::string::npos) << log.str();
    EXPECT_NE(log.str().find("incline: 2 frictional step(s) did not reach FCLIB error 1.0e-10 (nsgs)"),
              std::string::npos)
        << log.str();
    std::ifstream steps(opt.out_dir + "/steps.csv");
    std::string header, row;
    std::getline(steps, header);
    std::getline(steps, row);
    EXPECT_EQ(row.rfind("0,0,0,nsgs,max_iterations,max_iterations,1,", 0), 0u) << row;
    std::ifstream record_file(opt.out_dir + "/simulation.json");
    const json record = json::parse(record_file);
    EXPECT_EQ(record.at("friction").at("steps_not_converged"), 2);
    EXPECT_EQ(record.at("friction").at("mu"), 0.5);
    std::filesystem::remove_all(opt.out_dir);
}

TEST(FrictionIncline, SnapshotHoldsTheCoulombProblemOfTheStep)
{
    // The frictional snapshot of a step holds what a velocity-level method needs (mu, the tangent
    // rows, cT = T x_start, h, the start velocities): its Coulomb problem, reduced here with a dense
    // LLT of A and solved by NSGS, gives the positions the simulator stepped to.
    json j = incline_scene(0.2, "nsgs");
    j["frames"] = 2;
    j["output"] = {{"strip_frames", 0}};
    const char* tmp = std::getenv("TMPDIR");
    SimulatorOptions opt = test::harness_step_options();
    opt.out_dir = std::string(tmp ? tmp : "/tmp") + "/cb_test_friction_snap_" + std::to_string(::getpid());
    opt.fresh = true;
    Simulator sim(load_scene_json(j, "incline.json", PathRoots{}), opt);
    Vec x_start, v_start;
    for (int s = 0; s < 2; ++s) {
        x_start = sim.positions();
        v_start = sim.velocities();
        const auto recs = sim.step();
        ASSERT_EQ(recs[0].status, "converged");
    }
    // The second step's snapshot, written by run() as the simulator stepped above would.
    Simulator writer(load_scene_json(j, "incline.json", PathRoots{}), opt);
    ASSERT_TRUE(writer.run());
    const Qp qp = read_qpsnap(opt.out_dir + "/snapshots/incline_f0001_n0.qpsnap");
    const Eigen::Index m = qp.m(), n = qp.n();
    ASSERT_GT(m, 0);
    ASSERT_TRUE(qp.frictional());
    EXPECT_EQ(qp.friction.mu, Vec::Constant(m, 0.2));
    ASSERT_EQ(qp.friction.T.rows(), 2 * m);
    EXPECT_EQ(qp.friction.h, 0.01);
    EXPECT_EQ(qp.friction.v0, v_start);
    EXPECT_EQ(qp.friction.cT, Vec(qp.friction.T * x_start));
    for (Eigen::Index i = 0; i < m; ++i) {  // each contact's frame: orthonormal, the normal first
        const Eigen::MatrixXd frame = Eigen::MatrixXd(qp.J.row(i)).transpose();
        const Eigen::MatrixXd t1 = Eigen::MatrixXd(qp.friction.T.row(2 * i)).transpose();
        const Eigen::MatrixXd t2 = Eigen::MatrixXd(qp.friction.T.row(2 * i + 1)).transpose();
        EXPECT_NEAR(frame.col(0).dot(t1.col(0)), 0.0, 1e-15);
        EXPECT_NEAR(frame.col(0).dot(t2.col(0)), 0.0, 1e-15);
        EXPECT_NEAR(t1.col(0).dot(t2.col(0)), 0.0, 1e-15);
    }
    // The local problem from the snapshot's fields alone.
    Eigen::MatrixXd J_all(3 * m, n);
    Vec c_all(3 * m);
    const Eigen::MatrixXd J = Eigen::MatrixXd(qp.J), T = Eigen::MatrixXd(qp.friction.T);
    for (Eigen::Index i = 0; i < m; ++i) {
        J_all.row(3 * i) = J.row(i);
        J_all.row(3 * i + 1) = T.row(2 * i);
        J_all.row(3 * i + 2) = T.row(2 * i + 1);
        c_all.segment<3>(3 * i) << qp.c[i], qp.friction.cT[2 * i], qp.friction.cT[2 * i + 1];
    }
    const Eigen::LLT<Eigen::MatrixXd> llt{Eigen::MatrixXd(qp.A)};
    const Eigen::MatrixXd Y = llt.solve(J_all.transpose());
    FrictionLocal local;
    local.W = Eigen::MatrixXd(J_all * Y).sparseView(0.0, 0.0);
    local.q = J_all * llt.solve(qp.b) - c_all;
    local.mu = qp.friction.mu;
    FrictionNsgsSettings settings;
    settings.tol = 1e-10;
    settings.max_iterations = 100000;  // as the scene's (friction_settings' default)
    const FrictionRun run = friction_nsgs(local, settings);
    ASSERT_EQ(run.status, "converged") << run.error;
    const Vec x = llt.solve(qp.b) + Y * run.r;
    EXPECT_LE((x - sim.positions()).lpNorm<Eigen::Infinity>(), 1e-9 * SIZE);
    std::filesystem::remove_all(opt.out_dir);
}
