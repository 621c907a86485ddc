#pragma once
/// Where a result came from: git commit and dirty flag, build, compiler, CPU, libraries, host.
#include <nlohmann/json.hpp>

namespace cb {

/// {"git_commit","git_dirty","build_type","compiler","cpu","cores","date","eigen","suitesparse",
///  "blas","blas_threads","hostname","load_average"} and, inside a Slurm job, "slurm" (slurm_job_provenance).
/// Computed once per process (the date is the first call's, UTC ISO 8601) except the load
/// average [1, 5, 15 min] from /proc/loadavg, read at every call.
nlohmann::json provenance();

/// The node's load average over 1, 5 and 15 minutes (/proc/loadavg), null when unreadable.
nlohmann::json load_average();

/// The build a result comes from: {"commit": git commit, "binary": FNV-1a hash of the running
/// executable (/proc/self/exe)}. Part of every run's identity: a rebuild redoes the runs.
const nlohmann::json& build_identity();

/// Current UTC time as "YYYY-MM-DDTHH:MM:SSZ".
std::string utc_now_iso();

}  // namespace cb
