#pragma once
/// Times measured on different CPU models do not compare (counters do): which models the timed
/// runs of a results folder come from, and the warning `merge` prints when there are several.
#include <nlohmann/json.hpp>

#include <map>
#include <string>
#include <vector>

namespace cb {

/// CPU model (provenance "cpu") -> number of timed runs on it. A run is timed when it ran a
/// solver (not invalid_input or internal_error); a run without provenance counts as "unknown".
std::map<std::string, size_t> cpu_models_of_timed_runs(const std::vector<nlohmann::json>& runs);

/// Empty when at most one model; else one line naming each model with its run count.
std::string mixed_cpu_warning(const std::map<std::string, size_t>& models);

}  // namespace cb
