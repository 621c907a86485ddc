// `run` through the binary (env CB_CONTACTBENCH) where the environment decides: the shard of a
// Slurm array task (folder, provenance, bad variables), `--jobs` (parallel runs, identical
// counters), `cluster slurm` (files, printed commands, bad options) and merge's CPU-model warning.
#include "harness/results.hpp"

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

const fs::path& run_env_work_dir()
{
    static const fs::path dir = [] {
        fs::path d = test::make_test_work_dir("run_env");
        for (const char* name : {"SLURM_ARRAY_TASK_ID", "SLURM_ARRAY_TASK_MIN", "SLURM_ARRAY_TASK_MAX",
                                 "SLURM_ARRAY_TASK_COUNT", "SLURM_ARRAY_JOB_ID", "SLURM_JOB_ID", "SLURMD_NODENAME"})
            ::unsetenv(name);  // a test run inside a Slurm job must not see its own job
        return d;
    }();
    return dir;
}

/// Runs `ENV contactbench ARGS` (ENV: "NAME=value ...", ARGS shell-quoted where needed).
Output run_with_env(const std::string& args, const std::string& env = "")
{
    test::CliCall call;
    call.env = env;
    return test::run_contactbench(args, run_env_work_dir(), call);
}

/// 2 snapshots x 3 solvers = 6 jobs.
std::string write_env_suite(const std::string& name, bool timed)
{
    nlohmann::json suite = {
        {"name", name},
        {"generate",
         {{{"id", "p1"}, {"family", "plane"}, {"seed", 1}, {"params", {{"nx", 2}, {"ny", 2}, {"nz", 2}}}},
          {{"id", "p2"}, {"family", "plane"}, {"seed", 2}, {"params", {{"nx", 3}, {"ny", 2}, {"nz", 2}}}}}},
        {"solvers", {"mprgp", "pgs", "active-set"}},
        {"tol", 1e-6},
        {"time_limit_s", 20}};
    if (!timed) suite["timed"] = false;
    const fs::path p = run_env_work_dir() / (name + ".json");
    write_json_atomic(p.string(), suite);
    return p.string();
}

/// summary.csv without the columns that hold times and memory.
std::string summary_without_times(const fs::path& dir)
{
    std::ifstream in(dir / "summary.csv");
    std::string line, result;
    std::vector<bool> keep;
    while (std::getline(in, line)) {
        std::vector<std::string> cells;
        size_t start = 0;
        for (size_t comma; (comma = line.find(',', start)) != std::string::npos; start = comma + 1)
            cells.push_back(line.substr(start, comma - start));
        cells.push_back(line.substr(start));
        if (keep.empty())
            for (const auto& c : cells)  // measurements, not results: they differ between any two runs
                keep.push_back(c != "setup_s" && c != "solve_s" && c != "time_s" && c != "peak_rss_mb");
        for (size_t i = 0; i < cells.size() && i < keep.size(); ++i)
            if (keep[i]) result += cells[i] + ",";
        result += "\n";
    }
    return result;
}

const auto* const RUN_ENV_CLEAN_UP = ::testing::AddGlobalTestEnvironment(new test::RemoveAtEnd(run_env_work_dir));

}  // namespace

TEST(RunEnv, SlurmArrayTaskRunsItsShardInItsOwnFolder)
{
    const std::string suite = write_env_suite("env", true);
    const fs::path single = run_env_work_dir() / "single", out = run_env_work_dir() / "array";
    ASSERT_EQ(run_with_env("run '" + suite + "' --out '" + single.string() + "'").status, 0);
    // --array=5-7: three tasks, shards 1..3 of 3, each in OUT/shard-<i>-of-3.
    std::string merge_args = "merge '" + out.string() + "'";
    for (int task = 5; task <= 7; ++task) {
        const std::string env = "SLURM_JOB_ID=" + std::to_string(100 + task) +
                                " SLURM_ARRAY_JOB_ID=100 SLURM_ARRAY_TASK_ID=" + std::to_string(task) +
                                " SLURM_ARRAY_TASK_MIN=5 SLURM_ARRAY_TASK_MAX=7 "
                                "SLURM_ARRAY_TASK_COUNT=3 SLURMD_NODENAME=node-" +
                                std::to_string(task);
        const Output o = run_with_env("run '" + suite + "' --out '" + out.string() + "'", env);
        ASSERT_EQ(o.status, 0) << o.err;
        const fs::path shard = out / ("shard-" + std::to_string(task - 4) + "-of-3");
        EXPECT_NE(o.err.find("run: Slurm array task " + std::to_string(task) + ": shard " + std::to_string(task - 4) +
                             "/3 -> " + shard.string() + "\n"),
                  std::string::npos)
            << o.err;
        EXPECT_NE(o.err.find("ran 2 of 2 jobs"), std::string::npos) << o.err;  // 6 jobs over 3 shards
        merge_args += " '" + shard.string() + "'";
    }
    // Job j (snapshot-major) is in shard j % 3 + 1: p1 x pgs is job 1, shard 2 = task 6.
    const nlohmann::json pgs = read_json_file((out / "shard-2-of-3" / "runs" / "p1__pgs.json").string());
    EXPECT_EQ(pgs["provenance"]["slurm"]["job_id"], "106");
    EXPECT_EQ(pgs["provenance"]["slurm"]["array_job_id"], "100");
    EXPECT_EQ(pgs["provenance"]["slurm"]["array_task_id"], "6");
    EXPECT_EQ(pgs["provenance"]["slurm"]["node"], "node-6");
    EXPECT_EQ(pgs["provenance"]["load_average"].size(), 3u);
    EXPECT_TRUE(pgs["provenance"]["cpu"].is_string());
    EXPECT_FALSE(fs::exists(out / "runs"));  // tasks never write the parent folder

    const Output m = run_with_env(merge_args);
    ASSERT_EQ(m.status, 0) << m.err;
    EXPECT_EQ(m.err.find("warning"), std::string::npos) << m.err;  // one CPU model
    EXPECT_EQ(summary_without_times(out), summary_without_times(single));

    // --shard wins over the environment; a bad variable is named, exit 2, nothing written.
    const fs::path explicit_shard = run_env_work_dir() / "explicit";
    const Output o = run_with_env("run '" + suite + "' --out '" + explicit_shard.string() + "' --shard 1/1",
                                  "SLURM_ARRAY_TASK_ID=5 SLURM_ARRAY_TASK_MIN=5 SLURM_ARRAY_TASK_COUNT=3");
    ASSERT_EQ(o.status, 0) << o.err;
    EXPECT_NE(o.err.find("ran 6 of 6 jobs"), std::string::npos) << o.err;
    const fs::path bad_out = run_env_work_dir() / "bad";
    const Output bad = run_with_env("run '" + suite + "' --out '" + bad_out.string() + "'",
                                    "SLURM_ARRAY_TASK_ID=9 SLURM_ARRAY_TASK_MIN=5 SLURM_ARRAY_TASK_COUNT=3");
    EXPECT_EQ(bad.status, 2);
    EXPECT_EQ(bad.err, "contactbench run: error: run: SLURM_ARRAY_TASK_ID: 9 is outside the array 5..7\n");
    EXPECT_FALSE(fs::exists(bad_out));
}

TEST(RunEnv, MergeWarnsWhenTimedRunsComeFromTwoCpuModels)
{
    const std::string suite = write_env_suite("cpus", true);
    const fs::path a = run_env_work_dir() / "cpu-a", b = run_env_work_dir() / "cpu-b",
                   merged = run_env_work_dir() / "cpu-merged";
    ASSERT_EQ(run_with_env("run '" + suite + "' --out '" + a.string() + "' --shard 1/2").status, 0);
    ASSERT_EQ(run_with_env("run '" + suite + "' --out '" + b.string() + "' --shard 2/2").status, 0);
    for (const auto& entry : fs::directory_iterator(b / "runs")) {
        nlohmann::json record = read_json_file(entry.path().string());
        record["provenance"]["cpu"] = "Other CPU 9000";
        write_json_atomic(entry.path().string(), record);
    }
    const Output m = run_with_env("merge '" + merged.string() + "' '" + a.string() + "' '" + b.string() + "'");
    ASSERT_EQ(m.status, 0) << m.err;
    EXPECT_NE(m.err.find("merge: warning: timed runs come from 2 CPU models, so their times do not compare "
                         "(counters do): "),
              std::string::npos)
        << m.err;
    EXPECT_NE(m.err.find("'Other CPU 9000' (3 runs)"), std::string::npos) << m.err;
}

TEST(RunEnv, JobsRunUntimedSuitesInParallelWithTheSameCounters)
{
    const std::string untimed = write_env_suite("untimed", false);
    const fs::path serial = run_env_work_dir() / "serial", parallel = run_env_work_dir() / "parallel";
    const Output s = run_with_env("run '" + untimed + "' --out '" + serial.string() + "'");
    ASSERT_EQ(s.status, 0) << s.err;
    const Output p = run_with_env("run '" + untimed + "' --out '" + parallel.string() + "' --jobs 3");
    ASSERT_EQ(p.status, 0) << p.err;
    EXPECT_NE(p.err.find("run: --jobs 3: runs go 3 at a time in child processes (\"timed\": false: counters as in a "
                         "serial run, times not judged)\n"),
              std::string::npos)
        << p.err;
    EXPECT_NE(p.err.find("ran 6 of 6 jobs; 6 runs in"), std::string::npos) << p.err;
    EXPECT_EQ(summary_without_times(parallel), summary_without_times(serial));
    const Output judge = run_with_env("compare '" + serial.string() + "' '" + parallel.string() + "'");
    EXPECT_EQ(judge.status, 0) << judge.out;
    EXPECT_NE(judge.out.find("verdict: PASS (6 runs compared: 6 equal"), std::string::npos) << judge.out;
    EXPECT_EQ(read_json_file((parallel / "runs" / "p2__pgs.json").string())["concurrent_jobs"], 3);

    // A timed suite keeps its runs one at a time unless --jobs-timed.
    const std::string timed = write_env_suite("timed", true);
    const Output t =
        run_with_env("run '" + timed + "' --out '" + (run_env_work_dir() / "timed").string() + "' --jobs 3");
    ASSERT_EQ(t.status, 0) << t.err;
    EXPECT_NE(t.err.find("run: --jobs 3: this suite's times are judged, so its runs go one at a time"),
              std::string::npos)
        << t.err;
    EXPECT_FALSE(
        read_json_file((run_env_work_dir() / "timed" / "runs" / "p2__pgs.json").string()).contains("concurrent_jobs"));
    const Output forced = run_with_env("run '" + timed + "' --out '" + (run_env_work_dir() / "timed-par").string() +
                                       "' --jobs 2 --jobs-timed");
    ASSERT_EQ(forced.status, 0) << forced.err;
    EXPECT_NE(forced.err.find("runs go 2 at a time in child processes (--jobs-timed"), std::string::npos) << forced.err;
    EXPECT_EQ(summary_without_times(run_env_work_dir() / "timed-par"),
              summary_without_times(run_env_work_dir() / "timed"));

    const Output bad = run_with_env("run '" + timed + "' --jobs 0");
    EXPECT_EQ(bad.status, 2);
    EXPECT_EQ(bad.err, "contactbench run: error: run: --jobs: must be >= 1, got 0\n");
}

TEST(RunEnv, ClusterSlurmWritesFilesAndPrintsCommands)
{
    const std::string suite = write_env_suite("cl", true);
    const fs::path out = run_env_work_dir() / "cluster";
    const Output o = run_with_env("cluster slurm '" + suite + "' --out '" + out.string() +
                                  "' --shards 4 --partition short --time 00:20:00 --mem 1G --exclusive");
    ASSERT_EQ(o.status, 0) << o.err;
    const std::string array = (out / "slurm" / "array.sbatch").string(),
                      merge = (out / "slurm" / "merge.sbatch").string();
    EXPECT_EQ(o.out,
              "jobid=$(sbatch --parsable '" + array + "')\nsbatch --dependency=afterok:$jobid '" + merge + "'\n");
    const std::string text = slurp(array);
    EXPECT_NE(text.find("\n#SBATCH --array=0-3\n"), std::string::npos) << text;
    EXPECT_NE(text.find("\n#SBATCH --partition=short\n"), std::string::npos) << text;
    EXPECT_NE(text.find("\n#SBATCH --exclusive\n"), std::string::npos) << text;
    EXPECT_NE(text.find(" run '" + fs::canonical(suite).string() + "' --out '" + out.string() + "'\n"),
              std::string::npos)
        << text;
    EXPECT_NE(slurp(merge).find(" merge '" + out.string() + "'"), std::string::npos);

    const Output no_shards = run_with_env("cluster slurm '" + suite + "' --out '" + out.string() + "'");
    EXPECT_EQ(no_shards.status, 2);
    EXPECT_EQ(no_shards.err, "contactbench cluster: error: cluster: --shards: required: the number of array tasks\n");
    const Output zero = run_with_env("cluster slurm '" + suite + "' --out '" + out.string() + "' --shards 0");
    EXPECT_EQ(zero.err, "contactbench cluster: error: cluster: --shards: must be in 1..10000, got 0\n");
    const Output huge =
        run_with_env("cluster slurm '" + suite + "' --out '" + out.string() + "' --shards 99999999999999999999");
    EXPECT_EQ(huge.status, 2);
    EXPECT_EQ(huge.err, "contactbench cluster: error: cluster: --shards: '99999999999999999999' is out of range (at "
                        "most 9223372036854775807 in magnitude)\n");
    const Output pbs = run_with_env("cluster pbs '" + suite + "' --out x --shards 2");
    EXPECT_EQ(pbs.status, 2);
    EXPECT_EQ(pbs.err, "contactbench cluster: error: cluster: scheduler: expected 'slurm', got 'pbs'\n");
    const fs::path spaced = run_env_work_dir() / "with space";
    const Output space = run_with_env("cluster slurm '" + suite + "' --out '" + spaced.string() + "' --shards 2");
    EXPECT_EQ(space.status, 2);
    EXPECT_NE(space.err.find("holds a space, quote, backslash or %, which #SBATCH lines cannot carry"), std::string::npos)
        << space.err;
    EXPECT_FALSE(fs::exists(spaced));
}

TEST(RunEnv, ClusterSlurmGivesEachTaskTheThreadsItsLabelsUse)
{
    nlohmann::json suite = read_json_file(write_env_suite("threaded", true));
    suite["solvers"] = {"pgs", {{"label", "mprgp-2t"}, {"solver", "mprgp"}, {"settings", {{"threads", 2}}}}};
    const fs::path path = run_env_work_dir() / "threaded.json";
    write_json_atomic(path.string(), suite);
    const fs::path out = run_env_work_dir() / "cluster-threads";
    const Output o = run_with_env("cluster slurm '" + path.string() + "' --out '" + out.string() + "' --shards 2");
    ASSERT_EQ(o.status, 0) << o.err;
    const std::string text = slurp(out / "slurm" / "array.sbatch");
    EXPECT_NE(text.find("\n#SBATCH --cpus-per-task=2\n"), std::string::npos) << text;
    EXPECT_NE(text.find("\nsrun --ntasks=1 --cpus-per-task=2 "), std::string::npos) << text;
    const Output few = run_with_env("cluster slurm '" + path.string() + "' --out '" +
                                    (run_env_work_dir() / "few").string() + "' --shards 2 --cpus-per-task 1");
    EXPECT_EQ(few.status, 2);
    EXPECT_EQ(few.err,
              "contactbench cluster: error: cluster: --cpus-per-task: 1 is fewer than the 2 threads a label of " +
                  path.string() + " asks for (setting `threads`)\n");
    EXPECT_FALSE(fs::exists(run_env_work_dir() / "few"));
}

TEST(RunEnv, JobsComputeReferencesBeforeTheTimedRuns)
{
    const nlohmann::json suite = {
        {"name", "refs"},
        {"generate",
         {{{"id", "plane"}, {"family", "plane"}, {"seed", 1}, {"params", {{"nx", 3}, {"ny", 2}, {"nz", 3}}}},
          {{"id", "coupled"}, {"family", "coupled"}, {"seed", 13}, {"params", {{"nx", 4}, {"ny", 2}, {"nz", 4}}}}}},
        {"solvers",
         {"mprgp", "pgs"}},  // mprgp sees the coupled snapshot decoupled: still one reference, of the original QP
        {"reference", true},
        {"tol", 1e-6},
        {"time_limit_s", 20}};
    const fs::path path = run_env_work_dir() / "refs.json";
    write_json_atomic(path.string(), suite);
    const fs::path serial = run_env_work_dir() / "refs-serial", parallel = run_env_work_dir() / "refs-parallel";
    // Separate caches: the parallel run must compute every reference itself.
    const Output s = run_with_env("run '" + path.string() + "' --out '" + serial.string() + "'",
                                  "CB_CACHE='" + (run_env_work_dir() / "cache-serial").string() + "'");
    ASSERT_EQ(s.status, 0) << s.err;
    const Output p = run_with_env("run '" + path.string() + "' --out '" + parallel.string() + "' --jobs 2",
                                  "CB_CACHE='" + (run_env_work_dir() / "cache-parallel").string() + "'");
    ASSERT_EQ(p.status, 0) << p.err;
    EXPECT_NE(p.err.find("run: --jobs 2: reference solutions of 2 snapshot(s) computed 2 at a time before the runs\n"),
              std::string::npos)
        << p.err;
    EXPECT_NE(p.err.find("its runs go one at a time"), std::string::npos) << p.err;
    // Every run found its reference already computed: the prefetch used the runs' cache keys.
    for (const std::string name : {"plane__mprgp", "plane__pgs", "coupled__mprgp", "coupled__pgs"}) {
        const nlohmann::json par = read_json_file((parallel / "runs" / (name + ".json")).string());
        const nlohmann::json ser = read_json_file((serial / "runs" / (name + ".json")).string());
        EXPECT_TRUE(par["reference"]["cached"].get<bool>()) << name;
        EXPECT_EQ(par["reference"]["key"], ser["reference"]["key"]) << name;
        EXPECT_EQ(par["reference"]["objective"], ser["reference"]["objective"]) << name;
        EXPECT_EQ(par["energy_gap"].dump(), ser["energy_gap"].dump()) << name;
        EXPECT_EQ(par["reference"]["key"], par["snapshot"]["hash"]) << name;  // F* of the QP in the file
    }
    EXPECT_EQ(summary_without_times(parallel), summary_without_times(serial));
}
