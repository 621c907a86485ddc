// Results folder pieces: atomic writes, summary.csv, suite parsing and snapshot resolution,
// the reference cache.
#include "harness/reference.hpp"
#include "harness/results.hpp"
#include "harness/runner.hpp"
#include "harness/suite.hpp"
#include "problems/qpsnap.hpp"
#include "problems/synthetic.hpp"
#include "solvers/core/registry.hpp"
#include "tests/harness/cli_test_util.hpp"

#include <gtest/gtest.h>
#include <cmath>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <unistd.h>

using namespace cb;
namespace fs = std::filesystem;

namespace {

fs::path fresh_results_dir(const std::string& name)
{
    fs::path dir = fs::temp_directory_path() / ("cb_test_results_" + std::to_string(::getpid())) / name;
    fs::remove_all(dir);
    fs::create_directories(dir);
    return dir;
}

size_t count_tmp(const fs::path& dir)
{
    size_t n = 0;
    for (const auto& e : fs::recursive_directory_iterator(dir))
        if (e.path().filename().string().find(".tmp") != std::string::npos) ++n;
    return n;
}

std::string results_error_of(const std::function<void()>& f)
{
    try {
        f();
    } catch (const InputError& e) {
        return e.what();
    }
    return "(no InputError)";
}

/// Removes the scratch folder after the last test.
class ResultsCleanUp : public ::testing::Environment {
public:
    void TearDown() override
    {
        fs::remove_all(fs::temp_directory_path() / ("cb_test_results_" + std::to_string(::getpid())));
    }
};
const auto* const RESULTS_CLEAN_UP = ::testing::AddGlobalTestEnvironment(new ResultsCleanUp);

}  // namespace

TEST(Results, AtomicWriteReplacesAndLeavesNoTemporary)
{
    const fs::path dir = fresh_results_dir("atomic");
    const std::string path = (dir / "sub" / "a.json").string();
    write_json_atomic(path, {{"x", 1}});
    write_json_atomic(path, {{"x", 2}, {"nan", std::nan("")}});
    const nlohmann::json back = read_json_file(path);
    EXPECT_EQ(back["x"], 2);
    EXPECT_TRUE(back["nan"].is_null());
    EXPECT_EQ(count_tmp(dir), 0u);
    EXPECT_EQ(results_error_of([&] { read_json_file((dir / "missing.json").string()); }),
              (dir / "missing.json").string() + ": cannot open: No such file or directory");
}

TEST(Results, SummaryColumnsAndRow)
{
    const std::string expected =
        "suite,snapshot,label,solver,status,solver_status,criterion,status_confirmed,iterations,a_products,"
        "work,cholmod_factorizations,accuracy,stationarity,primal,dual,complementarity,gap,accuracy_solved,m_solved,"
        "objective,energy_gap,violation,native_residual,nonfinite,monotone,setup_s,solve_s,time_s,peak_rss_mb,n,m,tol,"
        "length_scale,length_scale_source,fclib_error,solved_problem,mu_min,mu_max";
    std::string header;
    for (size_t i = 0; i < summary_columns().size(); ++i) header += (i ? "," : "") + summary_columns()[i];
    EXPECT_EQ(header, expected);
    const nlohmann::json run = {{"solver", "mprgp"},
                                {"label", "mprgp-jacobi"},
                                {"status", "solved_relaxation"},
                                {"solver_status", "converged"},
                                {"criterion", "kkt"},
                                {"status_confirmed", true},
                                {"iterations", 54},
                                {"snapshot", {{"id", "plane-s1"}, {"n", 375}, {"m", 25}}},
                                {"counters", {{"a_products", 120}, {"work", 137.5}, {"cholmod_factorizations", 0}}},
                                {"accuracy",
                                 {{"max", 0.25},
                                  {"stationarity", 0.25},
                                  {"primal", 0.0},
                                  {"dual", 0.0},
                                  {"complementarity", 0.125},
                                  {"gap", 0.0625}}},
                                {"accuracy_solved", {{"max", 0.5}}},
                                {"m_solved", 12},
                                {"energy_gap", 0.75},
                                {"objective", -4.5},
                                {"violation", 0.0},
                                {"native_residual", nullptr},
                                {"nonfinite", false},
                                {"monotone", true},
                                {"time", {{"setup_s", 0.5}, {"solve_s", 1.5}, {"total_s", 2.0}}},
                                {"memory", {{"peak_rss_mb", 48.25}}},
                                {"tol", 1e-6},
                                {"length_scale", 2.0},
                                {"length_scale_source", "x0_extent"},
                                {"message", "a, \"quoted\" message"}};
    EXPECT_EQ(summary_row(run, "demo"),
              "demo,plane-s1,mprgp-jacobi,mprgp,solved_relaxation,converged,kkt,true,54,120,137.5,0,0.25,0.25,0,0,"
              "0.125,0.0625,0.5,12,-4.5,0.75,0,,false,true,0.5,1.5,2,48.25,375,25,9.9999999999999995e-07,2,x0_extent,"
              ",,,");
    // A run on an unchanged problem: the solved error and rows are the original's.
    nlohmann::json plain = run;
    plain.erase("accuracy_solved");
    plain.erase("m_solved");
    const std::string row = summary_row(plain, "demo");
    EXPECT_NE(row.find(",0.125,0.0625,0.25,25,-4.5,"), std::string::npos) << row;
    const std::string csv = summary_csv({run, run}, "demo");
    EXPECT_EQ(csv.substr(0, expected.size() + 1), expected + "\n");
    EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 3);
}

TEST(Results, WriteSummaryReadsEveryRunFile)
{
    const fs::path dir = fresh_results_dir("summary");
    write_json_atomic((dir / "runs" / run_file_name("b", "cg")).string(),
                      {{"label", "cg"}, {"solver", "cg"}, {"snapshot", {{"id", "b"}}}, {"status", "converged"}});
    write_json_atomic((dir / "runs" / run_file_name("a", "pgs")).string(),
                      {{"label", "pgs"}, {"solver", "pgs"}, {"snapshot", {{"id", "a"}}}, {"status", "stalled"}});
    EXPECT_EQ(write_summary(dir.string(), "s"), 2u);
    const std::string csv = cb::test::slurp(dir / "summary.csv");
    // Sorted by file name: a__pgs before b__cg.
    EXPECT_NE(csv.find("\ns,a,pgs,pgs,stalled,"), std::string::npos) << csv;
    EXPECT_LT(csv.find("s,a,pgs"), csv.find("s,b,cg"));
    EXPECT_EQ(count_tmp(dir), 0u);
}

TEST(Suite, ParsesDefaultsAndSolvers)
{
    const Suite s =
        parse_suite({{"name", "t"},
                     {"snapshots", {"x.qpsnap"}},
                     {"solvers", {{{"label", "m1"}, {"solver", "mprgp"}, {"settings", {{"tol", 1e-4}}}}, "cg"}}},
                    "suite.json");
    EXPECT_EQ(s.name, "t");
    ASSERT_EQ(s.solvers.size(), 2u);
    EXPECT_EQ(s.solvers[0].label, "m1");
    EXPECT_EQ(s.solvers[1].label, "cg");
    EXPECT_EQ(s.solvers[1].solver, "cg");
    EXPECT_DOUBLE_EQ(s.tol, 1e-6);
    EXPECT_EQ(s.repeat, 1);
    EXPECT_EQ(s.history_max, 2000);
    EXPECT_EQ(s.decouple, "auto");
    EXPECT_FALSE(s.chain);
    EXPECT_FALSE(s.reference);
}

TEST(Suite, RejectsBadSuitesNamingTheField)
{
    const nlohmann::json good = {{"name", "t"}, {"snapshots", {"x.qpsnap"}}, {"solvers", {"cg"}}};
    auto with = [&](const std::string& key, const nlohmann::json& value) {
        nlohmann::json j = good;
        j[key] = value;
        return j;
    };
    EXPECT_EQ(results_error_of([&] { parse_suite(with("colour", 1), "s.json"); }).substr(0, 24),
              "s.json: /colour: unknown");
    EXPECT_EQ(results_error_of([&] { parse_suite(with("tol", -1), "s.json"); }), "s.json: /tol: must be > 0, got -1");
    EXPECT_EQ(results_error_of([&] { parse_suite(with("decouple", "up"), "s.json"); }),
              "s.json: /decouple: expected one of auto, none, authors, random, depth, got 'up'");
    EXPECT_EQ(results_error_of([&] {
                  parse_suite(with("solvers", nlohmann::json::array({"cg", "cg"})), "s.json");
              }),
              "s.json: /solvers/1: /label: duplicate label 'cg'");
    EXPECT_EQ(results_error_of([&] { parse_suite(with("repeat", 0), "s.json"); }),
              "s.json: /repeat: must be >= 1, got 0");
    nlohmann::json no_solvers = good;
    no_solvers.erase("solvers");
    EXPECT_EQ(results_error_of([&] { parse_suite(no_solvers, "s.json"); }),
              "s.json: /solvers: missing (an array of {label, solver, settings})");
    EXPECT_EQ(results_error_of([&] { load_suite("/nonexistent/suite.json"); }),
              "/nonexistent/suite.json: cannot open: No such file or directory");
}

TEST(Suite, ResolvesGlobsFoldersDuplicatesAndGenerated)
{
    const fs::path dir = fresh_results_dir("resolve");
    const Qp qp = make_synthetic("plane", {{"nx", 2}, {"ny", 2}, {"nz", 2}}, 1);
    fs::create_directories(dir / "a");
    fs::create_directories(dir / "b");
    write_qpsnap((dir / "a" / "f1.qpsnap").string(), qp);
    write_qpsnap((dir / "a" / "f2.qpsnap").string(), qp);
    write_qpsnap((dir / "b" / "f1.qpsnap").string(), qp);
    const nlohmann::json j = {
        {"name", "r"},
        {"snapshots", {"a/f*.qpsnap", "b/", "a/f1.qpsnap"}},
        {"generate", {{{"id", "gen"}, {"family", "plane"}, {"seed", 3}, {"params", {{"nx", 2}}}}}},
        {"solvers", {"cg"}}};
    const Suite s = parse_suite(j, (dir / "suite.json").string());
    const auto snaps = resolve_snapshots(s, (dir / "cache").string());
    ASSERT_EQ(snaps.size(), 4u);  // a/f1 listed twice counts once
    EXPECT_EQ(snaps[0].id, "f1");
    EXPECT_EQ(snaps[1].id, "f2");
    EXPECT_EQ(snaps[2].id, "f1-2");
    EXPECT_EQ(snaps[3].id, "gen");
    EXPECT_TRUE(snaps[3].generated);
    const auto first_time = fs::last_write_time(snaps[3].path);
    const auto again = resolve_snapshots(s, (dir / "cache").string());
    EXPECT_EQ(again[3].path, snaps[3].path);  // cached by content key, not rewritten
    EXPECT_EQ(fs::last_write_time(again[3].path), first_time);
    EXPECT_EQ(read_qpsnap(snaps[3].path).n(), make_synthetic("plane", {{"nx", 2}}, 3).n());
    const Suite missing =
        parse_suite({{"name", "r"}, {"snapshots", {"zz*.qpsnap"}}, {"solvers", {"cg"}}}, (dir / "suite.json").string());
    EXPECT_EQ(results_error_of([&] { resolve_snapshots(missing, (dir / "cache").string()); }),
              (dir / "suite.json").string() + ": /snapshots/0: pattern '" + (dir / "zz*.qpsnap").string() +
                  "' matches no file");
}

TEST(Reference, CachedByKeyAndAttached)
{
    if (!builtin_registry().contains("active-set")) GTEST_SKIP() << "active-set not registered";
    const fs::path dir = fresh_results_dir("reference");
    const Qp qp = make_synthetic("plane", {{"nx", 2}, {"ny", 2}, {"nz", 2}}, 2);
    const nlohmann::json ref = reference_solution(qp, "k1", dir.string());
    ASSERT_TRUE(ref["objective"].is_number()) << ref.dump();
    EXPECT_FALSE(ref["cached"].get<bool>());
    // Keyed on the snapshot key and the reference method (solver, settings, version): k1-<method>.json.
    EXPECT_EQ(ref["method"]["solver"], "active-set");
    EXPECT_EQ(ref["method"]["version"], REFERENCE_VERSION);
    std::vector<fs::path> files;
    for (const auto& e : fs::directory_iterator(dir / "reference")) files.push_back(e.path());
    ASSERT_EQ(files.size(), 1u);
    EXPECT_EQ(files[0].filename().string().rfind("k1-", 0), 0u) << files[0];
    const nlohmann::json again = reference_solution(qp, "k1", dir.string());
    EXPECT_TRUE(again["cached"].get<bool>());
    EXPECT_EQ(again["objective"], ref["objective"]);
    // An entry made by another method under that name is recomputed, not trusted.
    nlohmann::json other = read_json_file(files[0].string());
    other["method"]["settings"]["tol"] = 1e-3;
    write_json_atomic(files[0].string(), other);
    EXPECT_FALSE(reference_solution(qp, "k1", dir.string())["cached"].get<bool>());
    // An independent solver agrees with F* to its tolerance.
    if (builtin_registry().contains("mprgp")) {
        RunOptions options;
        const RunOutcome run = run_solver(qp, "mprgp", {{"tol", 1e-9}}, options);
        nlohmann::json record = run.record;
        attach_reference(record, ref);
        const double f_star = ref["objective"].get<double>();
        EXPECT_NEAR(run.objective, f_star, 1e-6 * std::max(1.0, std::abs(f_star)));
        const auto& columns = record["history"]["columns"];
        EXPECT_EQ(columns.back(), "energy_gap");
        const auto& rows = record["history"]["rows"];
        ASSERT_FALSE(rows.empty());
        // |F - F*| / (d_ref l^2), from the record's own scales.
        const double energy =
            record["stiffness_scale"].get<double>() * std::pow(record["length_scale"].get<double>(), 2);
        EXPECT_DOUBLE_EQ(record["energy_gap"].get<double>(), std::abs(run.objective - f_star) / energy);
        EXPECT_LT(record["energy_gap"].get<double>(), 1e-9);
        EXPECT_DOUBLE_EQ(rows.back().back().get<double>(), record["energy_gap"].get<double>());
        // A reference of a reduced (decoupled) QP is not the original's F*: no energy gap.
        nlohmann::json reduced = run.record;
        reduced["snapshot"]["hash"] = "k1";
        nlohmann::json reduced_ref = ref;
        reduced_ref["key"] = "k1-authors-0";
        attach_reference(reduced, reduced_ref);
        EXPECT_FALSE(reduced.contains("energy_gap"));
        EXPECT_EQ(reduced["reference_note"],
                  "reference of a reduced QP (key k1-authors-0): no energy gap; F* must be the original QP's");
    }
}
