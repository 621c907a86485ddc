// Suite entries that pick snapshots from a simulation folder ({"sim": DIR, "frames": "a:b",
// "stride": k, "min_rows": r}): the selection follows steps.csv, and every missing piece is an
// error that names the suite field and prints the `contactbench simulate` command that makes it.
#include "harness/suite.hpp"
#include "solvers/core/types.hpp"

#include <gtest/gtest.h>
#include <filesystem>
#include <fstream>
#include <unistd.h>

namespace {

namespace fs = std::filesystem;

/// A simulation folder of six frames (one Newton step each) whose rows are 0, 10, 20, 30, 40, 50.
class SuiteSimulation : public ::testing::Test {
protected:
    void SetUp() override
    {
        root = fs::temp_directory_path() / ("cb_suite_sim_" + std::to_string(::getpid()) + "_" +
                                            ::testing::UnitTest::GetInstance()->current_test_info()->name());
        fs::remove_all(root);
        fs::create_directories(root / "sim" / "x" / "snapshots");
        std::ofstream steps(root / "sim" / "x" / "steps.csv");
        steps << "frame,step,newton_iteration,solver,status,iterations,accuracy,time_assembly_s,time_detection_s,"
                 "time_solve_s,rows,rows_solved,snapshot\n";
        for (int f = 0; f < 6; ++f) {
            char name[64];
            std::snprintf(name, sizeof name, "x_f%04d_n0.qpsnap", f);
            // steps.csv records the path used at simulate time; the folder's snapshots/ is what counts.
            steps << f << "," << f << ",0,mprgp,converged,3,1e-7,0.1,0.1,0.1," << 10 * f << "," << 10 * f
                  << ",elsewhere/snapshots/" << name << "\n";
            fs::copy_file(fs::path(CB_TEST_DATA_DIR) / "plane_2x2x2.qpsnap", root / "sim" / "x" / "snapshots" / name);
        }
    }
    void TearDown() override { fs::remove_all(root); }

    std::vector<std::string> stems(const nlohmann::json& entry)
    {
        const nlohmann::json suite = {{"name", "s"}, {"snapshots", {entry}}, {"solvers", {"cg"}}};
        std::vector<std::string> out;
        for (const auto& s : cb::resolve_snapshots(cb::parse_suite(suite, (root / "suite.json").string())))
            out.push_back(fs::path(s.path).filename().string());
        return out;
    }
    std::string error(const nlohmann::json& entry)
    {
        try {
            stems(entry);
        } catch (const cb::InputError& e) {
            return e.what();
        }
        return "no error";
    }

    fs::path root;
};

TEST_F(SuiteSimulation, FrameRangeStrideAndMinRows)
{
    EXPECT_EQ(stems({{"sim", "sim/x"}, {"frames", "3:5"}}),
              (std::vector<std::string>{"x_f0003_n0.qpsnap", "x_f0004_n0.qpsnap"}));
    EXPECT_EQ(stems({{"sim", "sim/x"}, {"frames", "1:"}, {"stride", 2}}),
              (std::vector<std::string>{"x_f0001_n0.qpsnap", "x_f0003_n0.qpsnap", "x_f0005_n0.qpsnap"}));
    EXPECT_EQ(stems({{"sim", "sim/x"}, {"frames", ":4"}, {"min_rows", 20}}),
              (std::vector<std::string>{"x_f0002_n0.qpsnap", "x_f0003_n0.qpsnap"}));
    EXPECT_EQ(stems({{"sim", "sim/x"}, {"frames", 5}}), (std::vector<std::string>{"x_f0005_n0.qpsnap"}));
    EXPECT_EQ(stems({{"sim", "sim/x"}}).size(), 6u);
}

TEST_F(SuiteSimulation, KeepsTheSuiteOrderAmongPatterns)
{
    const nlohmann::json suite = {
        {"name", "s"},
        {"snapshots", {"sim/x/snapshots/x_f0000_n0.qpsnap", {{"sim", "sim/x"}, {"frames", "4:5"}}}},
        {"solvers", {"cg"}}};
    const auto snaps = cb::resolve_snapshots(cb::parse_suite(suite, (root / "suite.json").string()));
    ASSERT_EQ(snaps.size(), 2u);
    EXPECT_EQ(snaps[0].id, "x_f0000_n0");
    EXPECT_EQ(snaps[1].id, "x_f0004_n0");
}

TEST_F(SuiteSimulation, MissingFolderSaysWhichCommandMakesIt)
{
    const std::string suite = (root / "suite.json").string();
    EXPECT_EQ(error({{"sim", "sim/demo"}, {"frames", "3:8"}, {"scene", "../scenes/demo.json"}}),
              suite + ": /snapshots/0: no simulation in '" + (root / "sim/demo").string() +
                  "' (no such folder); make it with: contactbench simulate " +
                  (root.parent_path() / "scenes/demo.json").string() + " --out " + (root / "sim/demo").string() +
                  " --frames 8");
}

TEST_F(SuiteSimulation, TooFewFramesSaysHowManyToSimulate)
{
    const std::string msg = error({{"sim", "sim/x"}, {"frames", "4:9"}});
    EXPECT_NE(msg.find("frames up to 8 asked, but '" + (root / "sim/x").string() + "' holds frames 0..5"),
              std::string::npos)
        << msg;
    EXPECT_NE(
        msg.find("make them with: contactbench simulate SCENE.json --out " + (root / "sim/x").string() + " --frames 9"),
        std::string::npos)
        << msg;
}

TEST_F(SuiteSimulation, MissingSnapshotIsNamed)
{
    fs::remove(root / "sim" / "x" / "snapshots" / "x_f0002_n0.qpsnap");
    const std::string msg = error({{"sim", "sim/x"}, {"frames", "2:4"}});
    EXPECT_NE(msg.find("snapshot '" + (root / "sim/x/snapshots/x_f0002_n0.qpsnap").string() +
                       "' is missing; make it with: contactbench simulate SCENE.json --out " +
                       (root / "sim/x").string() + " --frames 4"),
              std::string::npos)
        << msg;
}

TEST_F(SuiteSimulation, BadEntriesAreNamed)
{
    const std::string suite = (root / "suite.json").string();
    EXPECT_EQ(error({{"sim", "sim/x"}, {"frames", "5:3"}}),
              suite + ": /snapshots/0: /frames: \"5:3\" selects no frame (a:b means frames a to b-1)");
    EXPECT_EQ(error({{"sim", "sim/x"}, {"stride", 0}}),
              suite + ": /snapshots/0: /stride: expected an integer >= 1, got 0");
    EXPECT_EQ(error({{"sim", "sim/x"}, {"frame", "1"}}),
              suite + ": /snapshots/0: /frame: unknown key; known: frames, min_rows, newton, scene, sim, stride");
    EXPECT_EQ(error({{"sim", "sim/x"}, {"min_rows", 1000}}), suite + ": /snapshots/0: selects no snapshot of '" +
                                                                 (root / "sim/x").string() +
                                                                 "' (frames 0..5, min_rows 1000)");
}

}  // namespace
