// `chains` on frictional scenes (issue 45): the exact chain (the simulator's frictional step) is
// `simulate`'s, and the paper's BMF03 baseline (mprgp+bmf03) lets a box that should stick on an
// incline slide: its travel and its drift from the exact chain are reported, and are larger.
#include "harness/sim_step_solver.hpp"
#include "sim/chains.hpp"
#include "sim/simulator.hpp"
#include "solvers/peers/siconos_fc3d.hpp"

#include <gtest/gtest.h>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <map>
#include <sstream>
#include <unistd.h>

using namespace cb;
using namespace cb::sim;
using nlohmann::json;
namespace fs = std::filesystem;

namespace {

/// A soft box (0.1 m, 2 x 2 x 2 cubes, 9 contacts) thrown along the ground at 1 m/s, mu = 0.3,
/// stepped by our NSGS (a few hundred sweeps a step at this stiffness).
json slide_scene()
{
    return {{"name", "slide"},
            {"h", 0.01},
            {"frames", 6},
            {"gravity", {0.0, -9.8, 0.0}},
            {"a_M", 0.0},
            {"a_K", 0.01},
            {"solver", "active-set"},
            {"mu", 0.3},
            {"friction_settings", {{"solver", "nsgs"}, {"tol", 1e-10}}},
            {"detection", {{"margin", 0.005}}},
            {"bodies",
             {{{"box", {{"cells", {2, 2, 2}}, {"size", {0.1, 0.1, 0.1}}}},
               {"material", {{"youngs", 1e6}, {"poisson", 0.4}, {"density", 1000}}},
               {"translate", {0.0, 0.05, 0.0}},
               {"velocity", {1.0, 0.0, 0.0}}}}},
            {"obstacles", {{{"type", "plane"}, {"normal", {0, 1, 0}}, {"point", {0, 0, 0}}}}}};
}

fs::path fresh_chains_dir(const std::string& name)
{
    const char* tmp = std::getenv("TMPDIR");
    fs::path p = fs::path(tmp ? tmp : "/tmp") / ("cb_test_friction_chains_" + std::to_string(::getpid()) + "_" + name);
    fs::remove_all(p);
    return p;
}

/// chains.csv's rows of one chain, as column -> cell maps.
std::vector<std::map<std::string, std::string>> chain_rows(const fs::path& csv, const std::string& chain)
{
    std::ifstream in(csv);
    std::string line;
    std::getline(in, line);
    std::vector<std::string> header;
    std::stringstream hs(line);
    for (std::string cell; std::getline(hs, cell, ',');) header.push_back(cell);
    std::vector<std::map<std::string, std::string>> rows;
    while (std::getline(in, line)) {
        std::stringstream ls(line);
        std::map<std::string, std::string> row;
        size_t k = 0;
        for (std::string cell; std::getline(ls, cell, ',') && k < header.size(); ++k) row[header[k]] = cell;
        if (row["chain"] == chain) rows.push_back(row);
    }
    return rows;
}

std::string printed(double v)  // as chains.csv prints a number
{
    std::ostringstream s;
    s << std::setprecision(9) << v;
    return s.str();
}

ChainOptions frictional_chains(const fs::path& out)
{
    ChainOptions opt;
    opt.out_dir = out.string();
    ChainSpec exact{"exact", "nsgs", {{"tol", 1e-10}}, "none"};
    exact.friction_step = true;
    opt.chains = {exact, ChainSpec{"bmf03", "mprgp+bmf03", {{"tol", 1e-8}}, "none"}};
    opt.reference = "exact";
    opt.render_chain = "bmf03";
    opt.solve_step = harness_step_solver();
    return opt;
}

}  // namespace

TEST(FrictionChains, TheExactChainIsSimulatesFrames)
{
    const fs::path out = fresh_chains_dir("slide");
    const json scene = slide_scene();
    ASSERT_TRUE(run_chains([&] { return load_scene_json(scene, "slide.json", PathRoots{}); }, frictional_chains(out)));
    const auto rows = chain_rows(out / "chains.csv", "exact");
    ASSERT_EQ(rows.size(), 6u);
    SimulatorOptions so;
    so.solve_step = harness_step_solver();
    Simulator sim(load_scene_json(scene, "slide.json", PathRoots{}), so);
    const Vec3 start = vertex_mean(sim.positions());
    for (size_t f = 0; f < rows.size(); ++f) {
        const auto recs = sim.step();
        ASSERT_EQ(recs.size(), 1u);
        const FrameRecord fr = sim.frame_record();
        EXPECT_EQ(rows[f].at("solver"), "nsgs");
        EXPECT_EQ(rows[f].at("status"), recs[0].status) << "frame " << f;
        EXPECT_EQ(rows[f].at("accuracy"), printed(recs[0].accuracy)) << "frame " << f;
        EXPECT_EQ(rows[f].at("kinetic_energy"), printed(fr.kinetic_energy)) << "frame " << f;
        EXPECT_EQ(rows[f].at("elastic_energy"), printed(fr.elastic_energy)) << "frame " << f;
        EXPECT_EQ(rows[f].at("travel_rel"), printed((vertex_mean(sim.positions()) - start).norm() / 0.1))
            << "frame " << f;
        EXPECT_EQ(rows[f].at("drift_rel"), "0");
    }
    EXPECT_GT(std::stod(rows.back().at("travel_rel")), 0.3);  // it slid (1 m/s for 0.06 s, braking)
    // The baseline's chain stepped the same frames with its own (stalled) verdicts.
    const auto bmf = chain_rows(out / "chains.csv", "bmf03");
    ASSERT_EQ(bmf.size(), 6u);
    EXPECT_EQ(bmf.back().at("solver"), "mprgp+bmf03");
    EXPECT_GT(std::stod(bmf.back().at("drift_rel")), 0.0);
    const json record = json::parse(std::ifstream(out / "chains.json"));
    EXPECT_EQ(record["chains"][0]["friction_step"], true);
    EXPECT_EQ(record["chains"][1]["friction_step"], false);
    fs::remove_all(out);
}

TEST(FrictionChains, Bmf03SlidesWhereTheExactChainSticks)
{
    if (!siconos_fc3d_built()) GTEST_SKIP() << "contactbench is built without Siconos numerics (siconos-nsn)";
    // scenes/friction_incline.json: mu 0.5 > tan 20 deg, the stiff box must stay put.
    const fs::path out = fresh_chains_dir("incline");
    ChainOptions opt = frictional_chains(out);
    opt.chains[0].solver = "siconos-nsn";
    opt.frames = 10;
    const std::string scene = std::string(CB_SOURCE_DIR) + "/scenes/friction_incline.json";
    ASSERT_TRUE(run_chains([&] { return load_scene(scene, default_path_roots(scene, "")); }, opt));
    const auto exact = chain_rows(out / "chains.csv", "exact"), bmf = chain_rows(out / "chains.csv", "bmf03");
    ASSERT_EQ(exact.size(), 10u);
    ASSERT_EQ(bmf.size(), 10u);
    for (size_t f = 0; f < exact.size(); ++f) EXPECT_EQ(exact[f].at("status"), "converged") << "frame " << f;
    const double exact_travel = std::stod(exact.back().at("travel_rel"));
    const double bmf_travel = std::stod(bmf.back().at("travel_rel")), bmf_drift = std::stod(bmf.back().at("drift_rel"));
    std::cout << "after 0.1 s: exact chain travelled " << exact_travel << " of the box's size, bmf03 " << bmf_travel
              << " (drift from the exact chain " << bmf_drift << ")\n";
    EXPECT_LE(exact_travel, 1e-4);
    EXPECT_GT(bmf_travel, 100 * exact_travel);
    EXPECT_GT(bmf_drift, 1e-2);
    EXPECT_EQ(bmf.back().at("status"), "stalled");  // its point is not Coulomb's, and it says so
    EXPECT_EQ(bmf.back().at("steps_not_solved"), "1");
    fs::remove_all(out);
}

TEST(FrictionChains, AFrictionalStepChainTakesOnlyATolerance)
{
    ChainOptions opt = frictional_chains("/nonexistent/never-written");
    opt.chains[0].settings = {{"max_iterations", 10}};
    const json scene = slide_scene();
    std::string error = "(no error)";
    try {
        run_chains([&] { return load_scene_json(scene, "slide.json", PathRoots{}); }, opt);
    } catch (const InputError& e) {
        error = e.what();
    }
    EXPECT_EQ(error, "chain exact: max_iterations: a frictional-step chain takes only \"tol\" (> 0), got 10");
}
