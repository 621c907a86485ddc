// End to end through the contactbench binary (env CB_CONTACTBENCH): solve's exit codes and
// messages, and a suite run that resumes, shards, merges and is deterministic.
#include "harness/results.hpp"
#include "problems/qpsnap.hpp"
#include "problems/synthetic.hpp"

#include "tests/harness/cli_test_util.hpp"
#include "tests/harness/remove_at_end.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sys/wait.h>
#include <unistd.h>

namespace fs = std::filesystem;
using namespace cb;
using cb::test::Output;
using cb::test::slurp;

namespace {

const fs::path& cli_work_dir()
{
    static const fs::path dir = test::make_test_work_dir("cli");
    return dir;
}

/// Runs `contactbench ARGS` (ARGS already shell-quoted where needed).
Output run_cli(const std::string& args) { return test::run_contactbench(args, cli_work_dir()); }

std::string small_snapshot()
{
    const fs::path p = cli_work_dir() / "plane.qpsnap";
    if (!fs::exists(p)) write_qpsnap(p.string(), make_synthetic("plane", {{"nx", 2}, {"ny", 2}, {"nz", 2}}, 4));
    return p.string();
}

std::string write_cli_suite(const std::string& name, const nlohmann::json& solvers)
{
    const nlohmann::json suite = {
        {"name", name},
        {"generate",
         {{{"id", "p1"}, {"family", "plane"}, {"seed", 1}, {"params", {{"nx", 2}, {"ny", 2}, {"nz", 2}}}},
          {{"id", "p2"}, {"family", "plane"}, {"seed", 2}, {"params", {{"nx", 3}, {"ny", 2}, {"nz", 2}}}}}},
        {"solvers", solvers},
        {"tol", 1e-6},
        {"time_limit_s", 20}};
    const fs::path p = cli_work_dir() / (name + ".json");
    write_json_atomic(p.string(), suite);
    return p.string();
}

size_t count_files(const fs::path& dir, const std::string& needle)
{
    size_t n = 0;
    if (!fs::exists(dir)) return 0;
    for (const auto& e : fs::recursive_directory_iterator(dir))
        if (e.path().filename().string().find(needle) != std::string::npos) ++n;
    return n;
}

const nlohmann::json SOLVERS = {{{"label", "mprgp"}, {"solver", "mprgp"}},
                                {{"label", "exact"}, {"solver", "active-set"}},
                                {{"label", "ghost"}, {"solver", "no-such-solver"}}};

/// Removes the scratch folder after the last test.
const auto* const CLI_CLEAN_UP = ::testing::AddGlobalTestEnvironment(new test::RemoveAtEnd(cli_work_dir));

}  // namespace

TEST(Cli, SolveMissingFileIsBadInput)
{
    const Output o = run_cli("solve /nonexistent/x.qpsnap --solver mprgp");
    EXPECT_EQ(o.status, 2);
    EXPECT_EQ(o.err.rfind("contactbench solve: error: /nonexistent/x.qpsnap: ", 0), 0u) << o.err;
}

TEST(Cli, SolveUnknownSolverIsBadInput)
{
    const Output o = run_cli("solve '" + small_snapshot() + "' --solver nope");
    EXPECT_EQ(o.status, 2);
    EXPECT_EQ(o.err.rfind("contactbench solve: error: solver 'nope' is not registered; known: ", 0), 0u) << o.err;
    EXPECT_NE(o.err.find("mprgp"), std::string::npos);
}

TEST(Cli, SolveBadSetKeyIsBadInput)
{
    const Output o = run_cli("solve '" + small_snapshot() + "' --solver mprgp --set bogus=1");
    EXPECT_EQ(o.status, 2);
    EXPECT_EQ(o.err.rfind("contactbench solve: error: mprgp: /bogus: ", 0), 0u) << o.err;
    const Output flag = run_cli("solve '" + small_snapshot() + "' --solver mprgp --frobnicate");
    EXPECT_EQ(flag.status, 2);
    EXPECT_EQ(flag.err.rfind("contactbench solve: error: solve: --frobnicate: unknown option", 0), 0u) << flag.err;
    const Output repeat = run_cli("solve '" + small_snapshot() + "' --solver mprgp --repeat 0");
    EXPECT_EQ(repeat.status, 2);
    EXPECT_EQ(repeat.err, "contactbench solve: error: solve: --repeat: must be in 1..1000, got 0\n");
}

TEST(Cli, SolveWritesJsonAndSolution)
{
    const fs::path json = cli_work_dir() / "solve.json", sol = cli_work_dir() / "sol";
    const Output o = run_cli("solve '" + small_snapshot() + "' --solver mprgp --set tol=1e-8 --json '" + json.string() +
                             "' --save-solution '" + sol.string() + "' --history");
    ASSERT_EQ(o.status, 0) << o.err;
    EXPECT_NE(o.out.find("status      converged (kkt)"), std::string::npos) << o.out;
    const nlohmann::json r = read_json_file(json.string());
    for (const char* key : {"solver", "settings", "status", "iterations", "objective", "accuracy", "counters", "time",
                            "provenance", "history", "snapshot"})
        EXPECT_TRUE(r.contains(key)) << key;
    EXPECT_DOUBLE_EQ(r["settings"]["tol"].get<double>(), 1e-8);
    EXPECT_LE(r["accuracy"]["max"].get<double>(), 1e-8);
    EXPECT_EQ(r["snapshot"]["hash"], qpsnap_content_hash(small_snapshot()));
    const std::string x = slurp(sol / "x.mtx");
    const long n = r["snapshot"]["n"].get<long>();
    EXPECT_EQ(x.rfind("%%MatrixMarket matrix array real general\n" + std::to_string(n) + " 1\n", 0), 0u);
    EXPECT_EQ(std::count(x.begin(), x.end(), '\n'), n + 2);
    EXPECT_TRUE(fs::exists(sol / "lambda.mtx"));
    EXPECT_EQ(count_files(cli_work_dir(), ".tmp"), 0u);
}

TEST(Cli, SolveHelpListsSolversAndSettings)
{
    const Output list = run_cli("solve --help");
    EXPECT_EQ(list.status, 0);
    EXPECT_NE(list.out.find("  mprgp "), std::string::npos) << list.out;
    const Output settings = run_cli("solve --solver mprgp --help");
    EXPECT_EQ(settings.status, 0);
    EXPECT_NE(settings.out.find("tol [1e-6]"), std::string::npos) << settings.out;
    EXPECT_NE(settings.out.find("max_iterations [10000]"), std::string::npos);
}

TEST(Cli, RunResumesShardsMergesAndIsDeterministic)
{
    const std::string suite = write_cli_suite("e2e", SOLVERS);
    const fs::path out = cli_work_dir() / "e2e";
    const Output first = run_cli("run '" + suite + "' --out '" + out.string() + "'");
    ASSERT_EQ(first.status, 0) << first.err;
    EXPECT_EQ(count_files(out / "runs", ".json"), 6u);
    EXPECT_NE(first.err.find("[1/6] p1 x mprgp: converged in "), std::string::npos) << first.err;
    EXPECT_NE(first.err.find("p1 x ghost: invalid_input: solver 'no-such-solver' is not registered"), std::string::npos)
        << first.err;
    for (const char* f : {"summary.csv", "suite.json", "provenance.json"}) EXPECT_TRUE(fs::exists(out / f)) << f;
    const std::string summary = slurp(out / "summary.csv");
    EXPECT_EQ(std::count(summary.begin(), summary.end(), '\n'), 7);
    EXPECT_EQ(summary.rfind("suite,snapshot,label,solver,status,", 0), 0u);
    EXPECT_NE(summary.find("\ne2e,p1,ghost,no-such-solver,invalid_input,"), std::string::npos) << summary;
    EXPECT_EQ(count_files(out, ".tmp"), 0u);
    const nlohmann::json mprgp = read_json_file((out / "runs" / "p1__mprgp.json").string());
    EXPECT_EQ(mprgp["status"], "converged");
    EXPECT_TRUE(mprgp["status_confirmed"].get<bool>());
    EXPECT_EQ(mprgp["snapshot"]["id"], "p1");
    EXPECT_FALSE(mprgp["history"]["rows"].empty());

    // Second run: everything is skipped, files untouched.
    const auto stamp = fs::last_write_time(out / "runs" / "p2__exact.json");
    const Output second = run_cli("run '" + suite + "' --out '" + out.string() + "'");
    ASSERT_EQ(second.status, 0) << second.err;
    EXPECT_NE(second.err.find("ran 0 of 6 jobs"), std::string::npos) << second.err;
    EXPECT_EQ(fs::last_write_time(out / "runs" / "p2__exact.json"), stamp);

    // Interrupted: one run and the summary missing -> only that run is redone.
    fs::remove(out / "summary.csv");
    fs::remove(out / "runs" / "p2__mprgp.json");
    const Output resumed = run_cli("run '" + suite + "' --out '" + out.string() + "'");
    ASSERT_EQ(resumed.status, 0) << resumed.err;
    EXPECT_NE(resumed.err.find("ran 1 of 6 jobs"), std::string::npos) << resumed.err;
    EXPECT_NE(resumed.err.find("p2 x mprgp: converged"), std::string::npos) << resumed.err;
    EXPECT_EQ(slurp(out / "summary.csv").size() > 0, true);
    EXPECT_EQ(count_files(out / "runs", ".json"), 6u);

    // Shards 1/2 and 2/2 split the jobs; merged they give the same counters as the full run.
    const fs::path s1 = cli_work_dir() / "shard1", s2 = cli_work_dir() / "shard2", merged = cli_work_dir() / "merged";
    ASSERT_EQ(run_cli("run '" + suite + "' --out '" + s1.string() + "' --shard 1/2").status, 0);
    ASSERT_EQ(run_cli("run '" + suite + "' --out '" + s2.string() + "' --shard 2/2").status, 0);
    EXPECT_EQ(count_files(s1 / "runs", ".json"), 3u);
    EXPECT_EQ(count_files(s2 / "runs", ".json"), 3u);
    EXPECT_TRUE(fs::exists(s1 / "runs" / "p1__mprgp.json"));  // job 0
    EXPECT_TRUE(fs::exists(s2 / "runs" / "p1__exact.json"));  // job 1
    const Output m = run_cli("merge '" + merged.string() + "' '" + s1.string() + "' '" + s2.string() + "'");
    ASSERT_EQ(m.status, 0) << m.err;
    EXPECT_EQ(count_files(merged / "runs", ".json"), 6u);
    const std::string msummary = slurp(merged / "summary.csv");
    EXPECT_EQ(std::count(msummary.begin(), msummary.end(), '\n'), 7);
    // Deterministic counters: the merged shards judge equal to the first run.
    const Output judge = run_cli("compare '" + out.string() + "' '" + merged.string() + "'");
    EXPECT_EQ(judge.status, 0) << judge.out;
    EXPECT_NE(judge.out.find("verdict: PASS (6 runs compared: 6 equal"), std::string::npos) << judge.out;

    // A deliberately worse variant under the same labels: MPRGP without its preconditioner.
    const std::string worse_suite =
        write_cli_suite("e2e", {{{"label", "mprgp"}, {"solver", "mprgp"}, {"settings", {{"precond", "none"}}}},
                                {{"label", "exact"}, {"solver", "active-set"}},
                                {{"label", "ghost"}, {"solver", "no-such-solver"}}});
    const fs::path worse = cli_work_dir() / "worse";
    ASSERT_EQ(run_cli("run '" + worse_suite + "' --out '" + worse.string() + "'").status, 0);
    const Output regression = run_cli("compare '" + out.string() + "' '" + worse.string() + "'");
    EXPECT_EQ(regression.status, 3) << regression.out;  // 3: a regression (1 is an internal error)
    EXPECT_NE(regression.out.find("FAIL regressed: iterations a_products"), std::string::npos) << regression.out;
    EXPECT_NE(regression.out.find("verdict: FAIL"), std::string::npos);

    const Output bad_shard = run_cli("run '" + suite + "' --out '" + s1.string() + "' --shard 3/2");
    EXPECT_EQ(bad_shard.status, 2);
    EXPECT_EQ(bad_shard.err, "contactbench run: error: run: --shard: expected i/N with 1 <= i <= N, got '3/2'\n");
}

TEST(Cli, RunRejectsBadSuite)
{
    const Output missing = run_cli("run /nonexistent/suite.json");
    EXPECT_EQ(missing.status, 2);
    EXPECT_EQ(missing.err,
              "contactbench run: error: /nonexistent/suite.json: cannot open: No such file or directory\n");
    const fs::path p = cli_work_dir() / "bad.json";
    write_json_atomic(p.string(),
                      {{"name", "bad"}, {"generate", nlohmann::json::array()}, {"solvers", {"cg"}}, {"tol", "x"}});
    const Output bad = run_cli("run '" + p.string() + "'");
    EXPECT_EQ(bad.status, 2);
    EXPECT_EQ(bad.err, "contactbench run: error: " + p.string() +
                           ": /snapshots: the suite names no snapshots and generates none\n");
}

TEST(Cli, ChainCarriesWarmStateAndReferenceAddsEnergyGap)
{
    nlohmann::json suite = {
        {"name", "chain"},
        {"generate",
         {{{"id", "f1"}, {"family", "plane"}, {"seed", 1}, {"params", {{"nx", 2}, {"ny", 2}, {"nz", 2}}}},
          {{"id", "f2"},
           {"family", "plane"},
           {"seed", 1},
           {"params", {{"nx", 2}, {"ny", 2}, {"nz", 2}, {"h", 0.011}}}}}},
        {"solvers", {{{"label", "mprgp"}, {"solver", "mprgp"}}}},
        {"chain", true},
        {"reference", true}};
    const fs::path p = cli_work_dir() / "chain.json", out = cli_work_dir() / "chain";
    write_json_atomic(p.string(), suite);
    const Output o = run_cli("run '" + p.string() + "' --out '" + out.string() + "'");
    ASSERT_EQ(o.status, 0) << o.err;
    const nlohmann::json r1 = read_json_file((out / "runs" / "f1__mprgp.json").string());
    const nlohmann::json r2 = read_json_file((out / "runs" / "f2__mprgp.json").string());
    EXPECT_EQ(r1["mode"], "chain");
    EXPECT_FALSE(r1["warm"]["lambda0"].get<bool>());  // nothing to carry into the first step
    EXPECT_TRUE(r1["warm"]["eigenvector"].get<bool>());
    // Same mesh, same contacts: the multipliers of step 1 warm-start step 2.
    ASSERT_EQ(r1["snapshot"]["m"], r2["snapshot"]["m"]);
    EXPECT_TRUE(r2["warm"]["lambda0"].get<bool>());
    EXPECT_TRUE(r2["info"]["power"]["warm_start"].get<bool>()) << r2["info"].dump();
    // Reference: F* from active-set (the plane family is decoupled: the original QP), and the
    // energy gap |F - F*| / (d_ref l^2) small at the converged point.
    ASSERT_TRUE(r1["reference"]["objective"].is_number()) << r1["reference"].dump();
    EXPECT_EQ(r1["reference"]["source"], "active-set");
    EXPECT_EQ(r1["history"]["columns"].back(), "energy_gap");
    EXPECT_LT(r1["energy_gap"].get<double>(), 1e-6);
    // Cached by content hash and reference method (not by the binary: a rebuild keeps it).
    EXPECT_EQ(count_files(cli_work_dir() / "cache" / "reference", r1["snapshot"]["hash"].get<std::string>() + "-"), 1u);
    EXPECT_EQ(r1["reference"]["method"]["solver"], "active-set");
}

TEST(Cli, CorruptSnapshotFailsItsRunsOnly)
{
    const fs::path dir = cli_work_dir() / "corrupt";
    fs::create_directories(dir);
    fs::copy_file(small_snapshot(), dir / "good.qpsnap", fs::copy_options::overwrite_existing);
    std::ofstream(dir / "bad.qpsnap") << "not a snapshot";
    write_json_atomic((dir / "suite.json").string(),
                      {{"name", "corrupt"}, {"snapshots", {"*.qpsnap"}}, {"solvers", {"mprgp"}}, {"time_limit_s", 5}});
    const Output o = run_cli("run '" + (dir / "suite.json").string() + "' --out '" + (dir / "out").string() + "'");
    ASSERT_EQ(o.status, 0) << o.err;
    const nlohmann::json bad = read_json_file((dir / "out" / "runs" / "bad__mprgp.json").string());
    EXPECT_EQ(bad["status"], "invalid_input");
    EXPECT_EQ(bad["message"].get<std::string>().rfind((dir / "bad.qpsnap").string() + ": ", 0), 0u) << bad["message"];
    const nlohmann::json good = read_json_file((dir / "out" / "runs" / "good__mprgp.json").string());
    EXPECT_EQ(good["status"], "converged");
    EXPECT_DOUBLE_EQ(good["settings"]["time_limit_s"].get<double>(), 5.0);  // the suite's default reached the solver
}

// An optional solver this build lacks is skipped with a notice (no run file, no failed run), and
// a solver limited to some snapshots has jobs on those only: the job count and jobs.json say so.
TEST(Cli, RunSkipsUnbuiltOptionalSolversAndAppliesProblemFilters)
{
    const std::string suite =
        write_cli_suite("filters", {{{"label", "mprgp"}, {"solver", "mprgp"}, {"problems", {"p1"}}},
                                    {{"label", "exact"}, {"solver", "active-set"}, {"skip_problems", {"p1"}}},
                                    {{"label", "absent"}, {"solver", "no-such-peer"}, {"optional", true}}});
    const fs::path out = cli_work_dir() / "filters";
    const Output o = run_cli("run '" + suite + "' --out '" + out.string() + "'");
    ASSERT_EQ(o.status, 0) << o.err;
    EXPECT_NE(o.err.find("run: optional solver 'absent' (no-such-peer) is not built into this contactbench; its runs "
                         "are skipped\n"),
              std::string::npos)
        << o.err;
    EXPECT_NE(o.err.find("ran 2 of 2 jobs"), std::string::npos) << o.err;
    EXPECT_TRUE(fs::exists(out / "runs" / "p1__mprgp.json"));
    EXPECT_TRUE(fs::exists(out / "runs" / "p2__exact.json"));
    EXPECT_EQ(count_files(out / "runs", ".json"), 2u);
    const nlohmann::json jobs = read_json_file((out / "jobs.json").string());
    EXPECT_EQ(jobs["all_jobs"], 2);
    EXPECT_TRUE(jobs["complete"].get<bool>());
}
