#include "harness/slurm.hpp"

#include "solvers/core/types.hpp"  // throw_input_error

#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <unistd.h>

namespace cb {

namespace {

const char* const VARIABLES[] = {"SLURM_ARRAY_TASK_ID",  "SLURM_ARRAY_TASK_COUNT", "SLURM_ARRAY_TASK_MIN",
                                 "SLURM_ARRAY_TASK_MAX", "SLURM_ARRAY_JOB_ID",     "SLURM_JOB_ID",
                                 "SLURMD_NODENAME",      "SLURM_JOB_PARTITION",    "SLURM_CPUS_ON_NODE",
                                 "SLURM_CPU_BIND"};

/// The integer value of `name`, or nullopt when it is not set; InputError when it is not an integer.
std::optional<long> integer_variable(const Environment& env, const std::string& name)
{
    const auto it = env.find(name);
    if (it == env.end()) return std::nullopt;
    const std::string& text = it->second;
    char* end = nullptr;
    errno = 0;
    const long value = std::strtol(text.c_str(), &end, 10);
    if (text.empty() || *end != '\0' || errno == ERANGE)
        throw_input_error("run", name, "expected an integer, got '" + text + "'");
    return value;
}

long required_integer(const Environment& env, const std::string& name)
{
    const std::optional<long> value = integer_variable(env, name);
    if (!value) throw_input_error("run", name, "not set, but SLURM_ARRAY_TASK_ID is (an array task needs both)");
    return *value;
}

std::string host_name()
{
    char host[256] = {0};
    return ::gethostname(host, sizeof(host) - 1) == 0 ? std::string(host) : std::string("unknown");
}

/// A newline would end a comment or #SBATCH line and start a command; other control characters
/// (carriage return, escape) hide text on a terminal or confuse sbatch's parser.
void refuse_control_characters(const std::string& field, const std::string& value)
{
    for (const char c : value) {
        const auto byte = static_cast<unsigned char>(c);
        if (byte < 0x20 || byte == 0x7f) {
            char code[8];
            std::snprintf(code, sizeof(code), "0x%02x", byte);
            throw_input_error("cluster", field,
                              "holds the control character " + std::string(code) +
                                  ", which a generated sbatch file cannot carry safely");
        }
    }
}

/// sbatch reads `#SBATCH --output=PATH` without shell quoting and expands % in it.
void refuse_sbatch_unsafe(const std::string& field, const std::string& value)
{
    refuse_control_characters(field, value);
    for (const char c : value)
        if (c == ' ' || c == '%' || c == '\'' || c == '"' || c == '\\')
            throw_input_error("cluster", field,
                              "'" + value + "' holds a space, quote, backslash or %, which #SBATCH lines cannot carry");
}

/// The suite name as a job name: letters, digits, '.', '_' and '-' kept, anything else '_'.
std::string job_name(const std::string& suite_name)
{
    std::string name;
    for (const char c : suite_name)
        name += (std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '_' || c == '-') ? c : '_';
    return name.substr(0, 100);
}

void sbatch_common(std::ostringstream& s, const SbatchOptions& o)
{
    if (!o.partition.empty()) s << "#SBATCH --partition=" << o.partition << "\n";
    if (!o.time.empty()) s << "#SBATCH --time=" << o.time << "\n";
    for (const auto& line : o.extra) s << "#SBATCH " << line << "\n";
}

}  // namespace

Environment slurm_environment()
{
    Environment env;
    for (const char* name : VARIABLES)
        if (const char* value = std::getenv(name)) env[name] = value;
    return env;
}

std::optional<ArrayShard> shard_from_slurm(const Environment& env)
{
    const std::optional<long> task = integer_variable(env, "SLURM_ARRAY_TASK_ID");
    if (!task) return std::nullopt;
    const long min = required_integer(env, "SLURM_ARRAY_TASK_MIN");
    const std::optional<long> max = integer_variable(env, "SLURM_ARRAY_TASK_MAX");
    const std::optional<long> count = integer_variable(env, "SLURM_ARRAY_TASK_COUNT");
    if (!count && !max)
        throw_input_error("run", "SLURM_ARRAY_TASK_COUNT", "not set and neither is SLURM_ARRAY_TASK_MAX");
    if (max && *max < min)
        throw_input_error("run", "SLURM_ARRAY_TASK_MAX",
                          std::to_string(*max) + " is below SLURM_ARRAY_TASK_MIN " + std::to_string(min));
    const long span = max ? *max - min + 1 : *count;
    if (count && *count < 1)
        throw_input_error("run", "SLURM_ARRAY_TASK_COUNT", "must be >= 1, got " + std::to_string(*count));
    // A stepped or listed array (0-15:4, 1,3,7) has holes: task ids no longer number the shards.
    if (count && *count != span)
        throw_input_error("run", "SLURM_ARRAY_TASK_COUNT",
                          std::to_string(*count) + " tasks over the ids " + std::to_string(min) + ".." +
                              std::to_string(*max) +
                              ": only a contiguous array (e.g. --array=0-3 or 5-8) maps to shards");
    if (*task < min || *task >= min + span)
        throw_input_error("run", "SLURM_ARRAY_TASK_ID",
                          std::to_string(*task) + " is outside the array " + std::to_string(min) + ".." +
                              std::to_string(min + span - 1));
    return ArrayShard{*task - min + 1, span};
}

std::string shard_folder_name(long index, long count)
{
    return "shard-" + std::to_string(index) + "-of-" + std::to_string(count);
}

nlohmann::json slurm_job_provenance(const Environment& env)
{
    const auto job = env.find("SLURM_JOB_ID");
    if (job == env.end()) return nullptr;
    auto get = [&](const char* name) -> nlohmann::json {
        const auto it = env.find(name);
        return it == env.end() ? nlohmann::json() : nlohmann::json(it->second);
    };
    const auto node = env.find("SLURMD_NODENAME");
    return {{"job_id", job->second},
            {"array_job_id", get("SLURM_ARRAY_JOB_ID")},
            {"array_task_id", get("SLURM_ARRAY_TASK_ID")},
            {"node", node == env.end() ? host_name() : node->second},
            {"partition", get("SLURM_JOB_PARTITION")},
            {"cpus_on_node", get("SLURM_CPUS_ON_NODE")},
            {"cpu_bind", get("SLURM_CPU_BIND")}};  // set by srun --cpu-bind where the cluster binds
}

std::string shell_quote(const std::string& word)
{
    std::string quoted = "'";
    for (const char c : word) {
        if (c == '\'')
            quoted += "'\\''";
        else
            quoted += c;
    }
    return quoted + "'";
}

void check_sbatch_options(const SbatchOptions& o)
{
    if (o.shards < 1 || o.shards > MAX_ARRAY_SHARDS)
        throw_input_error("cluster", "--shards",
                          "must be in 1.." + std::to_string(MAX_ARRAY_SHARDS) + ", got " + std::to_string(o.shards));
    if (o.first_index < 0 || o.first_index > MAX_ARRAY_INDEX - o.shards + 1)
        throw_input_error("cluster", "--first-index",
                          "must be in 0.." + std::to_string(MAX_ARRAY_INDEX - o.shards + 1) + " for " +
                              std::to_string(o.shards) + " shards (Slurm array indices end at " +
                              std::to_string(MAX_ARRAY_INDEX) + "), got " + std::to_string(o.first_index));
    if (o.cpus_per_task < 1 || o.cpus_per_task > 100000)
        throw_input_error("cluster", "--cpus-per-task", "must be in 1..100000, got " + std::to_string(o.cpus_per_task));
    if (o.max_parallel < 0 || o.max_parallel > MAX_ARRAY_SHARDS)
        throw_input_error("cluster", "--max-parallel",
                          "must be in 0.." + std::to_string(MAX_ARRAY_SHARDS) + ", got " +
                              std::to_string(o.max_parallel));
    // Shell-quoted words and comment lines: only a line break (or another control character) escapes.
    refuse_control_characters("contactbench binary", o.contactbench);
    refuse_control_characters("suite", o.suite);
    refuse_control_characters("suite name", o.suite_name);
    // Values on #SBATCH lines: sbatch splits them at spaces and expands %.
    refuse_sbatch_unsafe("--out", o.out);
    refuse_sbatch_unsafe("--partition", o.partition);
    refuse_sbatch_unsafe("--time", o.time);
    refuse_sbatch_unsafe("--mem", o.mem);
    for (const auto& line : o.extra) {
        refuse_control_characters("--sbatch-option", line);
        if (line.rfind("--", 0) != 0)
            throw_input_error("cluster", "--sbatch-option",
                              "expected one option such as --account=abc, got '" + line + "'");
    }
}

std::string sbatch_array_script(const SbatchOptions& o)
{
    check_sbatch_options(o);
    std::ostringstream s;
    s << "#!/bin/bash\n"
      << "# Written by `contactbench cluster slurm`: one array task per shard of the suite\n"
      << "# " << o.suite << "; task i writes " << o.out << "/shard-<i>-of-" << o.shards << ".\n"
      << "# Submit it first: jobid=$(sbatch --parsable " << shell_quote(o.out + "/slurm/array.sbatch") << ")\n"
      << "#SBATCH --job-name=cb-" << job_name(o.suite_name) << "\n"
      << "#SBATCH --array=" << o.first_index << "-" << o.first_index + o.shards - 1;
    if (o.max_parallel > 0) s << "%" << o.max_parallel;
    s << "\n"
      << "#SBATCH --ntasks=1\n"
      << "#SBATCH --cpus-per-task=" << o.cpus_per_task
      << "\n"
      // Timing hygiene: whole cores (no hyperthread sibling shared with another job).
      << "#SBATCH --hint=nomultithread\n";
    if (o.exclusive) s << "#SBATCH --exclusive\n";
    if (!o.mem.empty()) s << "#SBATCH --mem=" << o.mem << "\n";
    sbatch_common(s, o);
    s << "#SBATCH --output=" << o.out << "/slurm/%x-%A_%a.out\n"
      << "set -euo pipefail\n"
      << "# One BLAS thread: CHOLMOD's results, and so the counters, do not depend on the core count.\n"
      << "export OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1\n"
      << "# `run` reads its shard from SLURM_ARRAY_TASK_ID/MIN/COUNT and records job, node, CPU and load.\n"
      // --cpus-per-task again: srun 22.05 does not inherit it from the batch allocation.
      << "srun --ntasks=1 --cpus-per-task=" << o.cpus_per_task << " --cpu-bind=cores " << shell_quote(o.contactbench)
      << " run " << shell_quote(o.suite) << " --out " << shell_quote(o.out) << "\n";
    return s.str();
}

std::string sbatch_merge_script(const SbatchOptions& o)
{
    check_sbatch_options(o);
    std::ostringstream s;
    s << "#!/bin/bash\n"
      << "# Written by `contactbench cluster slurm`: joins the " << o.shards << " shards of " << o.suite << "\n"
      << "# into " << o.out << "/summary.csv once the array has succeeded:\n"
      << "#   sbatch --dependency=afterok:$jobid " << shell_quote(o.out + "/slurm/merge.sbatch") << "\n"
      << "#SBATCH --job-name=cb-" << job_name(o.suite_name) << "-merge\n"
      << "#SBATCH --ntasks=1\n"
      << "#SBATCH --cpus-per-task=1\n";
    sbatch_common(s, o);
    s << "#SBATCH --output=" << o.out << "/slurm/%x-%j.out\n"
      << "set -euo pipefail\n"
      << shell_quote(o.contactbench) << " merge " << shell_quote(o.out);
    for (long i = 1; i <= o.shards; ++i) s << " \\\n    " << shell_quote(o.out + "/" + shard_folder_name(i, o.shards));
    s << "\n";
    return s.str();
}

}  // namespace cb
