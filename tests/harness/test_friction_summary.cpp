// Issue 48: summary.csv carries a frictional run's friction columns (fclib_error, solved_problem,
// mu_min, mu_max), empty for a frictionless run; plots/loader.py names the same columns.
#include "harness/results.hpp"
#include "harness/runner.hpp"
#include "problems/synthetic.hpp"

#include "tests/solvers/friction_test_qps.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <iterator>
#include <map>
#include <regex>

using namespace cb;

namespace {

/// The summary row of `run` by column name (no cell of these runs holds a comma).
std::map<std::string, std::string> summary_cells(const nlohmann::json& run)
{
    const std::string line = summary_row(run, "suite");
    std::map<std::string, std::string> cells;
    size_t start = 0;
    for (const std::string& column : summary_columns()) {
        const size_t end = std::min(line.find(',', start), line.size());
        cells[column] = line.substr(start, end - start);
        start = end + 1;
    }
    return cells;
}

}  // namespace

TEST(FrictionSummary, FrictionalRunsFillTheFrictionColumnsFrictionlessOnesLeaveThemEmpty)
{
    RunOptions quiet;
    quiet.record_history = false;
    const Qp qp = testing_qps::pushed_plane(0.2, 0.5);
    const RunOutcome fric = run_solver(qp, "nsgs-friction", {{"tol", 1e-8}, {"max_iterations", 100000}}, quiet);
    auto cells = summary_cells(fric.record);
    ASSERT_FALSE(cells["fclib_error"].empty());
    EXPECT_EQ(std::stod(cells["fclib_error"]), fric.fclib_error);
    EXPECT_EQ(cells["solved_problem"], "");  // it solved the frictional problem itself
    EXPECT_EQ(cells["mu_min"], "0.5");
    EXPECT_EQ(cells["mu_max"], "0.5");

    const RunOutcome relaxation = run_solver(qp, "pgs", {{"tol", 1e-8}}, quiet);
    cells = summary_cells(relaxation.record);
    EXPECT_EQ(cells["status"], "solved_relaxation");
    EXPECT_EQ(cells["solved_problem"], "frictionless");
    EXPECT_FALSE(cells["fclib_error"].empty());
    EXPECT_EQ(cells["mu_max"], "0.5");

    const Qp plain = make_synthetic("plane", {{"nx", 2}, {"ny", 2}, {"nz", 2}}, 3);
    cells = summary_cells(run_solver(plain, "pgs", {{"tol", 1e-8}}, quiet).record);
    EXPECT_EQ(cells["status"], "converged");
    for (const char* column : {"fclib_error", "solved_problem", "mu_min", "mu_max"})
        EXPECT_EQ(cells[column], "") << column;
}

TEST(FrictionSummary, LoaderNamesEverySummaryColumnInOrder)
{
    std::ifstream in(std::string(CB_SOURCE_DIR) + "/plots/loader.py");
    const std::string text((std::istreambuf_iterator<char>(in)), {});
    const size_t at = text.find("SUMMARY_COLUMNS = [");
    ASSERT_NE(at, std::string::npos);
    const std::string list = text.substr(at, text.find(']', at) - at);
    std::vector<std::string> loader;
    const std::regex quoted("\"([a-z_]+)\"");
    for (auto it = std::sregex_iterator(list.begin(), list.end(), quoted); it != std::sregex_iterator(); ++it)
        loader.push_back((*it)[1]);
    EXPECT_EQ(loader, summary_columns());
}
