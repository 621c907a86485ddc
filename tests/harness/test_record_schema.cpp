// The record schema's one name for the accuracy error (harness/record_schema.hpp): every writer
// uses "accuracy"; files of the previous release (JSON "kkt_relative", CSV "kkt_rel" and
// "kkt_rel_solved") are still read, with one notice per file and name on stderr. docs/INTERFACES.md
// names every key and column the code writes.
#include "harness/compare.hpp"
#include "harness/history.hpp"
#include "harness/perf_record.hpp"
#include "harness/record_schema.hpp"
#include "harness/results.hpp"
#include "harness/run_record.hpp"
#include "harness/runner.hpp"
#include "problems/qpsnap.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <unistd.h>

using namespace cb;
namespace fs = std::filesystem;

namespace {

fs::path fresh_schema_dir(const std::string& name)
{
    fs::path dir = fs::temp_directory_path() / ("cb_test_record_schema_" + std::to_string(::getpid())) / name;
    fs::remove_all(dir);
    fs::create_directories(dir);
    return dir;
}

std::string notice(const std::string& source, const std::string& old_name, const std::string& new_name)
{
    return "notice: " + source + ": read the old name '" + old_name + "' as '" + new_name +
           "' (accepted until the next release; rewrite the file to use '" + new_name + "')\n";
}

bool has(const std::vector<std::string>& names, const std::string& name)
{
    return std::find(names.begin(), names.end(), name) != names.end();
}

}  // namespace

TEST(RecordSchema, WritersUseTheNewNamesOnly)
{
    for (const auto* columns : {&summary_columns(), &perf_record_columns()}) {
        EXPECT_TRUE(has(*columns, "accuracy"));
        EXPECT_FALSE(has(*columns, "kkt_rel"));
        EXPECT_FALSE(has(*columns, "kkt_rel_solved"));
    }
    EXPECT_TRUE(has(summary_columns(), "accuracy_solved"));
    EXPECT_TRUE(has(HistoryMonitor::columns(), "accuracy"));
    EXPECT_FALSE(has(HistoryMonitor::columns(), "kkt_rel"));
}

TEST(RecordSchema, OtherColumnNamesPassUnchangedWithoutNotice)
{
    testing::internal::CaptureStderr();
    EXPECT_EQ(current_column_name("accuracy", "x.csv"), "accuracy");
    EXPECT_EQ(current_column_name("kkt", "x.csv"), "kkt");
    EXPECT_EQ(current_column_name("accuracy_solved", "x.csv"), "accuracy_solved");
    EXPECT_EQ(testing::internal::GetCapturedStderr(), "");
}

TEST(RecordSchema, OldPerfRecordColumnReadWithOneNotice)
{
    const fs::path dir = fresh_schema_dir("perf");
    const std::string csv = (dir / "old.csv").string();
    write_file_atomic(csv, "snapshot,label,status,kkt_rel,tol\nbox,cg,converged,2.5e-07,1e-06\nbox,pgs,converged,3e-"
                           "07,1e-06\n");
    testing::internal::CaptureStderr();
    const std::vector<nlohmann::json> runs = read_perf_record(csv);
    read_perf_record(csv);  // a second read of the same file: no second notice
    EXPECT_EQ(testing::internal::GetCapturedStderr(), notice(csv, "kkt_rel", "accuracy"));
    ASSERT_EQ(runs.size(), 2u);
    EXPECT_DOUBLE_EQ(runs[0]["accuracy"]["max"].get<double>(), 2.5e-7);
    EXPECT_DOUBLE_EQ(runs[1]["accuracy"]["max"].get<double>(), 3e-7);
    EXPECT_FALSE(runs[0].contains("kkt_relative"));
    // A bad cell is still reported under the column name the file uses.
    const std::string bad = (dir / "bad.csv").string();
    write_file_atomic(bad, "snapshot,label,status,kkt_rel\nbox,cg,converged,x\n");
    testing::internal::CaptureStderr();
    try {
        read_perf_record(bad);
        ADD_FAILURE() << "no error";
    } catch (const InputError& e) {
        EXPECT_EQ(std::string(e.what()), bad + ": line 2: column kkt_rel: expected a number, got 'x'");
    }
    testing::internal::GetCapturedStderr();
}

TEST(RecordSchema, CommittedBaselineIsReadable)
{
    // results/baselines/ci.csv was recorded before the rename; the perf gate reads it through the shim.
    const std::string csv = std::string(CB_SOURCE_DIR) + "/results/baselines/ci.csv";
    testing::internal::CaptureStderr();
    const std::vector<nlohmann::json> runs = read_perf_record(csv);
    const std::string err = testing::internal::GetCapturedStderr();
    ASSERT_FALSE(runs.empty());
    EXPECT_TRUE(err.empty() || err == notice(csv, "kkt_rel", "accuracy")) << err;
    for (const auto& run : runs) EXPECT_TRUE(run.contains("accuracy")) << run.dump();
}

TEST(RecordSchema, OldRunRecordReadWithNotice)
{
    const nlohmann::json old_run = {{"_file", "plane__old-cg.json"},
                                    {"snapshot", {{"id", "plane"}}},
                                    {"label", "old-cg"},
                                    {"solver", "cg"},
                                    {"status", "converged"},
                                    {"tol", 1e-6},
                                    {"iterations", 4},
                                    {"kkt_relative",
                                     {{"stationarity", 0.125},
                                      {"primal", 0.0},
                                      {"dual", 0.0},
                                      {"complementarity", 0.0},
                                      {"gap", 0.0},
                                      {"max", 0.125}}}};
    testing::internal::CaptureStderr();
    const std::string row = summary_row(old_run, "s");
    EXPECT_EQ(testing::internal::GetCapturedStderr(), notice("plane__old-cg.json", "kkt_relative", "accuracy"));
    // accuracy, stationarity .. gap, accuracy_solved (= accuracy when the problem was not changed)
    EXPECT_NE(row.find(",0.125,0.125,0,0,0,0,0.125,"), std::string::npos) << row;

    // compare judges an old BASE against a new NEW on the same quantity.
    nlohmann::json new_run = old_run;
    new_run.erase("kkt_relative");
    new_run["accuracy"] = {{"max", 0.5}};
    CompareInput base, next;
    base.source = "OLD";
    next.source = "NEW";
    base.runs = {old_run};
    next.runs = {new_run};
    testing::internal::CaptureStderr();
    const CompareReport report = compare_inputs(base, next, CompareOptions{});
    EXPECT_EQ(testing::internal::GetCapturedStderr(), notice("OLD", "kkt_relative", "accuracy"));
    ASSERT_EQ(report.rows.size(), 1u);
    EXPECT_DOUBLE_EQ(report.rows[0].base["accuracy"].get<double>(), 0.125);
    EXPECT_EQ(report.rows[0].regressed, std::vector<std::string>{"accuracy"});
}

TEST(RecordSchema, NewNameWinsOverTheOldOne)
{
    const nlohmann::json both = {{"accuracy", {{"max", 1e-8}}}, {"kkt_relative", {{"max", 1.0}}}};
    testing::internal::CaptureStderr();
    EXPECT_DOUBLE_EQ(accuracy_max(both, "both.json").get<double>(), 1e-8);
    EXPECT_EQ(testing::internal::GetCapturedStderr(), "");
    EXPECT_TRUE(accuracy_max(nlohmann::json::object(), "none.json").is_null());
}

namespace {

/// The text of one "## ..." or "### ..." section of docs/INTERFACES.md (up to the next heading).
std::string interfaces_section(const std::string& heading)
{
    std::ifstream in(std::string(CB_SOURCE_DIR) + "/docs/INTERFACES.md");
    std::string line, text;
    bool inside = false;
    while (std::getline(in, line)) {
        if (line.rfind('#', 0) == 0) {
            if (inside) break;
            inside = line.find(heading) != std::string::npos;
            continue;
        }
        if (inside) text += line + "\n";
    }
    return text;
}

/// The names a section documents: the first cell of each table row (comma-separated names) and
/// every `backticked` word.
std::set<std::string> documented_names(const std::string& section)
{
    std::set<std::string> names;
    std::istringstream in(section);
    std::string line;
    while (std::getline(in, line)) {
        if (line.rfind("| ", 0) == 0) {
            std::string cell = line.substr(2, line.find(" |", 2) - 2);
            std::replace(cell.begin(), cell.end(), ',', ' ');
            std::istringstream words(cell);
            for (std::string w; words >> w;) names.insert(w);
        }
        for (size_t a = line.find('`'); a != std::string::npos; a = line.find('`', a + 1)) {
            const size_t b = line.find('`', a + 1);
            if (b == std::string::npos) break;
            names.insert(line.substr(a + 1, b - a - 1));
            a = b;
        }
    }
    return names;
}

}  // namespace

TEST(RecordSchema, InterfacesDocumentsEveryKeyAndColumn)
{
    const std::set<std::string> summary = documented_names(interfaces_section("summary.csv columns"));
    for (const auto& column : summary_columns()) EXPECT_TRUE(summary.count(column)) << "summary.csv: " << column;
    const std::set<std::string> perf = documented_names(interfaces_section("Performance record columns"));
    for (const auto& column : perf_record_columns()) EXPECT_TRUE(perf.count(column)) << "perf record: " << column;
    const std::set<std::string> history = documented_names(interfaces_section("History columns"));
    for (const auto& column : HistoryMonitor::columns()) EXPECT_TRUE(history.count(column)) << "history: " << column;
    // Every key of a real run record (with its history and the keys `run` adds) and of a failed one.
    const std::set<std::string> record = documented_names(interfaces_section("Run record"));
    const Qp qp = read_qpsnap(std::string(CB_TEST_DATA_DIR) + "/plane_2x2x2.qpsnap");
    RunOptions options;
    options.repeat = 2;
    nlohmann::json run = run_solver(qp, "cg", {}, options).record;  // cg changes the QP: accuracy_solved
    for (const char* key :
         {"suite", "mode", "concurrent_jobs", "final", "identity", "reference", "reference_note", "energy_gap"})
        run[key] = nullptr;
    for (const auto& item : run.items()) EXPECT_TRUE(record.count(item.key())) << "run record: " << item.key();
    for (const auto& item : run["time"].items()) EXPECT_TRUE(record.count(item.key())) << "time: " << item.key();
    for (const auto& item : run["memory"].items()) EXPECT_TRUE(record.count(item.key())) << "memory: " << item.key();
    for (const auto& item : run["accuracy"].items())
        EXPECT_TRUE(record.count(item.key())) << "accuracy: " << item.key();
    const nlohmann::json failed = failed_record("cg", "cg", {}, {}, "invalid_input", "m", 1e-6);
    for (const auto& item : failed.items()) EXPECT_TRUE(record.count(item.key())) << "failed record: " << item.key();
}
