// The end of `run` (issue 46): the table per solver label (harness/run_summary_table.hpp) and the
// `report` command's refusals. The page itself: tests/python/test_html_report.py and, in
// Chromium, tests/browser/test_report_browser.py (ctest browser.report).
#include "harness/run_summary_table.hpp"

#include "cli_test_util.hpp"

#include <gtest/gtest.h>

using namespace cb;

namespace {

nlohmann::json run_end_record(const std::string& label, const std::string& status, double total_s)
{
    return {{"label", label}, {"solver", label}, {"status", status}, {"time", {{"total_s", total_s}}}};
}

}  // namespace

TEST(RunSummaryTable, SolvedStatusesAndShiftedGeometricMean)
{
    // Solved times 1, 3, 2, 4: median 2.5, shift 0.25. a: sqrt(1.25 * 3.25) - 0.25 = 1.7656;
    // b: its unsolved run at the 10 s penalty, sqrt(2.25 * 10.25) - 0.25 = 4.5523; c: its n/a run
    // is not judged, 4 s.
    const std::vector<nlohmann::json> runs = {
        run_end_record("a", "converged", 1.0),      run_end_record("b", "converged", 2.0),
        run_end_record("c", "not_applicable", 0.1), run_end_record("a", "converged", 3.0),
        run_end_record("b", "max_iterations", 7.0), run_end_record("c", "converged", 4.0)};
    EXPECT_EQ(run_summary_table(runs, 10.0),
              "summary: solved = status converged (e <= tol on the original QP) of the runs judged (n/a left out);\n"
              "         sgm = shifted geometric mean of setup + solve time, unsolved runs at 10 s, shift 0.25 s\n"
              "  label  solved      sgm [s]  statuses\n"
              "  a      2/2            1.77  converged 2\n"
              "  b      1/2            4.55  converged 1, max_iterations 1\n"
              "  c      1/1               4  converged 1, not_applicable 1\n");
}

TEST(RunSummaryTable, NoTimeLimitCountsUnsolvedAtTheLargestTime)
{
    const std::vector<nlohmann::json> runs = {run_end_record("long-label-x", "stalled", 8.0)};
    const std::string table = run_summary_table(runs, 0.0);
    EXPECT_NE(table.find("unsolved runs at 8 s, shift 1e-06 s"), std::string::npos) << table;
    EXPECT_NE(table.find("  long-label-x  0/1               8  stalled 1\n"), std::string::npos) << table;
}

TEST(ReportCommand, RefusesWhatIsNoResultsFolder)
{
    const auto dir = test::make_test_work_dir("report_refusal");
    const std::string cb = test::contactbench_binary();
    const test::Output missing = test::run_captured(cb + " report '" + (dir / "nope").string() + "'", dir);
    EXPECT_EQ(missing.status, 2);
    EXPECT_EQ(missing.err, "contactbench report: error: " + (dir / "nope").string() + ": not a folder\n");
    std::filesystem::create_directories(dir / "empty");
    const test::Output empty = test::run_captured(cb + " report '" + (dir / "empty").string() + "'", dir);
    EXPECT_EQ(empty.status, 2) << empty.err;
    EXPECT_NE(empty.err.find("empty: not a results folder (no runs/ and no summary.csv)"), std::string::npos)
        << empty.err;
    EXPECT_FALSE(std::filesystem::exists(dir / "empty" / "report"));
    std::filesystem::remove_all(dir);
}
