// `simulate --solver NAME` with another solver than the scene's (issue 25): NAME gets its own
// defaults plus the scene's common settings, never the scene solver's own keys or its native
// tolerance (a native residual is each solver's own, in its own units).
#include "cli_test_util.hpp"
#include "harness/sim_step_solver.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <sstream>

using namespace cb;
using nlohmann::json;
namespace fs = std::filesystem;

namespace {
const json MPRGP_NATIVE = {{"stop", "native"}, {"tol", 1e-5}, {"max_iterations", 5000}, {"gamma", 2}};
}

TEST(SettingsForSolver, TheScenesOwnSolverKeepsEverySetting)
{
    const ReplacedSolverSettings same = settings_for_solver("mprgp", MPRGP_NATIVE, "mprgp");
    EXPECT_EQ(same.settings, MPRGP_NATIVE);
    EXPECT_TRUE(same.dropped.empty());
}

TEST(SettingsForSolver, AnotherSolverGetsOnlyTheCommonSettingsAndNoNativeTolerance)
{
    const ReplacedSolverSettings pgs = settings_for_solver("mprgp", MPRGP_NATIVE, "pgs");
    EXPECT_EQ(pgs.settings, json({{"max_iterations", 5000}}));
    EXPECT_EQ(pgs.dropped, (std::vector<std::string>{"gamma", "stop", "tol"}));
    // A tolerance on e means the same for every solver: it is passed on with its stop rule.
    const json kkt = {{"stop", "kkt"}, {"tol", 1e-7}, {"seed", 3}, {"time_limit_s", 9.5}, {"precond", "ichol"}};
    const ReplacedSolverSettings on_e = settings_for_solver("mprgp", kkt, "active-set");
    EXPECT_EQ(on_e.settings, json({{"stop", "kkt"}, {"tol", 1e-7}, {"seed", 3}, {"time_limit_s", 9.5}}));
    EXPECT_EQ(on_e.dropped, std::vector<std::string>{"precond"});
}

TEST(SimulateSolver, PgsStepsAMprgpSceneWithItsOwnDefaults)
{
    const fs::path dir = test::make_test_work_dir("simulate_solver");
    std::ifstream in(std::string(CB_SOURCE_DIR) + "/scenes/demo.json");
    json scene = json::parse(in);
    scene["solver_settings"] = MPRGP_NATIVE;  // gamma is mprgp's: pgs would reject it
    {
        std::ofstream(dir / "demo_gamma.json") << scene.dump();
    }
    const fs::path out = dir / "out";
    const test::Output run =
        test::run_captured("'" + test::contactbench_binary() + "' simulate '" + (dir / "demo_gamma.json").string() +
                               "' --solver pgs --frames 3 --no-snapshots --out '" + out.string() + "'",
                           dir);
    ASSERT_EQ(run.status, 0) << run.err;
    EXPECT_NE(run.err.find("simulate: --solver pgs: the scene's settings for mprgp not passed on: gamma stop tol "
                           "(pgs's defaults apply; docs/simulator.md)\n"),
              std::string::npos)
        << run.err;
    // Frame 2 has the lower box's ground rows: pgs stops on its default, e <= 1e-6 on every row
    // (with mprgp's native tol 1e-5 it would stop on its own natural residual instead).
    std::stringstream steps(test::slurp(out / "steps.csv"));
    std::string line;
    std::getline(steps, line);
    ASSERT_EQ(line.rfind("frame,step,newton_iteration,solver,status,solver_status,iterations,accuracy,", 0), 0u)
        << line;
    int with_rows = 0;
    while (std::getline(steps, line)) {
        std::vector<std::string> cell;
        std::stringstream ls(line);
        for (std::string c; std::getline(ls, c, ',');) cell.push_back(c);
        ASSERT_GE(cell.size(), 14u) << line;
        EXPECT_EQ(cell[3], "pgs");
        EXPECT_EQ(cell[4], "converged");
        EXPECT_LE(std::stod(cell[7]), 1e-6) << line;
        with_rows += std::stol(cell[12]) > 0;
    }
    EXPECT_GE(with_rows, 1);
    fs::remove_all(dir);
}
