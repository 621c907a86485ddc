// Slurm glue without a Slurm: array variables -> shard (offset ranges, bad values named), the
// job's provenance, the generated sbatch files, the mixed-CPU warning of merge, and `run`
// taking its shard from the environment (through the binary, env CB_CONTACTBENCH).
#include "harness/results.hpp"
#include "harness/slurm.hpp"
#include "harness/timing_hygiene.hpp"
#include "solvers/core/types.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sys/wait.h>
#include <unistd.h>

namespace fs = std::filesystem;
using namespace cb;

namespace {

std::string input_error(const Environment& env)
{
    try {
        shard_from_slurm(env);
    } catch (const InputError& e) {
        return e.what();
    }
    return "no error";
}

}  // namespace

TEST(SlurmShard, NoArrayNoShard)
{
    EXPECT_FALSE(shard_from_slurm({}).has_value());
    EXPECT_FALSE(shard_from_slurm({{"SLURM_JOB_ID", "17"}}).has_value());  // a plain job runs the whole suite
}

TEST(SlurmShard, ZeroBasedArrayMapsToShards)
{
    for (long task = 0; task < 4; ++task) {
        const auto shard = shard_from_slurm({{"SLURM_ARRAY_TASK_ID", std::to_string(task)},
                                             {"SLURM_ARRAY_TASK_MIN", "0"},
                                             {"SLURM_ARRAY_TASK_MAX", "3"},
                                             {"SLURM_ARRAY_TASK_COUNT", "4"}});
        ASSERT_TRUE(shard.has_value());
        EXPECT_EQ(shard->index, task + 1);
        EXPECT_EQ(shard->count, 4);
    }
}

TEST(SlurmShard, OffsetArrayMapsThroughMin)
{
    // --array=5-8: tasks 5, 6, 7, 8 are shards 1..4 of 4.
    for (long task = 5; task <= 8; ++task) {
        const auto shard = shard_from_slurm({{"SLURM_ARRAY_TASK_ID", std::to_string(task)},
                                             {"SLURM_ARRAY_TASK_MIN", "5"},
                                             {"SLURM_ARRAY_TASK_MAX", "8"},
                                             {"SLURM_ARRAY_TASK_COUNT", "4"}});
        ASSERT_TRUE(shard.has_value());
        EXPECT_EQ(shard->index, task - 4);
        EXPECT_EQ(shard->count, 4);
    }
    // COUNT absent (older Slurm): MAX - MIN + 1.
    const auto no_count = shard_from_slurm(
        {{"SLURM_ARRAY_TASK_ID", "12"}, {"SLURM_ARRAY_TASK_MIN", "10"}, {"SLURM_ARRAY_TASK_MAX", "12"}});
    ASSERT_TRUE(no_count.has_value());
    EXPECT_EQ(no_count->index, 3);
    EXPECT_EQ(no_count->count, 3);
    // MAX absent: COUNT alone.
    const auto no_max = shard_from_slurm(
        {{"SLURM_ARRAY_TASK_ID", "7"}, {"SLURM_ARRAY_TASK_MIN", "7"}, {"SLURM_ARRAY_TASK_COUNT", "2"}});
    ASSERT_TRUE(no_max.has_value());
    EXPECT_EQ(no_max->index, 1);
    EXPECT_EQ(no_max->count, 2);
    EXPECT_EQ(shard_folder_name(3, 4), "shard-3-of-4");
}

TEST(SlurmShard, BadVariablesAreNamed)
{
    EXPECT_EQ(
        input_error({{"SLURM_ARRAY_TASK_ID", "x1"}, {"SLURM_ARRAY_TASK_MIN", "0"}, {"SLURM_ARRAY_TASK_COUNT", "4"}}),
        "run: SLURM_ARRAY_TASK_ID: expected an integer, got 'x1'");
    EXPECT_EQ(input_error({{"SLURM_ARRAY_TASK_ID", "1"}, {"SLURM_ARRAY_TASK_COUNT", "4"}}),
              "run: SLURM_ARRAY_TASK_MIN: not set, but SLURM_ARRAY_TASK_ID is (an array task needs both)");
    EXPECT_EQ(input_error({{"SLURM_ARRAY_TASK_ID", "1"}, {"SLURM_ARRAY_TASK_MIN", "0"}}),
              "run: SLURM_ARRAY_TASK_COUNT: not set and neither is SLURM_ARRAY_TASK_MAX");
    EXPECT_EQ(input_error({{"SLURM_ARRAY_TASK_ID", "9"},
                           {"SLURM_ARRAY_TASK_MIN", "5"},
                           {"SLURM_ARRAY_TASK_MAX", "8"},
                           {"SLURM_ARRAY_TASK_COUNT", "4"}}),
              "run: SLURM_ARRAY_TASK_ID: 9 is outside the array 5..8");
    EXPECT_EQ(
        input_error({{"SLURM_ARRAY_TASK_ID", "4"}, {"SLURM_ARRAY_TASK_MIN", "5"}, {"SLURM_ARRAY_TASK_COUNT", "4"}}),
        "run: SLURM_ARRAY_TASK_ID: 4 is outside the array 5..8");
    // --array=0-15:4 gives ids 0, 4, 8, 12: four tasks over sixteen ids.
    EXPECT_EQ(input_error({{"SLURM_ARRAY_TASK_ID", "4"},
                           {"SLURM_ARRAY_TASK_MIN", "0"},
                           {"SLURM_ARRAY_TASK_MAX", "12"},
                           {"SLURM_ARRAY_TASK_COUNT", "4"}}),
              "run: SLURM_ARRAY_TASK_COUNT: 4 tasks over the ids 0..12: only a contiguous array (e.g. --array=0-3 or "
              "5-8) maps to shards");
    EXPECT_EQ(input_error({{"SLURM_ARRAY_TASK_ID", "3"}, {"SLURM_ARRAY_TASK_MIN", "3"}, {"SLURM_ARRAY_TASK_MAX", "1"}}),
              "run: SLURM_ARRAY_TASK_MAX: 1 is below SLURM_ARRAY_TASK_MIN 3");
    EXPECT_EQ(
        input_error({{"SLURM_ARRAY_TASK_ID", "0"}, {"SLURM_ARRAY_TASK_MIN", "0"}, {"SLURM_ARRAY_TASK_COUNT", "0"}}),
        "run: SLURM_ARRAY_TASK_COUNT: must be >= 1, got 0");
}

TEST(SlurmProvenance, JobNodeAndArrayTask)
{
    EXPECT_TRUE(slurm_job_provenance({}).is_null());
    const nlohmann::json p = slurm_job_provenance({{"SLURM_JOB_ID", "42"},
                                                   {"SLURM_ARRAY_JOB_ID", "40"},
                                                   {"SLURM_ARRAY_TASK_ID", "6"},
                                                   {"SLURMD_NODENAME", "node07"},
                                                   {"SLURM_JOB_PARTITION", "short"}});
    EXPECT_EQ(p["job_id"], "42");
    EXPECT_EQ(p["array_job_id"], "40");
    EXPECT_EQ(p["array_task_id"], "6");
    EXPECT_EQ(p["node"], "node07");
    EXPECT_EQ(p["partition"], "short");
    EXPECT_TRUE(p["cpus_on_node"].is_null());
    char host[256] = {0};
    ASSERT_EQ(::gethostname(host, sizeof(host) - 1), 0);
    EXPECT_EQ(slurm_job_provenance({{"SLURM_JOB_ID", "1"}})["node"], std::string(host));  // no SLURMD_NODENAME
}

TEST(SlurmSbatch, ArrayAndMergeFiles)
{
    SbatchOptions o;
    o.contactbench = "/opt/cb/bin/contactbench";
    o.suite = "/home/u/suites/ci.json";
    o.suite_name = "ci";
    o.out = "/scratch/u/ci";
    o.shards = 4;
    o.first_index = 5;
    o.partition = "short";
    o.time = "00:30:00";
    o.mem = "2G";
    o.exclusive = true;
    o.max_parallel = 2;
    o.cpus_per_task = 2;
    o.extra = {"--account=abc"};
    const std::string array = sbatch_array_script(o);
    for (const std::string line :
         {"#!/bin/bash\n", "\n#SBATCH --job-name=cb-ci\n", "\n#SBATCH --array=5-8%2\n", "\n#SBATCH --ntasks=1\n",
          "\n#SBATCH --cpus-per-task=2\n", "\n#SBATCH --hint=nomultithread\n", "\n#SBATCH --exclusive\n",
          "\n#SBATCH --mem=2G\n", "\n#SBATCH --partition=short\n", "\n#SBATCH --time=00:30:00\n",
          "\n#SBATCH --account=abc\n", "\n#SBATCH --output=/scratch/u/ci/slurm/%x-%A_%a.out\n",
          "\nexport OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1\n",
          "\nsrun --ntasks=1 --cpus-per-task=2 --cpu-bind=cores '/opt/cb/bin/contactbench' run "
          "'/home/u/suites/ci.json' --out "
          "'/scratch/u/ci'\n"})
        EXPECT_NE(array.find(line), std::string::npos) << line << "\nnot in\n" << array;
    // Every #SBATCH line comes before the first command (sbatch stops reading them there).
    EXPECT_LT(array.rfind("#SBATCH"), array.find("\nset -euo pipefail"));

    const std::string merge = sbatch_merge_script(o);
    EXPECT_NE(merge.find("\n#SBATCH --job-name=cb-ci-merge\n"), std::string::npos) << merge;
    EXPECT_EQ(merge.find("--array"), std::string::npos) << merge;
    EXPECT_EQ(merge.find("--exclusive"), std::string::npos) << merge;
    EXPECT_NE(merge.find("\n'/opt/cb/bin/contactbench' merge '/scratch/u/ci' \\\n    '/scratch/u/ci/shard-1-of-4' \\\n"
                         "    '/scratch/u/ci/shard-2-of-4' \\\n    '/scratch/u/ci/shard-3-of-4' \\\n"
                         "    '/scratch/u/ci/shard-4-of-4'\n"),
              std::string::npos)
        << merge;
    EXPECT_EQ(shell_quote("it's"), "'it'\\''s'");
}

namespace {

/// The message of the InputError both script functions throw for `o`, or "no error".
std::string sbatch_error(const SbatchOptions& o)
{
    std::string array_error = "no error", merge_error = "no error";
    try {
        sbatch_array_script(o);
    } catch (const InputError& e) {
        array_error = e.what();
    }
    try {
        sbatch_merge_script(o);
    } catch (const InputError& e) {
        merge_error = e.what();
    }
    EXPECT_EQ(array_error, merge_error);
    return array_error;
}

SbatchOptions plain_options()
{
    SbatchOptions o;
    o.contactbench = "/opt/cb/bin/contactbench";
    o.suite = "/home/u/suites/ci.json";
    o.suite_name = "ci";
    o.out = "/scratch/u/ci";
    o.shards = 4;
    return o;
}

}  // namespace

TEST(SlurmSbatch, LineBreaksInEmbeddedValuesAreRefused)
{
    // Issue 27: a newline in the suite path ended the comment line and ran the next line on the cluster.
    SbatchOptions o = plain_options();
    o.suite = "/home/u/x\ntouch /tmp/pwned\n.json";
    EXPECT_EQ(sbatch_error(o),
              "cluster: suite: holds the control character 0x0a, which a generated sbatch file cannot carry safely");
    o = plain_options();
    o.contactbench = "/opt/cb\r/contactbench";
    EXPECT_EQ(sbatch_error(o), "cluster: contactbench binary: holds the control character 0x0d, which a generated "
                               "sbatch file cannot carry safely");
    o = plain_options();
    o.suite_name = "ci\nrm -rf ~";
    EXPECT_EQ(
        sbatch_error(o),
        "cluster: suite name: holds the control character 0x0a, which a generated sbatch file cannot carry safely");
    o = plain_options();
    o.extra = {"--comment=a\x1b[2Jb"};
    EXPECT_EQ(sbatch_error(o), "cluster: --sbatch-option: holds the control character 0x1b, which a generated "
                               "sbatch file cannot carry safely");
    o = plain_options();
    o.out = "/scratch/u/a b";
    EXPECT_EQ(sbatch_error(o), "cluster: --out: '/scratch/u/a b' holds a space, quote, backslash or %, which "
                               "#SBATCH lines cannot carry");
    // Shell metacharacters that stay on their line are quoted, and the job name keeps only safe characters.
    o = plain_options();
    o.suite = "/home/u/$(touch x);`id` 'q'.json";
    o.suite_name = "ci $(id)";
    const std::string array = sbatch_array_script(o);
    EXPECT_NE(array.find(" run '/home/u/$(touch x);`id` '\\''q'\\''.json' --out "), std::string::npos) << array;
    EXPECT_NE(array.find("\n#SBATCH --job-name=cb-ci___id_\n"), std::string::npos) << array;
}

TEST(SlurmSbatch, ShardsAndIndicesAreBounded)
{
    SbatchOptions o = plain_options();
    o.shards = 1000000000;  // issue 27: ran on with a growing memory footprint
    EXPECT_EQ(sbatch_error(o), "cluster: --shards: must be in 1..10000, got 1000000000");
    o.shards = 0;
    EXPECT_EQ(sbatch_error(o), "cluster: --shards: must be in 1..10000, got 0");
    o.shards = 4;
    o.first_index = 3999998;  // 3999998..4000001 passes Slurm's last index
    EXPECT_EQ(sbatch_error(o), "cluster: --first-index: must be in 0..3999997 for 4 shards (Slurm array indices end "
                               "at 4000000), got 3999998");
    o.first_index = 3999997;
    EXPECT_NE(sbatch_array_script(o).find("\n#SBATCH --array=3999997-4000000\n"), std::string::npos);
}

TEST(TimingHygiene, MixedCpuModelsWarn)
{
    const nlohmann::json a = {{"status", "converged"}, {"provenance", {{"cpu", "Xeon A"}}}};
    const nlohmann::json b = {{"status", "max_iterations"}, {"provenance", {{"cpu", "EPYC B"}}}};
    const nlohmann::json failed = {{"status", "invalid_input"}, {"provenance", {{"cpu", "Other C"}}}};
    EXPECT_EQ(mixed_cpu_warning(cpu_models_of_timed_runs({a, a, failed})), "");
    const auto models = cpu_models_of_timed_runs({a, b, a, failed});
    ASSERT_EQ(models.size(), 2u);
    EXPECT_EQ(models.at("Xeon A"), 2u);
    EXPECT_EQ(
        mixed_cpu_warning(models),
        "timed runs come from 2 CPU models, so their times do not compare (counters do): 'EPYC B' (1 runs); "
        "'Xeon A' (2 runs). Pin the partition (cluster slurm --partition, or --sbatch-option=--constraint=...) to "
        "time on one model.");
}
