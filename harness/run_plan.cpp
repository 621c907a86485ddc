#include "harness/run_plan.hpp"

#include "harness/results.hpp"
#include "harness/runner.hpp"
#include "problems/qpsnap.hpp"
#include "solvers/core/types.hpp"

#include <cstdlib>
#include <filesystem>

namespace cb {

namespace fs = std::filesystem;

Shard parse_shard(const std::string& text)
{
    Shard s;
    const auto slash = text.find('/');
    char* end = nullptr;
    bool ok = slash != std::string::npos && slash > 0;
    if (ok) {
        // Keep the substrings alive while `end` points into them (ASan: stack-use-after-scope).
        const std::string index_text = text.substr(0, slash), count_text = text.substr(slash + 1);
        s.index = std::strtol(index_text.c_str(), &end, 10);
        ok = *end == '\0';
        s.count = std::strtol(count_text.c_str(), &end, 10);
        ok = ok && *end == '\0' && !count_text.empty();
    }
    if (!ok || s.count < 1 || s.index < 1 || s.index > s.count)
        throw_input_error("run", "--shard", "expected i/N with 1 <= i <= N, got '" + text + "'");
    return s;
}

RunPlan::RunPlan(const Suite& suite, std::vector<SuiteSnapshot> snapshots, Shard shard, std::string out)
    : m_suite(suite), m_snapshots(std::move(snapshots)), m_shard(shard), m_out(std::move(out)),
      m_options_entry({{"tol", suite.tol},
                       {"time_limit_s", suite.time_limit_s},
                       {"repeat", suite.repeat},
                       {"history_max", suite.history_max},
                       {"reference", suite.reference},
                       {"decouple", suite.decouple},
                       {"decouple_seed", suite.decouple_seed},
                       {"chain", suite.chain}}),
      m_hashes(m_snapshots.size()), m_stale(m_snapshots.size(), std::vector<std::string>(labels())),
      m_todo(m_snapshots.size(), std::vector<bool>(labels(), false))
{
    // Only when given, so that the identities of runs without it stay what they were.
    if (suite.length_scale > 0.0)
        m_options_entry["length_scale"] = {{"value", suite.length_scale}, {"source", suite.length_scale_source}};
}

bool RunPlan::in_shard(size_t s, size_t v) const
{
    const size_t key = m_suite.chain ? v : s * labels() + v;
    return static_cast<long>(key % static_cast<size_t>(m_shard.count)) == m_shard.index - 1 &&
           solver_applies(m_suite.solvers[v], m_snapshots[s].id);  // a job that does not apply is none
}

std::string RunPlan::run_path(size_t s, size_t v) const
{
    return (fs::path(m_out) / "runs" / run_file_name(m_snapshots[s].id, m_suite.solvers[v].label)).string();
}

std::set<std::string> RunPlan::job_files() const
{
    std::set<std::string> files;
    for (size_t s = 0; s < m_snapshots.size(); ++s)
        for (size_t v = 0; v < labels(); ++v)
            if (in_shard(s, v)) files.insert(run_file_name(m_snapshots[s].id, m_suite.solvers[v].label));
    return files;
}

SettingDefaults RunPlan::defaults() const
{
    SettingDefaults defaults;
    defaults.tol = m_suite.tol;
    defaults.time_limit_s = m_suite.time_limit_s;
    return defaults;
}

nlohmann::json RunPlan::settings_of(size_t v) const
{
    return settings_with_defaults(m_suite.solvers[v].settings, defaults());
}

nlohmann::json RunPlan::identity_of(size_t s, size_t v) const
{
    const nlohmann::json entry = {{"snapshot", m_snapshots[s].id},
                                  {"path", m_snapshots[s].path},
                                  {"generated", m_snapshots[s].generated},
                                  {"label", m_suite.solvers[v].label},
                                  {"options", m_options_entry}};
    return run_identity(m_hashes[s], m_suite.solvers[v].solver, settings_of(v), entry);
}

void RunPlan::hash_snapshots()
{
    for (size_t s = 0; s < m_snapshots.size(); ++s) {
        bool needed = false;
        for (size_t v = 0; v < labels(); ++v) needed = needed || in_shard(s, v);
        if (!needed) continue;
        try {
            m_hashes[s] = qpsnap_content_hash(m_snapshots[s].path);
        } catch (const InputError&) {
            m_hashes[s] = nullptr;  // the run fails on loading and is retried next time
        }
    }
}

void RunPlan::find_stale()
{
    for (size_t s = 0; s < m_snapshots.size(); ++s)
        for (size_t v = 0; v < labels(); ++v) {
            if (!in_shard(s, v)) continue;
            const std::string path = run_path(s, v);
            if (!fs::exists(fs::symlink_status(path))) {
                m_stale[s][v] = "missing";
                continue;
            }
            try {
                m_stale[s][v] = stale_reason(read_json_file(path), identity_of(s, v));
            } catch (const InputError&) {
                m_stale[s][v] = "the run file is damaged";
            }
        }
}

void RunPlan::choose(bool force)
{
    m_total = 0;
    for (size_t v = 0; v < labels(); ++v) {
        bool chain_complete = true;
        for (size_t s = 0; s < m_snapshots.size(); ++s)
            if (in_shard(s, v) && !m_stale[s][v].empty()) chain_complete = false;
        for (size_t s = 0; s < m_snapshots.size(); ++s) {
            if (!in_shard(s, v)) continue;
            ++m_total;
            m_todo[s][v] = force || (m_suite.chain ? !chain_complete : !m_stale[s][v].empty());
        }
    }
}

bool RunPlan::any_todo(size_t s) const
{
    for (size_t v = 0; v < labels(); ++v)
        if (m_todo[s][v]) return true;
    return false;
}

bool RunPlan::any_todo() const
{
    for (size_t s = 0; s < m_snapshots.size(); ++s)
        if (any_todo(s)) return true;
    return false;
}

}  // namespace cb
