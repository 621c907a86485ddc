#include "harness/timing_hygiene.hpp"

namespace cb {

std::map<std::string, size_t> cpu_models_of_timed_runs(const std::vector<nlohmann::json>& runs)
{
    std::map<std::string, size_t> models;
    for (const auto& run : runs) {
        const std::string status = run.value("status", std::string());
        if (status == "invalid_input" || status == "internal_error") continue;  // no solver ran: no time
        std::string cpu = "unknown";
        if (run.contains("provenance") && run["provenance"].is_object())
            cpu = run["provenance"].value("cpu", std::string("unknown"));
        ++models[cpu];
    }
    return models;
}

std::string mixed_cpu_warning(const std::map<std::string, size_t>& models)
{
    if (models.size() < 2) return "";
    std::string text = "timed runs come from " + std::to_string(models.size()) +
                       " CPU models, so their times do not compare (counters do):";
    for (const auto& [model, count] : models) text += " '" + model + "' (" + std::to_string(count) + " runs);";
    text.pop_back();
    return text +
           ". Pin the partition (cluster slurm --partition, or --sbatch-option=--constraint=...) to time on one model.";
}

}  // namespace cb
