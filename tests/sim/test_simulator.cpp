// The simulator end to end: scene validation, paper sizes, resting contact, momentum, the
// authors' two-dinosaur QP of frame 11 (when their data is present), and the outputs.
#include "harness/sim_step_solver.hpp"
#include "harness/suite.hpp"  // cache_dir
#include "problems/qpsnap.hpp"
#include "sim/simulator.hpp"
#include "solvers/core/registry.hpp"
#include "tests/sim/harness_step_options.hpp"
#include "tests/sim/input_error.hpp"

#include <gtest/gtest.h>
#include <fstream>
#include <sys/stat.h>
#include <unistd.h>

using namespace cb;
using namespace cb::sim;
using nlohmann::json;

namespace {
const std::string SOURCE = CB_SOURCE_DIR;
// The authors' data where `make paper-data` writes it ($CB_CACHE/paper-data); the test using it skips without it.
const std::string PAPER_DATA = cb::cache_dir() + "/paper-data";

std::string sim_tmp_dir(const std::string& name)
{
    const char* dir = std::getenv("TMPDIR");
    std::string p = std::string(dir ? dir : "/tmp") + "/cb_test_sim_" + std::to_string(::getpid()) + "_" + name;
    ::mkdir(p.c_str(), 0755);
    return p;
}
bool exists(const std::string& p)
{
    struct stat st {};
    return ::stat(p.c_str(), &st) == 0;
}
std::string reference_solver() { return builtin_registry().contains("active-set") ? "active-set" : "mprgp"; }

json box_body(const Vec3& translate, const Vec3& velocity)
{
    return {{"box", {{"cells", {3, 3, 3}}, {"size", {0.3, 0.3, 0.3}}}},
            {"material", {{"youngs", 1e5}, {"poisson", 0.4}, {"density", 1000}}},
            {"translate", {translate.x(), translate.y(), translate.z()}},
            {"velocity", {velocity.x(), velocity.y(), velocity.z()}}};
}
Vec3 momentum(const Simulator& s)
{
    Vec3 p = Vec3::Zero();
    for (long i = 0; i < s.vertices(); ++i) p += s.fem().vertex_mass()[i] * s.velocities().segment<3>(3 * i);
    return p;
}
}  // namespace

TEST(Simulator, LongCubeHasThePapersSize)
{
    const std::string path = SOURCE + "/scenes/long_cube.json";
    Scene scene = load_scene(path, default_path_roots(path, ""));
    ASSERT_EQ(scene.bodies.size(), 1u);
    EXPECT_EQ(scene.bodies[0].mesh.vertices(), 9537);
    EXPECT_EQ(scene.bodies[0].mesh.tet_count(), 49152);
    Simulator sim(std::move(scene), test::harness_step_options());
    EXPECT_EQ(sim.dofs(), 28611);
    EXPECT_EQ(sim.tets(), 49152);
    // Scaled by 0.5: 0.5 x 0.5 x 1 m of density 1000.
    EXPECT_NEAR(sim.fem().vertex_mass().sum(), 250.0, 1e-9);
}

TEST(Simulator, BoxRestingOnPlaneStaysOnItFor100Steps)
{
    const json j = {{"name", "rest"},
                    {"h", 0.01},
                    {"frames", 100},
                    {"a_M", 0.02},
                    {"a_K", 0.01},
                    {"solver", reference_solver()},
                    {"detection", {{"margin", 0.005}}},
                    {"bodies", {box_body(Vec3(0, 0.15, 0), Vec3::Zero())}},
                    {"obstacles", {{{"type", "plane"}, {"normal", {0, 1, 0}}, {"point", {0, 0, 0}}}}}};
    Simulator sim(load_scene_json(j, "rest.json", PathRoots{}), test::harness_step_options());
    double min_y = 1e300, max_y = -1e300;
    for (int s = 0; s < 100; ++s) {
        const auto recs = sim.step();
        ASSERT_EQ(recs.size(), 1u);
        EXPECT_EQ(recs[0].status, "converged") << "step " << s;
        const Vec& x = sim.positions();
        double lowest = 1e300;
        for (long i = 0; i < sim.vertices(); ++i) lowest = std::min(lowest, x[3 * i + 1]);
        min_y = std::min(min_y, lowest);
        max_y = std::max(max_y, lowest);
    }
    // The bottom stays on the plane (no sinking, no bouncing) and the box comes to rest.
    EXPECT_GT(min_y, -1e-6);
    EXPECT_LT(max_y, 1e-3);
    const FrameRecord fr = sim.frame_record();
    EXPECT_LT(fr.max_speed, 1e-2);
    EXPECT_FALSE(fr.blow_up);
}

TEST(Simulator, TwoBodiesInFreeFlightConserveLinearMomentum)
{
    // a_M = 0: stiffness damping a_K K annihilates translations, so momentum is conserved exactly.
    json j = {{"name", "flight"},
              {"h", 0.01},
              {"gravity", {0, 0, 0}},
              {"a_M", 0.0},
              {"a_K", 0.02},
              {"bodies", {box_body(Vec3(0, 0, 0), Vec3(1, 0, 0)), box_body(Vec3(1, 0.1, 0), Vec3(-2, 0.5, 0.3))}}};
    j["bodies"][1]["rotate_deg"] = {10, 20, 30};
    Simulator sim(load_scene_json(j, "flight.json", PathRoots{}), test::harness_step_options());
    // Spin the second body so that the elastic forces work during the flight.
    const long nv = sim.vertices();
    for (long i = nv / 2; i < nv; ++i) {
        const Vec3 r = sim.positions().segment<3>(3 * i) - Vec3(1, 0.1, 0);
        sim.velocities().segment<3>(3 * i) += Vec3(0, 0, 5).cross(r);
    }
    const Vec3 p0 = momentum(sim);
    for (int s = 0; s < 20; ++s) {
        const auto recs = sim.step();
        EXPECT_EQ(recs[0].rows, 0);
    }
    EXPECT_LT((momentum(sim) - p0).norm(), 1e-9 * p0.norm());
    EXPECT_GT(sim.frame_record().elastic_energy, 0.0);
}

TEST(Simulator, MalformedScenesNameFileAndKey)
{
    json j = {{"bodies", {box_body(Vec3::Zero(), Vec3::Zero())}}};
    j["bodies"][0]["materal"] = json::object();
    EXPECT_EQ(test::input_error_of([&] { load_scene_json(j, "s.json", PathRoots{}); }),
              "s.json: /bodies/0/materal: unknown key (see scenes/README.md for the keys of this object)");
    json k = {{"h", "0.01"}, {"bodies", {box_body(Vec3::Zero(), Vec3::Zero())}}};
    EXPECT_EQ(test::input_error_of([&] { load_scene_json(k, "s.json", PathRoots{}); }),
              "s.json: /h: expected a number, got string \"0.01\"");
    json l = {{"bodies", {{{"mesh", {"data:meshes/nope.abq", "missing.off"}}}}}};
    const std::string e = test::input_error_of([&] {
        load_scene_json(l, "s.json", PathRoots{"", "", "/nonexistent"});
    });
    EXPECT_EQ(e,
              "s.json: /bodies/0/mesh: no mesh alternative is available: tried data:meshes/nope.abq (no --data given); "
              "/nonexistent/missing.off (not found)");
    json m = {{"bodies", {box_body(Vec3::Zero(), Vec3::Zero())}}, {"obstacles", {{{"type", "cone"}}}}};
    EXPECT_EQ(test::input_error_of([&] { load_scene_json(m, "s.json", PathRoots{}); }),
              "s.json: /obstacles/0/type: must be one of plane, sphere, box, cylinder, mesh, stairs, got 'cone'");
    json n = {{"bodies", {box_body(Vec3::Zero(), Vec3::Zero())}}, {"solver", "no-such-solver"}};
    EXPECT_NE(test::input_error_of([&] {
                  Simulator(load_scene_json(n, "s.json", PathRoots{}), test::harness_step_options());
              }).find("no-such-solver"),
              std::string::npos);
    // A malformed mesh file is reported with its file and line through the scene.
    const std::string dir = sim_tmp_dir("badmesh");
    std::ofstream(dir + "/bad.abq") << "*NODE\n1, 0,0,0\n*ELEMENT, TYPE=C3D4\n1, 1,1\n";
    json o = {{"bodies", {{{"mesh", "bad.abq"}}}}};
    EXPECT_EQ(test::input_error_of([&] {
                  load_scene_json(o, "s.json", PathRoots{"", "", dir});
              }),
              dir + "/bad.abq: line 4: expected 5 integers 'id,n1,n2,n3,n4', got '1, 1,1'");
}

TEST(Simulator, AuthorsIniImportMapsSwappedDampingNames)
{
    const json ini = {{"h", 0.005},
                      {"alpha_k", 0.02},
                      {"alpha_m", 0.01},
                      {"gravity", {0, 0, 0}},
                      {"num_frames", 35},
                      {"mprgp_tolerance", 1e-5},
                      {"vol_file", {"model/mesh_1303_4014.abq"}},
                      {"trans_rot_scale", {{0, 0, 0.5, 0, 0, 0, 1}}},
                      {"init_vel", {{0, 0, -4}}}};
    const json s = import_authors_ini(ini, "x/dino_two.ini");
    EXPECT_EQ(s["a_M"], 0.02);  // their "alpha_k" multiplies M
    EXPECT_EQ(s["a_K"], 0.01);
    EXPECT_EQ(s["bodies"][0]["mesh"], "data:meshes/dino_1303_4014.abq");
    EXPECT_EQ(s["bodies"][0]["velocity"], json({0, 0, -4}));
}

TEST(Simulator, TwoDinosFrame11HasInterBodyRowsOf12Nonzeros)
{
    if (!exists(PAPER_DATA + "/meshes/dino_1303_4014.abq")) GTEST_SKIP() << "no authors' data at " << PAPER_DATA;
    const std::string path = SOURCE + "/scenes/two_dinos_1303.json";
    SimulatorOptions opt = test::harness_step_options();
    opt.out_dir = sim_tmp_dir("two_dinos");
    opt.frames = 12;
    Scene scene = load_scene(path, default_path_roots(path, PAPER_DATA));
    scene.output.snapshot_first = 11;
    scene.output.strip_frames = 0;
    Simulator sim(std::move(scene), opt);
    EXPECT_TRUE(sim.run());
    const Qp qp = read_qpsnap(opt.out_dir + "/snapshots/two_dinos_1303_f0011_n0.qpsnap");
    EXPECT_EQ(qp.n(), 7818);
    EXPECT_EQ(qp.A.nonZeros(), 256122);  // the authors' a_nonzeros for this mesh pair
    ASSERT_GT(qp.m(), 10);
    for (Eigen::Index i = 0; i < qp.m(); ++i) {
        EXPECT_EQ(qp.J.outerIndexPtr()[i + 1] - qp.J.outerIndexPtr()[i], 12);
        EXPECT_EQ(qp.contacts.kind[static_cast<size_t>(i)], static_cast<std::int64_t>(ContactKind::INTER_BODY));
        EXPECT_EQ(qp.c[i], 0.0);
    }
    EXPECT_EQ(qp.meta["frame"], 11);
    EXPECT_EQ(qp.meta["newton_iteration"], 0);
    EXPECT_EQ(qp.meta["units"], "SI");
}

TEST(Simulator, DemoWritesCsvPngAndObj)
{
    const std::string path = SOURCE + "/scenes/demo.json";
    SimulatorOptions opt = test::harness_step_options();
    opt.out_dir = sim_tmp_dir("demo");
    opt.frames = 20;
    Scene scene = load_scene(path, default_path_roots(path, ""));
    Simulator sim(std::move(scene), opt);
    EXPECT_TRUE(sim.run());
    for (const char* f : {"/steps.csv", "/frames.csv", "/demo_strip.png", "/frames/demo_f0019_b0.obj",
                          "/snapshots/demo_f0000_n0.qpsnap", "/snapshots/demo_f0019_n0.qpsnap"})
        EXPECT_TRUE(exists(opt.out_dir + f)) << f;
    std::ifstream in(opt.out_dir + "/frames.csv");
    std::string line;
    long lines = 0;
    while (std::getline(in, line)) ++lines;
    EXPECT_EQ(lines, 21);
}
