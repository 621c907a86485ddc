// Issue 15 through the contactbench binary (env CB_CONTACTBENCH): run identity and resume rules,
// one suite per --out, the lock, merge's checks, atomic and checked writes under a file-size
// limit, and hostile inputs (tests/hostile/, FIFOs, folders, symlink loops, deep JSON, huge
// declared sizes under a memory limit) that must end in exit 2 with the file and field named.
#include "harness/results.hpp"
#include "problems/qpsnap.hpp"
#include "problems/synthetic.hpp"
#include "sim/simulator.hpp"
#include "tests/harness/shell_quoted.hpp"

#include "tests/harness/cli_test_util.hpp"
#include "tests/harness/remove_at_end.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <cstdlib>
#include <fcntl.h>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sys/file.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <sys/wait.h>
#include <unistd.h>

namespace fs = std::filesystem;
using namespace cb;
using cb::test::Output;
using cb::test::slurp;

namespace {

const fs::path& hostile_work_dir()
{
    static const fs::path dir = test::make_test_work_dir("hostile");
    return dir;
}

const fs::path HOSTILE = fs::path(CB_TEST_DATA_DIR).parent_path() / "hostile";

/// Runs `[PREFIX;] timeout 120 contactbench ARGS` in bash (PREFIX: ulimit ...); a hang ends as 124.
Output run_hostile(const std::string& args, const std::string& prefix = "",
                   const std::string& program = test::contactbench_binary())
{
    test::CliCall call;
    call.prefix = prefix;
    call.program = program;
    return test::run_contactbench(args, hostile_work_dir(), call);
}

size_t count_matching(const fs::path& dir, const std::string& needle)
{
    size_t n = 0;
    if (!fs::exists(dir)) return 0;
    for (const auto& e : fs::recursive_directory_iterator(dir))
        if (e.path().filename().string().find(needle) != std::string::npos) ++n;
    return n;
}

void write_snapshot(const fs::path& p, int seed, int nx = 2)
{
    write_qpsnap(p.string(), make_synthetic("plane", {{"nx", nx}, {"ny", 2}, {"nz", 2}}, std::uint64_t(seed)));
}

/// A suite over the snapshots a.qpsnap and b.qpsnap of `dir`.
fs::path write_hostile_suite(const fs::path& dir, const std::string& name, const nlohmann::json& solvers,
                             double tol = 1e-6)
{
    const nlohmann::json suite = {{"name", name},
                                  {"snapshots", {"a.qpsnap", "b.qpsnap"}},
                                  {"solvers", solvers},
                                  {"tol", tol},
                                  {"time_limit_s", 20}};
    fs::path p = dir / (name + ".json");
    write_json_atomic(p.string(), suite);
    return p;
}

const nlohmann::json TWO_SOLVERS = {{{"label", "mprgp"}, {"solver", "mprgp"}},
                                    {{"label", "exact"}, {"solver", "active-set"}}};

fs::path fresh_hostile_dir(const std::string& name)
{
    fs::path d = hostile_work_dir() / name;
    fs::remove_all(d);
    fs::create_directories(d);
    return d;
}

const auto* const HOSTILE_CLEAN_UP = ::testing::AddGlobalTestEnvironment(new test::RemoveAtEnd(hostile_work_dir));

}  // namespace

// ---- run identity -----------------------------------------------------------------------------

TEST(RunIdentity, EditedSuiteReplacedSnapshotAndFixedInputAreRedone)
{
    const fs::path dir = fresh_hostile_dir("identity");
    write_snapshot(dir / "a.qpsnap", 1);
    write_snapshot(dir / "b.qpsnap", 2);
    const fs::path out = dir / "out";
    const fs::path suite = write_hostile_suite(dir, "ident", TWO_SOLVERS);
    ASSERT_EQ(run_hostile("run " + test::shell_quoted(suite) + " --out " + test::shell_quoted(out)).status, 0);
    const nlohmann::json first = read_json_file((out / "runs" / "a__mprgp.json").string());
    ASSERT_TRUE(first["identity"].is_object()) << first.dump();
    EXPECT_EQ(first["identity"]["snapshot_hash"], qpsnap_content_hash((dir / "a.qpsnap").string()));
    EXPECT_EQ(first["identity"]["solver"], "mprgp");
    EXPECT_EQ(first["identity"]["settings"]["tol"], 1e-6);
    EXPECT_TRUE(first["identity"]["build"]["binary"].is_string());
    EXPECT_TRUE(first["final"].get<bool>());

    // Unchanged: nothing reruns.
    const Output same = run_hostile("run " + test::shell_quoted(suite) + " --out " + test::shell_quoted(out));
    ASSERT_EQ(same.status, 0) << same.err;
    EXPECT_NE(same.err.find("ran 0 of 4 jobs"), std::string::npos) << same.err;

    // The suite's tol edited: every run is redone and suite.json describes the new suite.
    write_hostile_suite(dir, "ident", TWO_SOLVERS, 1e-8);
    const Output edited = run_hostile("run " + test::shell_quoted(suite) + " --out " + test::shell_quoted(out));
    ASSERT_EQ(edited.status, 0) << edited.err;
    EXPECT_NE(edited.err.find("ran 4 of 4 jobs"), std::string::npos) << edited.err;
    EXPECT_NE(edited.err.find("a x mprgp: stored run not reused: the settings changed\n"), std::string::npos)
        << edited.err;
    EXPECT_EQ(read_json_file((out / "suite.json").string())["tol"], 1e-8);
    EXPECT_EQ(read_json_file((out / "runs" / "b__exact.json").string())["tol"], 1e-8);
    EXPECT_FALSE(fs::exists(out / "suite.pending.json"));

    // One solver's settings edited: only its runs are redone.
    write_json_atomic(suite.string(), {{"name", "ident"},
                                       {"snapshots", {"a.qpsnap", "b.qpsnap"}},
                                       {"solvers",
                                        {{{"label", "mprgp"}, {"solver", "mprgp"}, {"settings", {{"precond", "none"}}}},
                                         {{"label", "exact"}, {"solver", "active-set"}}}},
                                       {"tol", 1e-8},
                                       {"time_limit_s", 20}});
    const Output one = run_hostile("run " + test::shell_quoted(suite) + " --out " + test::shell_quoted(out));
    ASSERT_EQ(one.status, 0) << one.err;
    EXPECT_NE(one.err.find("ran 2 of 4 jobs"), std::string::npos) << one.err;
    EXPECT_NE(one.err.find("b x exact: done before, skipped"), std::string::npos) << one.err;

    // A snapshot replaced at the same path: its runs are redone.
    write_snapshot(dir / "b.qpsnap", 7);
    const Output replaced = run_hostile("run " + test::shell_quoted(suite) + " --out " + test::shell_quoted(out));
    ASSERT_EQ(replaced.status, 0) << replaced.err;
    EXPECT_NE(replaced.err.find("ran 2 of 4 jobs"), std::string::npos) << replaced.err;
    EXPECT_NE(replaced.err.find("b x exact: stored run not reused: the snapshot's content changed\n"),
              std::string::npos)
        << replaced.err;

    // A run that failed because its snapshot was corrupt is retried once the file is fixed.
    const std::string good = slurp(dir / "a.qpsnap");
    std::ofstream(dir / "a.qpsnap", std::ios::trunc) << "not a snapshot";
    ASSERT_EQ(run_hostile("run " + test::shell_quoted(suite) + " --out " + test::shell_quoted(out)).status, 0);
    const nlohmann::json failed = read_json_file((out / "runs" / "a__mprgp.json").string());
    EXPECT_EQ(failed["status"], "invalid_input");
    EXPECT_FALSE(failed["final"].get<bool>());
    std::ofstream(dir / "a.qpsnap", std::ios::binary | std::ios::trunc) << good;
    const Output fixed = run_hostile("run " + test::shell_quoted(suite) + " --out " + test::shell_quoted(out));
    ASSERT_EQ(fixed.status, 0) << fixed.err;
    EXPECT_NE(fixed.err.find("ran 2 of 4 jobs"), std::string::npos) << fixed.err;
    EXPECT_EQ(read_json_file((out / "runs" / "a__mprgp.json").string())["status"], "converged");

    // A run file of an older contactbench (no identity) is redone, not trusted.
    nlohmann::json old = read_json_file((out / "runs" / "b__mprgp.json").string());
    old.erase("identity");
    write_json_atomic((out / "runs" / "b__mprgp.json").string(), old);
    const Output legacy = run_hostile("run " + test::shell_quoted(suite) + " --out " + test::shell_quoted(out));
    EXPECT_NE(legacy.err.find(
                  "b x mprgp: stored run not reused: it has no run identity (written by an older contactbench)\n"),
              std::string::npos)
        << legacy.err;
    EXPECT_NE(legacy.err.find("ran 1 of 4 jobs"), std::string::npos) << legacy.err;
}

TEST(RunIdentity, SolverOutcomesAreFinal)
{
    const fs::path dir = fresh_hostile_dir("final");
    write_snapshot(dir / "a.qpsnap", 1);
    write_snapshot(dir / "b.qpsnap", 2);
    // max_iterations 1: the solver's outcome, kept on resume.
    const fs::path suite = write_hostile_suite(
        dir, "final", {{{"label", "capped"}, {"solver", "mprgp"}, {"settings", {{"max_iterations", 1}}}}});
    const fs::path out = dir / "out";
    ASSERT_EQ(run_hostile("run " + test::shell_quoted(suite) + " --out " + test::shell_quoted(out)).status, 0);
    const nlohmann::json capped = read_json_file((out / "runs" / "a__capped.json").string());
    EXPECT_EQ(capped["status"], "max_iterations");
    EXPECT_TRUE(capped["final"].get<bool>());
    const Output again = run_hostile("run " + test::shell_quoted(suite) + " --out " + test::shell_quoted(out));
    EXPECT_NE(again.err.find("ran 0 of 2 jobs"), std::string::npos) << again.err;
}

TEST(RunIdentity, AnotherBuildRedoesTheRuns)
{
    const fs::path dir = fresh_hostile_dir("rebuild");
    write_snapshot(dir / "a.qpsnap", 1);
    write_snapshot(dir / "b.qpsnap", 2);
    const fs::path suite = write_hostile_suite(dir, "rebuild", {"mprgp"}), out = dir / "out";
    ASSERT_EQ(run_hostile("run " + test::shell_quoted(suite) + " --out " + test::shell_quoted(out)).status, 0);
    // "Rebuilt": the same program with one byte more (an ELF file runs with trailing bytes).
    const fs::path rebuilt = dir / "contactbench-rebuilt";
    fs::copy_file(test::contactbench_binary(), rebuilt);
    std::ofstream(rebuilt, std::ios::app) << '\n';
    fs::permissions(rebuilt, fs::perms::owner_exec, fs::perm_options::add);
    const Output again =
        run_hostile("run " + test::shell_quoted(suite) + " --out " + test::shell_quoted(out), "", rebuilt.string());
    ASSERT_EQ(again.status, 0) << again.err;
    EXPECT_NE(again.err.find("a x mprgp: stored run not reused: the build changed (commit or binary)\n"),
              std::string::npos)
        << again.err;
    EXPECT_NE(again.err.find("ran 2 of 2 jobs"), std::string::npos) << again.err;
}

TEST(RunIdentity, OneSuitePerOutAndFresh)
{
    const fs::path dir = fresh_hostile_dir("onesuite");
    write_snapshot(dir / "a.qpsnap", 1);
    write_snapshot(dir / "b.qpsnap", 2);
    const fs::path out = dir / "out";
    const fs::path first = write_hostile_suite(dir, "first", {"mprgp"});
    const fs::path second = write_hostile_suite(dir, "second", {"mprgp"});
    ASSERT_EQ(run_hostile("run " + test::shell_quoted(first) + " --out " + test::shell_quoted(out)).status, 0);
    const Output other = run_hostile("run " + test::shell_quoted(second) + " --out " + test::shell_quoted(out));
    EXPECT_EQ(other.status, 2);
    EXPECT_EQ(other.err,
              "contactbench run: error: " + out.string() +
                  ": suite.json: holds results of suite 'first', not 'second'; use another --out, or --fresh "
                  "to discard the results in " +
                  out.string() + "\n");
    // A label removed from the suite: its run files would be mixed into summary.csv.
    write_hostile_suite(dir, "first", {"cg"});
    const Output shrunk = run_hostile("run " + test::shell_quoted(first) + " --out " + test::shell_quoted(out));
    EXPECT_EQ(shrunk.status, 2);
    EXPECT_EQ(shrunk.err,
              "contactbench run: error: " + (out / "runs" / "a__mprgp.json").string() +
                  ": not a job of suite 'first' (2 such run files: an earlier suite or shard?); use another "
                  "--out, or --fresh "
                  "to discard the results in " +
                  out.string() + "\n");
    // Another shard into the same --out is refused the same way.
    write_hostile_suite(dir, "first", {"mprgp"});
    const Output shard =
        run_hostile("run " + test::shell_quoted(first) + " --out " + test::shell_quoted(out) + " --shard 2/2");
    EXPECT_EQ(shard.status, 2);
    EXPECT_NE(
        shard.err.find((out / "runs" / "a__mprgp.json").string() + ": not a job of suite 'first' shard 2/2 (1 such"),
        std::string::npos)
        << shard.err;
    // --fresh starts over.
    const Output fresh =
        run_hostile("run " + test::shell_quoted(second) + " --out " + test::shell_quoted(out) + " --fresh");
    ASSERT_EQ(fresh.status, 0) << fresh.err;
    EXPECT_NE(fresh.err.find("ran 2 of 2 jobs"), std::string::npos) << fresh.err;
    EXPECT_EQ(read_json_file((out / "suite.json").string())["name"], "second");
    const std::string summary = slurp(out / "summary.csv");
    EXPECT_EQ(summary.find("first,"), std::string::npos) << summary;
}

TEST(RunIdentity, LockKeepsTwoRunsApart)
{
    const fs::path dir = fresh_hostile_dir("lock");
    write_snapshot(dir / "a.qpsnap", 1);
    write_snapshot(dir / "b.qpsnap", 2);
    const fs::path out = dir / "out";
    fs::create_directories(out);
    // Another run holds the lock (this process plays it).
    const int fd = ::open((out / ".lock").c_str(), O_RDWR | O_CREAT, 0644);
    ASSERT_GE(fd, 0);
    ASSERT_EQ(::flock(fd, LOCK_EX | LOCK_NB), 0);
    const std::string pid = std::to_string(::getpid()) + "\n";
    ASSERT_EQ(::write(fd, pid.data(), pid.size()), ssize_t(pid.size()));
    const fs::path suite = write_hostile_suite(dir, "locked", {"mprgp"});
    const Output locked = run_hostile("run " + test::shell_quoted(suite) + " --out " + test::shell_quoted(out));
    EXPECT_EQ(locked.status, 2);
    EXPECT_EQ(locked.err, "contactbench run: error: " + out.string() + ": another `contactbench run` (pid " +
                              std::to_string(::getpid()) +
                              ") is writing to this folder; wait for it to finish or use another --out\n");
    EXPECT_EQ(count_matching(out / "runs", ".json"), 0u);
    ::close(fd);  // released: the run goes ahead
    EXPECT_EQ(run_hostile("run " + test::shell_quoted(suite) + " --out " + test::shell_quoted(out)).status, 0);
}

TEST(Merge, RefusesIncompleteOrMixedShards)
{
    const fs::path dir = fresh_hostile_dir("merge");
    write_snapshot(dir / "a.qpsnap", 1);
    write_snapshot(dir / "b.qpsnap", 2);
    const fs::path suite = write_hostile_suite(dir, "sharded", TWO_SOLVERS);
    const fs::path s1 = dir / "s1", s2 = dir / "s2", other = dir / "other";
    ASSERT_EQ(
        run_hostile("run " + test::shell_quoted(suite) + " --out " + test::shell_quoted(s1) + " --shard 1/2").status,
        0);
    const Output lonely = run_hostile("merge " + test::shell_quoted(dir / "m1") + " " + test::shell_quoted(s1));
    EXPECT_EQ(lonely.status, 2);
    EXPECT_EQ(lonely.err, "contactbench merge: error: merge: shards: missing shard(s) 2/2 of suite \"sharded\"\n");
    EXPECT_FALSE(fs::exists(dir / "m1"));
    // A shard of an edited suite is not of the same suite.
    const fs::path edited = write_hostile_suite(dir, "sharded", TWO_SOLVERS, 1e-8);
    ASSERT_EQ(run_hostile("run " + test::shell_quoted(edited) + " --out " + test::shell_quoted(other) + " --shard 2/2")
                  .status,
              0);
    const Output mixed = run_hostile("merge " + test::shell_quoted(dir / "m2") + " " + test::shell_quoted(s1) + " " +
                                     test::shell_quoted(other));
    EXPECT_EQ(mixed.status, 2);
    EXPECT_NE(mixed.err.find((other / "jobs.json").string() + ": suite: shard of suite \"sharded\""), std::string::npos)
        << mixed.err;
    EXPECT_NE(mixed.err.find("not one suite"), std::string::npos) << mixed.err;
    // The right shard 2/2, but one of its runs lost.
    write_hostile_suite(dir, "sharded", TWO_SOLVERS);
    ASSERT_EQ(
        run_hostile("run " + test::shell_quoted(suite) + " --out " + test::shell_quoted(s2) + " --shard 2/2").status,
        0);
    fs::remove(s2 / "runs" / "a__exact.json");
    const Output holes = run_hostile("merge " + test::shell_quoted(dir / "m3") + " " + test::shell_quoted(s1) + " " +
                                     test::shell_quoted(s2));
    EXPECT_EQ(holes.status, 2);
    EXPECT_EQ(holes.err, "contactbench merge: error: " + (s2 / "runs" / "a__exact.json").string() +
                             ": missing: shard 2 is incomplete (run it again)\n");
    ASSERT_EQ(
        run_hostile("run " + test::shell_quoted(suite) + " --out " + test::shell_quoted(s2) + " --shard 2/2").status,
        0);
    const Output ok = run_hostile("merge " + test::shell_quoted(dir / "m4") + " " + test::shell_quoted(s1) + " " +
                                  test::shell_quoted(s2));
    ASSERT_EQ(ok.status, 0) << ok.err;
    EXPECT_EQ(count_matching(dir / "m4" / "runs", ".json"), 4u);
}

// Issue 27: a refused merge still wrote run files into OUT; run files edited to another suite or
// an unknown status ("banana" reached summary.csv) were merged; a shard claiming 3-of-2 was
// reported only as a missing shard 2/2.
TEST(Merge, EveryShardIsCheckedWholeBeforeAnythingIsWritten)
{
    const fs::path dir = fresh_hostile_dir("merge_hostile");
    write_snapshot(dir / "a.qpsnap", 1);
    write_snapshot(dir / "b.qpsnap", 2);
    const fs::path suite = write_hostile_suite(dir, "sharded", TWO_SOLVERS);
    const fs::path s1 = dir / "s1", s2 = dir / "s2", good = dir / "good";
    ASSERT_EQ(
        run_hostile("run " + test::shell_quoted(suite) + " --out " + test::shell_quoted(s1) + " --shard 1/2").status,
        0);
    ASSERT_EQ(
        run_hostile("run " + test::shell_quoted(suite) + " --out " + test::shell_quoted(s2) + " --shard 2/2").status,
        0);
    ASSERT_EQ(
        run_hostile("merge " + test::shell_quoted(good) + " " + test::shell_quoted(s1) + " " + test::shell_quoted(s2))
            .status,
        0);
    const std::string good_summary = slurp(good / "summary.csv");
    const fs::path victim = s2 / "runs" / "a__exact.json";
    const std::string original = slurp(victim);
    auto edited = [&](const fs::path& file, const std::function<void(nlohmann::json&)>& edit) {
        nlohmann::json j = nlohmann::json::parse(slurp(file));
        edit(j);
        write_json_atomic(file.string(), j);
    };
    // Each refused merge goes to a fresh OUT (never created) and to the good OUT (left as it was).
    auto refused = [&](const std::string& expected_error, const std::vector<fs::path>& shards, bool prefix = false) {
        for (const fs::path& out : {dir / "fresh", good}) {
            std::string args = "merge " + test::shell_quoted(out);
            for (const auto& sh : shards) args += " " + test::shell_quoted(sh);
            const Output r = run_hostile(args);
            EXPECT_EQ(r.status, 2) << r.err;
            const std::string expected = "contactbench merge: error: " + expected_error + (prefix ? "" : "\n");
            EXPECT_EQ(prefix ? r.err.substr(0, expected.size()) : r.err, expected);
            EXPECT_FALSE(fs::exists(dir / "fresh"));
            EXPECT_EQ(slurp(good / "summary.csv"), good_summary);
            EXPECT_EQ(slurp(good / "runs" / "a__exact.json"), original);
            EXPECT_EQ(count_matching(dir, ".tmp."), 0u);
        }
    };
    edited(victim, [](nlohmann::json& j) { j["suite"] = "another"; });
    refused(victim.string() + ": suite: expected \"sharded\" (the shard's suite), got \"another\"", {s1, s2});
    edited(victim, [](nlohmann::json& j) {
        j["suite"] = "sharded";
        j["status"] = "banana";
    });
    refused(victim.string() + ": status: not a known run status: \"banana\"", {s1, s2});
    // The harness's own statuses are run statuses too (a decoupled relaxation, an unconfirmed claim):
    // the real-Slurm test's merge refused a shard holding mprgp's solved_relaxation.
    for (const char* status : {"solved_relaxation", "unconfirmed", "internal_error"}) {
        edited(victim, [&](nlohmann::json& j) { j["status"] = status; });
        const fs::path out = dir / (std::string("merged_") + status);
        const Output r = run_hostile("merge " + test::shell_quoted(out) + " " + test::shell_quoted(s1) + " " +
                                     test::shell_quoted(s2));
        EXPECT_EQ(r.status, 0) << status << ": " << r.err;
        EXPECT_NE(slurp(out / "summary.csv").find(std::string(",") + status + ","), std::string::npos) << status;
    }
    std::ofstream(victim, std::ios::trunc) << original.substr(0, original.size() / 2);  // a torn run file
    refused(victim.string() + ": not valid JSON: ", {s1, s2}, true);
    std::ofstream(victim, std::ios::trunc) << original;
    const std::string jobs = slurp(s2 / "jobs.json");
    edited(s2 / "jobs.json", [](nlohmann::json& j) { j["shard"]["index"] = 3; });
    refused((s2 / "jobs.json").string() + ": shard: shard 3 of 2: expected 1 <= i <= N <= 100000", {s1, s2});
    edited(s2 / "jobs.json", [](nlohmann::json& j) {
        j["shard"]["index"] = 2;
        j["jobs"].push_back(j["jobs"][0]);
    });
    refused((s2 / "jobs.json").string() + ": jobs: " + nlohmann::json::parse(jobs)["jobs"][0].get<std::string>() +
                " listed twice",
            {s1, s2});
    std::ofstream(s2 / "jobs.json", std::ios::trunc) << jobs;
    refused((s1 / "jobs.json").string() + ": shard: shard 1 of 2 given twice (also " + s1.string() + ")", {s1, s1, s2});
    edited(s2 / "suite.json", [](nlohmann::json& j) { j["tol"] = 1e-3; });
    refused((s2 / "suite.json").string() + ": does not match the suite hash " +
                nlohmann::json::parse(jobs)["suite_hash"].get<std::string>() + " of " + (s2 / "jobs.json").string() +
                " (edited?)",
            {s1, s2});
    write_json_atomic((s2 / "suite.json").string(), nlohmann::json::parse(slurp(s1 / "suite.json")));
    const Output again =
        run_hostile("merge " + test::shell_quoted(good) + " " + test::shell_quoted(s1) + " " + test::shell_quoted(s2));
    EXPECT_EQ(again.status, 0) << again.err;
}

// ---- writes -----------------------------------------------------------------------------------

namespace {

/// A scene small enough to simulate in well under a second.
fs::path tiny_scene(const fs::path& dir, long frames)
{
    fs::path p = dir / "tiny.json";
    write_json_atomic(p.string(), {{"name", "tiny"},
                                   {"h", 0.01},
                                   {"frames", frames},
                                   {"bodies",
                                    {{{"name", "cube"},
                                      {"box", {{"cells", {1, 1, 1}}, {"size", {0.2, 0.2, 0.2}}}},
                                      {"translate", {0, 0.11, 0}},
                                      {"velocity", {0, -1, 0}}}}},
                                   {"obstacles", {{{"type", "plane"}, {"normal", {0, 1, 0}}, {"point", {0, 0, 0}}}}},
                                   {"output", {{"strip_frames", 0}}}});
    return p;
}

}  // namespace

TEST(Writes, SimulateReplacesAnOldOutOnlyWithFreshAndFinishesItsTables)
{
    const fs::path dir = fresh_hostile_dir("simulate");
    const fs::path scene = tiny_scene(dir, 4), out = dir / "out";
    ASSERT_EQ(run_hostile("simulate " + test::shell_quoted(scene) + " --out " + test::shell_quoted(out)).status, 0);
    EXPECT_EQ(count_matching(out / "snapshots", ".qpsnap"), 4u);
    // Fewer frames than the folder holds: refused, nothing deleted (issue 43).
    const Output refused =
        run_hostile("simulate " + test::shell_quoted(scene) + " --out " + test::shell_quoted(out) + " --frames 2");
    EXPECT_EQ(refused.status, 2);
    EXPECT_EQ(refused.err.substr(refused.err.find("contactbench simulate: error:")),
              "contactbench simulate: error: " + out.string() +
                  ": --out: holds 4 frames of this simulation, more than the 2 asked; --fresh discards it, or use "
                  "another --out\n");
    EXPECT_EQ(count_matching(out / "snapshots", ".qpsnap"), 4u);
    // With --fresh: the old snapshots do not survive next to the new ones.
    const Output again = run_hostile("simulate " + test::shell_quoted(scene) + " --out " + test::shell_quoted(out) +
                                     " --frames 2 --fresh");
    ASSERT_EQ(again.status, 0) << again.err;
    EXPECT_EQ(count_matching(out / "snapshots", ".qpsnap"), 2u);
    const std::string steps = slurp(out / "steps.csv"), frames = slurp(out / "frames.csv");
    EXPECT_EQ(std::count(steps.begin(), steps.end(), '\n'), 3);  // header + 2 frames x 1 Newton step
    EXPECT_EQ(std::count(frames.begin(), frames.end(), '\n'), 3);
    EXPECT_EQ(count_matching(out, ".partial"), 0u);
    const nlohmann::json record = read_json_file((out / "simulation.json").string());
    EXPECT_EQ(record["frames_done"], 2);
    EXPECT_EQ(record["simulator_version"], sim::SIMULATOR_VERSION);
    const Output version = run_hostile("simulate --version");
    EXPECT_EQ(version.out, "simulator " + std::to_string(sim::SIMULATOR_VERSION) + "\n");
}

TEST(Writes, FileSizeLimitIsAClearErrorWithNoPartialOutput)
{
    const fs::path dir = fresh_hostile_dir("fsize");
    // simulate: the first snapshot passes 4 kB (ulimit -f counts 1024-byte blocks).
    const fs::path scene = tiny_scene(dir, 3), out = dir / "sim";
    const Output sim =
        run_hostile("simulate " + test::shell_quoted(scene) + " --out " + test::shell_quoted(out), "ulimit -f 4");
    EXPECT_EQ(sim.status, 2) << sim.err;
    EXPECT_NE(sim.err.find("contactbench simulate: error: " + (out / "snapshots" / "tiny_f0000_n0.qpsnap").string() +
                           ": write failed: File too large (nothing written)\n"),
              std::string::npos)
        << sim.err;
    EXPECT_EQ(count_matching(out, ".tmp"), 0u);
    EXPECT_EQ(count_matching(out, ".csv"), 0u);  // neither tables nor .partial tables are left
    EXPECT_FALSE(fs::exists(out / "simulation.json"));

    // convert to a folder: nothing of OUT, no OUT.tmp.* or OUT.old.* left.
    const fs::path snap = dir / "big.qpsnap", folder = dir / "folder";
    write_snapshot(snap, 3, 4);
    const Output conv =
        run_hostile("convert " + test::shell_quoted(snap) + " " + test::shell_quoted(folder), "ulimit -f 8");
    EXPECT_EQ(conv.status, 2) << conv.err;
    EXPECT_NE(conv.err.find(": write failed: File too large (nothing written)"), std::string::npos) << conv.err;
    EXPECT_FALSE(fs::exists(folder));
    for (const auto& e : fs::directory_iterator(dir))
        EXPECT_EQ(e.path().filename().string().find("folder."), std::string::npos) << e.path();
    // An existing folder is replaced whole or kept whole.
    ASSERT_EQ(run_hostile("convert " + test::shell_quoted(snap) + " " + test::shell_quoted(folder)).status, 0);
    const std::string meta = slurp(folder / "meta.json"), a = slurp(folder / "A.mtx");
    const Output keep =
        run_hostile("convert " + test::shell_quoted(snap) + " " + test::shell_quoted(folder), "ulimit -f 8");
    EXPECT_EQ(keep.status, 2);
    EXPECT_EQ(slurp(folder / "meta.json"), meta);
    EXPECT_EQ(slurp(folder / "A.mtx"), a);

    // run: a results file that cannot be written ends the run with exit 2, no partial file.
    write_snapshot(dir / "a.qpsnap", 1);
    write_snapshot(dir / "b.qpsnap", 2);
    const fs::path suite = write_hostile_suite(dir, "fsize", {"mprgp"});
    const Output r =
        run_hostile("run " + test::shell_quoted(suite) + " --out " + test::shell_quoted(dir / "runout"), "ulimit -f 4");
    EXPECT_EQ(r.status, 2) << r.err;
    EXPECT_NE(r.err.find(": write failed: File too large (nothing written)"), std::string::npos) << r.err;
    EXPECT_EQ(count_matching(dir / "runout", ".tmp"), 0u);
}

// ---- hostile inputs ---------------------------------------------------------------------------

TEST(Hostile, SpecialFilesAreRefusedNamingTheFile)
{
    const fs::path dir = fresh_hostile_dir("special");
    const fs::path fifo = dir / "pipe.qpsnap";
    ASSERT_EQ(::mkfifo(fifo.c_str(), 0644), 0);
    const std::string fifo_error = fifo.string() + ": not a regular file (a FIFO)\n";
    const Output info = run_hostile("info " + test::shell_quoted(fifo));
    EXPECT_EQ(info.status, 2);
    EXPECT_EQ(info.err, "contactbench info: error: " + fifo_error);
    const Output suite = run_hostile("run " + test::shell_quoted(fifo));
    EXPECT_EQ(suite.status, 2);
    EXPECT_EQ(suite.err, "contactbench run: error: " + fifo_error);
    const Output scene = run_hostile("simulate " + test::shell_quoted(fifo));
    EXPECT_EQ(scene.status, 2);
    EXPECT_EQ(scene.err, "contactbench simulate: error: " + fifo_error);
    // A FIFO matched by a suite glob fails its own runs, the others go ahead.
    write_snapshot(dir / "good.qpsnap", 1);
    write_json_atomic((dir / "glob.json").string(),
                      {{"name", "glob"}, {"snapshots", {"*.qpsnap"}}, {"solvers", {"mprgp"}}});
    const Output glob =
        run_hostile("run " + test::shell_quoted(dir / "glob.json") + " --out " + test::shell_quoted(dir / "out"));
    ASSERT_EQ(glob.status, 0) << glob.err;
    EXPECT_NE(glob.err.find("pipe x mprgp: invalid_input: " + fifo.string() + ": not a regular file (a FIFO)"),
              std::string::npos)
        << glob.err;
    EXPECT_NE(glob.err.find("good x mprgp: converged"), std::string::npos) << glob.err;

    // A folder as suite or scene, a symlink loop.
    const Output folder = run_hostile("run " + test::shell_quoted(dir));
    EXPECT_EQ(folder.status, 2);
    EXPECT_EQ(folder.err, "contactbench run: error: " + dir.string() + ": not a regular file (a folder)\n");
    const Output folder_scene = run_hostile("simulate " + test::shell_quoted(dir));
    EXPECT_EQ(folder_scene.status, 2);
    EXPECT_EQ(folder_scene.err, "contactbench simulate: error: " + dir.string() + ": not a regular file (a folder)\n");
    fs::create_symlink(dir / "loop2.json", dir / "loop1.json");
    fs::create_symlink(dir / "loop1.json", dir / "loop2.json");
    const Output loop = run_hostile("run " + test::shell_quoted(dir / "loop1.json"));
    EXPECT_EQ(loop.status, 2);
    EXPECT_EQ(loop.err, "contactbench run: error: " + (dir / "loop1.json").string() +
                            ": cannot open: Too many levels of symbolic links\n");
    // An --out that cannot be a folder.
    write_snapshot(dir / "a.qpsnap", 1);
    write_snapshot(dir / "b.qpsnap", 2);
    const fs::path s = write_hostile_suite(dir, "unwritable", {"mprgp"});
    const Output unwritable =
        run_hostile("run " + test::shell_quoted(s) + " --out " + test::shell_quoted(dir / "a.qpsnap" / "out"));
    EXPECT_EQ(unwritable.status, 2);
    EXPECT_EQ(unwritable.err, "contactbench run: error: " + (dir / "a.qpsnap" / "out").string() +
                                  ": --out: cannot create the results folder: Not a directory\n");
}

// Issue 27: writing through a temporary name and a rename replaced a FIFO or a device given as
// --json or a convert target by a regular file (as root, /dev/null too), exit 0.
TEST(Hostile, SpecialOutputTargetsAreNeverReplaced)
{
    const fs::path dir = fresh_hostile_dir("special_out");
    write_snapshot(dir / "a.qpsnap", 1);
    const std::string solve = "solve " + test::shell_quoted(dir / "a.qpsnap") + " --solver mprgp";
    auto is_fifo = [](const fs::path& p) {
        struct stat st {};
        return ::lstat(p.c_str(), &st) == 0 && S_ISFIFO(st.st_mode);
    };
    // A FIFO without a reader: exit 2, the FIFO stays; with a reader, the record flows through it.
    const fs::path fifo = dir / "record.json";
    ASSERT_EQ(::mkfifo(fifo.c_str(), 0644), 0);
    const Output lonely = run_hostile(solve + " --json " + test::shell_quoted(fifo));
    EXPECT_EQ(lonely.status, 2);
    EXPECT_NE(lonely.err.find("contactbench solve: error: " + fifo.string() +
                              ": is a FIFO with no reader: nothing written\n"),
              std::string::npos)
        << lonely.err;
    EXPECT_TRUE(is_fifo(fifo));
    const fs::path got = dir / "got.json";
    const Output piped = run_hostile(solve + " --json " + test::shell_quoted(fifo),
                                     "{ cat " + test::shell_quoted(fifo) + " >" + test::shell_quoted(got) + " & }");
    EXPECT_EQ(piped.status, 0) << piped.err;
    nlohmann::json record;
    for (int tries = 0; tries < 100 && !record.is_object(); ++tries) {  // cat finishes after the writer closes
        record = nlohmann::json::parse(slurp(got), nullptr, false);
        if (!record.is_object()) ::usleep(50000);
    }
    EXPECT_EQ(record.value("status", ""), "converged") << slurp(got);
    EXPECT_TRUE(is_fifo(fifo)) << "the FIFO was replaced";
    // A character device (a twin of /dev/null, made where the test may: root) is written to, not replaced.
    const fs::path null_twin = dir / "null";
    if (::mknod(null_twin.c_str(), S_IFCHR | 0666, makedev(1, 3)) == 0) {
        const Output null_out = run_hostile(solve + " --json " + test::shell_quoted(null_twin));
        EXPECT_EQ(null_out.status, 0) << null_out.err;
        struct stat st {};
        ASSERT_EQ(::lstat(null_twin.c_str(), &st), 0);
        EXPECT_TRUE(S_ISCHR(st.st_mode)) << "the device was replaced by a regular file";
    }
    // The shell's stdout as --json (a file here: run() redirects it): appended after the summary,
    // and nothing is created or renamed under /proc (/dev/stdout as root was replaced).
    const Output through = run_hostile(solve + " --json /proc/self/fd/1");
    EXPECT_EQ(through.status, 0) << through.err;
    const size_t brace = through.out.find("\n{");
    ASSERT_NE(brace, std::string::npos) << through.out;
    EXPECT_EQ(nlohmann::json::parse(through.out.substr(brace + 1)).value("status", ""), "converged");
    // A folder as --json; FIFOs as convert targets (a .qpsnap streams, an FCLIB file needs to seek).
    const Output folder = run_hostile(solve + " --json " + test::shell_quoted(dir));
    EXPECT_EQ(folder.status, 2);
    EXPECT_NE(folder.err.find(dir.string() + ": is a folder: not replaced (name a file)\n"), std::string::npos)
        << folder.err;
    const fs::path snap_fifo = dir / "out.qpsnap", hdf5_fifo = dir / "out.hdf5";
    ASSERT_EQ(::mkfifo(snap_fifo.c_str(), 0644), 0);
    ASSERT_EQ(::mkfifo(hdf5_fifo.c_str(), 0644), 0);
    const Output snap =
        run_hostile("convert " + test::shell_quoted(dir / "a.qpsnap") + " " + test::shell_quoted(snap_fifo));
    EXPECT_EQ(snap.status, 2);
    EXPECT_EQ(snap.err,
              "contactbench convert: error: " + snap_fifo.string() + ": is a FIFO with no reader: nothing written\n");
    const Output hdf5 =
        run_hostile("convert " + test::shell_quoted(dir / "a.qpsnap") + " " + test::shell_quoted(hdf5_fifo));
    EXPECT_EQ(hdf5.status, 2);
    EXPECT_EQ(hdf5.err, "contactbench convert: error: " + hdf5_fifo.string() +
                            ": is a FIFO: not replaced (this output needs a regular file)\n");
    EXPECT_TRUE(is_fifo(snap_fifo) && is_fifo(hdf5_fifo));
    // Unclear before: an empty --json, and --save-solution onto a file (both before the solve).
    const Output empty = run_hostile(solve + " --json ''");
    EXPECT_EQ(empty.status, 2);
    EXPECT_EQ(empty.err, "contactbench solve: error: solve: --json: expects a file or folder name, got \"\"\n");
    const Output onto_file = run_hostile(solve + " --save-solution " + test::shell_quoted(dir / "a.qpsnap"));
    EXPECT_EQ(onto_file.status, 2);
    EXPECT_EQ(onto_file.err, "contactbench solve: error: " + (dir / "a.qpsnap").string() +
                                 ": --save-solution: exists and is not a folder (x.mtx and lambda.mtx are written "
                                 "into a folder)\n");
    EXPECT_EQ(count_matching(dir, ".tmp."), 0u);
}

// A symlink planted as OUT/.lock made `run` truncate the file it points to (outside OUT).
TEST(Hostile, PlantedLockLinkIsNotFollowed)
{
    const fs::path dir = fresh_hostile_dir("lock_link");
    write_snapshot(dir / "a.qpsnap", 1);
    write_snapshot(dir / "b.qpsnap", 2);
    const fs::path suite = write_hostile_suite(dir, "locked", {"mprgp"});
    std::ofstream(dir / "victim.txt") << "precious\n";
    fs::create_directories(dir / "out");
    fs::create_symlink(dir / "victim.txt", dir / "out" / ".lock");
    const Output r = run_hostile("run " + test::shell_quoted(suite) + " --out " + test::shell_quoted(dir / "out"));
    EXPECT_EQ(r.status, 2);
    EXPECT_EQ(r.err, "contactbench run: error: " + (dir / "out" / ".lock").string() +
                         ": cannot create the lock file: Too many levels of symbolic links\n");
    EXPECT_EQ(slurp(dir / "victim.txt"), "precious\n");
}

// Issue 27: an interrupted convert or merge left PATH.tmp.<pid> that no later run cleaned.
TEST(Hostile, TemporariesOfAnInterruptedRunAreRemovedByTheNext)
{
    const fs::path dir = fresh_hostile_dir("stale_tmp");
    write_snapshot(dir / "a.qpsnap", 1);
    const pid_t child = ::fork();  // a pid that is surely gone
    ASSERT_GE(child, 0);
    if (child == 0) ::_exit(0);
    ASSERT_EQ(::waitpid(child, nullptr, 0), child);
    const std::string dead = std::to_string(child);
    std::ofstream(dir / ("b.qpsnap.tmp." + dead)) << "half a snapshot";
    std::ofstream(dir / ("b.hdf5.tmp." + dead)) << "half an HDF5 file";
    fs::create_directories(dir / ("b_mm.tmp." + dead));
    std::ofstream(dir / ("b_mm.tmp." + dead) / "A.mtx") << "half a folder";
    std::ofstream(dir / ("other.txt.tmp." + dead)) << "not a target of this run: kept";
    // Left over: untouched for an hour. A young one may be another machine's write in progress on
    // a shared file system (the pid is only known gone here): named and kept.
    const std::string tmp_suffix = ".tmp." + dead;
    for (const std::string target : {"b.qpsnap", "b.hdf5", "b_mm"})
        fs::last_write_time(dir / (target + tmp_suffix), fs::file_time_type::clock::now() - std::chrono::hours(1));
    std::ofstream(dir / ("young.qpsnap.tmp." + dead)) << "maybe another machine's";
    const Output young =
        run_hostile("convert " + test::shell_quoted(dir / "a.qpsnap") + " " + test::shell_quoted(dir / "young.qpsnap"));
    ASSERT_EQ(young.status, 0) << young.err;
    EXPECT_EQ(young.err, "note: kept " + (dir / ("young.qpsnap.tmp." + dead)).string() + ": process " + dead +
                             " is gone here, but the file is younger than 10 minutes (another machine may be "
                             "writing it); remove it if not\n");
    EXPECT_TRUE(fs::exists(dir / ("young.qpsnap.tmp." + dead)));
    fs::remove(dir / ("young.qpsnap.tmp." + dead));
    for (const std::string target : {"b.qpsnap", "b.hdf5", "b_mm"}) {
        const fs::path tmp = dir / (target + tmp_suffix);
        const Output r = run_hostile(std::string("convert ")
                                         .append(test::shell_quoted(dir / "a.qpsnap"))
                                         .append(" ")
                                         .append(test::shell_quoted(dir / target)));
        ASSERT_EQ(r.status, 0) << r.err;
        EXPECT_EQ(r.err, std::string("note: removed ")
                             .append(tmp.string())
                             .append(", left by an interrupted earlier run (process ")
                             .append(dead)
                             .append(" is gone)\n"));
        EXPECT_FALSE(fs::exists(tmp));
    }
    EXPECT_TRUE(fs::exists(dir / ("other.txt.tmp." + dead)));
    EXPECT_EQ(count_matching(dir, ".tmp."), 1u);
}

TEST(Hostile, DeepJsonIsRefusedNotACrash)
{
    const fs::path dir = fresh_hostile_dir("deep");
    const std::string deep = std::string(1000000, '[') + std::string(1000000, ']');
    // A suite comment nested 10^6 deep.
    // The 64th '[' opens level 65 (the object is level 1): its byte is reported.
    const std::string suite_head = R"({"name": "deep", "comment": )";
    std::ofstream(dir / "suite.json") << suite_head << deep << R"(, "solvers": ["cg"]})";
    const Output suite = run_hostile("run " + test::shell_quoted(dir / "suite.json"));
    EXPECT_EQ(suite.status, 2);
    EXPECT_EQ(suite.err, "contactbench run: error: " + (dir / "suite.json").string() +
                             ": JSON nested deeper than 64 levels (at byte " + std::to_string(suite_head.size() + 63) +
                             ")\n");
    // A scene.
    const std::string scene_head = R"({"name": "deep", "description": )";
    std::ofstream(dir / "scene.json") << scene_head << deep << "}";
    const Output scene = run_hostile("simulate " + test::shell_quoted(dir / "scene.json"));
    EXPECT_EQ(scene.status, 2);
    EXPECT_EQ(scene.err, "contactbench simulate: error: " + (dir / "scene.json").string() +
                             ": JSON nested deeper than 64 levels (at byte " + std::to_string(scene_head.size() + 63) +
                             ")\n");
    // A snapshot header: meta nested 10^6 deep.
    const std::string header_head = R"({"format": "qpsnap", "version": 1, "n": 0, "m": 0, "arrays": {}, "meta": )";
    const std::string header = header_head + deep + "}";
    std::string bytes(8, '\0');
    for (int i = 0; i < 8; ++i) bytes[size_t(i)] = char((std::uint64_t(header.size()) >> (8 * i)) & 0xff);
    std::ofstream(dir / "deep.qpsnap", std::ios::binary) << bytes << header;
    const Output snap = run_hostile("info " + test::shell_quoted(dir / "deep.qpsnap"));
    EXPECT_EQ(snap.status, 2);
    EXPECT_EQ(snap.err, "contactbench info: error: " + (dir / "deep.qpsnap").string() +
                            ": header: JSON nested deeper than 64 levels (at byte " +
                            std::to_string(header_head.size() + 63) + ")\n");
}

TEST(Hostile, HugeDeclaredSizesUnderAMemoryLimit)
{
    // 600 MB of address space: enough for the binary and its libraries, far from the 1.6 GB the
    // declared 2e8 rows once cost.
    const std::string limit = "ulimit -v 600000";
    const fs::path rows = HOSTILE / "mtx_huge_rows";
    const Output a = run_hostile(
        "convert " + test::shell_quoted(rows) + " " + test::shell_quoted(hostile_work_dir() / "huge.qpsnap"), limit);
    EXPECT_EQ(a.status, 2);
    EXPECT_EQ(a.err, "contactbench convert: error: " + (rows / "A.mtx").string() +
                         ": line 2: declares 200000000 rows but only 1 entries (every row needs its diagonal entry)\n");
    const fs::path vec = HOSTILE / "mtx_huge_vector";
    const Output b = run_hostile(
        "convert " + test::shell_quoted(vec) + " " + test::shell_quoted(hostile_work_dir() / "huge.qpsnap"), limit);
    EXPECT_EQ(b.status, 2);
    EXPECT_EQ(b.err, "contactbench convert: error: " + (vec / "b.mtx").string() +
                         ": size: expected n (from A.mtx) = 1 entries, got 200000000\n");
    const fs::path j = HOSTILE / "mtx_huge_j";
    const Output jj = run_hostile(
        "convert " + test::shell_quoted(j) + " " + test::shell_quoted(hostile_work_dir() / "huge.qpsnap"), limit);
    EXPECT_EQ(jj.status, 2);
    const auto c_bytes = fs::file_size(j / "c.mtx");
    EXPECT_EQ(jj.err, "contactbench convert: error: " + (j / "J.mtx").string() +
                          ": line 2: declares 200000000 rows, at most " + std::to_string(c_bytes / 2 + 1) +
                          " possible (c.mtx holds " + std::to_string(c_bytes) +
                          " bytes, this file declares 1 entries)\n");
    EXPECT_FALSE(fs::exists(hostile_work_dir() / "huge.qpsnap"));

    // A snapshot with a 4 GB sparse tail: refused before it is mapped.
    const fs::path sparse = hostile_work_dir() / "sparse.qpsnap";
    write_snapshot(sparse, 1);
    ASSERT_EQ(::truncate(sparse.c_str(), off_t(4) << 30), 0);
    const Output s = run_hostile("solve " + test::shell_quoted(sparse) + " --solver cg", limit);
    EXPECT_EQ(s.status, 2);
    EXPECT_EQ(s.err.rfind("contactbench solve: error: " + sparse.string() + ": data: sparse file: ", 0), 0u) << s.err;
    EXPECT_NE(s.err.find(" of its 4294967296 bytes (from byte "), std::string::npos) << s.err;
}

TEST(Hostile, SceneAndGeneratorParametersAreBounded)
{
    const Output cells = run_hostile("simulate " + test::shell_quoted(HOSTILE / "scene_box_cells.json") + " --out " +
                                     test::shell_quoted(hostile_work_dir() / "x"));
    EXPECT_EQ(cells.status, 2);
    EXPECT_EQ(cells.err, "contactbench simulate: error: " + (HOSTILE / "scene_box_cells.json").string() +
                             ": /bodies/0/box/cells: [3000000000, 1, 1] is 3000000000 cells, more than the limit of "
                             "1000000 (6000000 tets)\n");
    const Output count = run_hostile("simulate " + test::shell_quoted(HOSTILE / "scene_array_count.json") + " --out " +
                                     test::shell_quoted(hostile_work_dir() / "x"));
    EXPECT_EQ(count.status, 2);
    EXPECT_EQ(count.err,
              "contactbench simulate: error: " + (HOSTILE / "scene_array_count.json").string() +
                  ": /bodies/0/array/count: 1000000000000000 copies, more than the limit of 6000000 tets allows\n");
    const Output many = run_hostile("simulate " + test::shell_quoted(HOSTILE / "scene_many_bodies.json") + " --out " +
                                    test::shell_quoted(hostile_work_dir() / "x"));
    EXPECT_EQ(many.status, 2);
    EXPECT_EQ(many.err,
              "contactbench simulate: error: " + (HOSTILE / "scene_many_bodies.json").string() +
                  ": /bodies/0/array/count: the scene reaches 13500000 tets, more than the limit of 6000000\n");
    EXPECT_FALSE(fs::exists(hostile_work_dir() / "x"));

    const fs::path out = hostile_work_dir() / "gen.qpsnap";
    const Output nx = run_hostile("generate plane --out " + test::shell_quoted(out) +
                                  " --param nx=1000 --param ny=1000 --param nz=1000");
    EXPECT_EQ(nx.status, 2);
    EXPECT_EQ(nx.err, "contactbench generate: error: synthetic family 'plane': params: nx: expected at most 1e6 "
                      "vertices in all (nx+1)(ny+1)(nz+1), got 1.003e+09\n");
    const Output inf = run_hostile("generate plane --out " + test::shell_quoted(out) + " --param youngs=1e308");
    EXPECT_EQ(inf.status, 2);
    EXPECT_EQ(inf.err.rfind("contactbench generate: error: synthetic family 'plane': params: the parameters give a "
                            "non-finite value in A (",
                            0),
              0u)
        << inf.err;
    EXPECT_FALSE(fs::exists(out));
}

TEST(Hostile, IntegerSettingsDoNotOverflow)
{
    const fs::path snap = fs::path(CB_TEST_DATA_DIR) / "plane_2x2x2.qpsnap";
    const Output o =
        run_hostile("solve " + test::shell_quoted(snap) + " --solver mprgp --set max_iterations=9223372036854775807");
    EXPECT_EQ(o.status, 2);
    EXPECT_EQ(o.err,
              "contactbench solve: error: mprgp: /max_iterations: must be <= 1000000000000, got 9223372036854775807\n");
    const Output big = run_hostile("solve " + test::shell_quoted(snap) + " --solver mprgp --set max_iterations=1e19");
    EXPECT_EQ(big.status, 2);
    EXPECT_EQ(big.err, "contactbench solve: error: mprgp: /max_iterations: must be <= 1000000000000, got 1e+19\n");
    // The same through a suite (tests/hostile/suite_overflow.json): the run is refused, named.
    const fs::path out = hostile_work_dir() / "overflow";
    const Output r =
        run_hostile("run " + test::shell_quoted(HOSTILE / "suite_overflow.json") + " --out " + test::shell_quoted(out));
    ASSERT_EQ(r.status, 0) << r.err;
    const nlohmann::json rec = read_json_file((out / "runs" / "plane_2x2x2__mprgp.json").string());
    EXPECT_EQ(rec["status"], "invalid_input");
    EXPECT_EQ(rec["message"], "mprgp: /max_iterations: must be <= 1000000000000, got 9223372036854775807");
}
