#pragma once
/// Slurm glue: a job array task's shard from Slurm's environment variables, the job's facts
/// for provenance, and the sbatch files of `contactbench cluster slurm` (an array of shards
/// plus a merge job that depends on it).
#include <nlohmann/json.hpp>

#include <map>
#include <optional>
#include <string>
#include <vector>

namespace cb {

/// Environment variables by name (only those that are set).
using Environment = std::map<std::string, std::string>;

/// The SLURM_* and host variables this file reads, from the process environment.
Environment slurm_environment();

/// A shard as `run --shard i/N` takes it: 1-based index of count.
struct ArrayShard {
    long index = 1;
    long count = 1;
};

/// The shard of a Slurm array task, or nullopt when SLURM_ARRAY_TASK_ID is not set.
/// Arrays may start at any index (--array=0-3 or 5-8): index = TASK_ID - TASK_MIN + 1, count =
/// TASK_COUNT (or TASK_MAX - TASK_MIN + 1 when COUNT is absent). Only contiguous arrays map to
/// shards (a step such as 0-15:4 or a list such as 1,3,7 is refused). Throws InputError naming
/// the variable that is missing, not an integer, or inconsistent.
std::optional<ArrayShard> shard_from_slurm(const Environment& env);

/// The folder name of shard i of N inside a run's --out folder: "shard-<i>-of-<N>".
std::string shard_folder_name(long index, long count);

/// Facts of the Slurm job this process runs in, for provenance: job_id, array_job_id,
/// array_task_id, node (SLURMD_NODENAME, else the host name), partition, cpus_on_node, cpu_bind; null
/// when SLURM_JOB_ID is not set.
nlohmann::json slurm_job_provenance(const Environment& env);

/// At most this many array tasks: the merge job names every shard on its command line, and Slurm's
/// default MaxArraySize is 1001 (a larger array needs a site that raised it).
constexpr long MAX_ARRAY_SHARDS = 10000;

/// Highest array index Slurm accepts (MaxArraySize is at most 4000001).
constexpr long MAX_ARRAY_INDEX = 4000000;

/// What `contactbench cluster slurm` writes.
struct SbatchOptions {
    std::string contactbench;        ///< absolute path of the binary the jobs run
    std::string suite;               ///< absolute path of the suite file
    std::string suite_name;          ///< for job names
    std::string out;                 ///< absolute results folder (shared between the nodes)
    long shards = 1;                 ///< array tasks, one shard each
    long first_index = 0;            ///< the array runs first_index .. first_index + shards - 1
    std::string partition;           ///< empty: the cluster's default
    std::string time;                ///< per task, e.g. 01:00:00; empty: the partition's default
    std::string mem;                 ///< per task, e.g. 4G; empty: the partition's default
    long cpus_per_task = 1;          ///< cores per task (solvers are single-threaded)
    bool exclusive = false;          ///< whole nodes per task: no neighbour disturbs the clock
    long max_parallel = 0;           ///< array throttle (%K); 0: no limit
    std::vector<std::string> extra;  ///< further #SBATCH options, written as given
};

/// Throws InputError("cluster: FIELD: ...") when a value the sbatch files embed could leave its
/// line or its word: a control character (newline, carriage return, tab, escape ...) anywhere, a
/// space, quote or % in a value written on an #SBATCH line, shards or indices out of range.
/// Both script functions call it first, so no script is ever built from such a value.
void check_sbatch_options(const SbatchOptions& options);

/// The sbatch file of the job array: each task runs `contactbench run SUITE --out OUT` pinned
/// to its cores (srun --cpu-bind=cores, one thread per core, one BLAS thread); `run` finds its
/// shard in the array variables and writes OUT/shard-<i>-of-<N>.
std::string sbatch_array_script(const SbatchOptions& options);

/// The sbatch file of the merge job: `contactbench merge OUT OUT/shard-1-of-N ... OUT/shard-N-of-N`.
std::string sbatch_merge_script(const SbatchOptions& options);

/// Shell-quotes a word with single quotes.
std::string shell_quote(const std::string& word);

}  // namespace cb
