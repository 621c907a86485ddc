#pragma once
/// Which jobs of a suite `contactbench run` does (harness/cmd_run.cpp): the jobs of this shard,
/// the identity each result depends on, why each stored result cannot be reused, and so which
/// jobs run (a chain's label runs whole unless every one of its runs is reusable).
#include "harness/runner.hpp"
#include "harness/suite.hpp"

#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <vector>

namespace cb {

/// Shard i of N (1-based).
struct Shard {
    long index = 1, count = 1;
};

/// "i/N" with 1 <= i <= N; InputError on anything else.
Shard parse_shard(const std::string& text);

/// The jobs of one suite (or shard) in one results folder. Job (s, v): snapshot s, solver label v.
class RunPlan {
public:
    RunPlan(const Suite& suite, std::vector<SuiteSnapshot> snapshots, Shard shard, std::string out);

    const Suite& suite() const { return m_suite; }
    const std::vector<SuiteSnapshot>& snapshots() const { return m_snapshots; }
    size_t labels() const { return m_suite.solvers.size(); }
    const Shard& shard() const { return m_shard; }

    /// Job j (snapshot-major, j = s * labels + v; label v in a chain) is in shard i iff
    /// j % N == i-1, and a job whose solver does not apply to the snapshot is none.
    bool in_shard(size_t s, size_t v) const;
    /// DIR/runs/<id>__<label>.json
    std::string run_path(size_t s, size_t v) const;
    /// The run file names of this shard's jobs.
    std::set<std::string> job_files() const;
    /// The suite's defaults of every solver's settings (its tol and time limit; a solver's own wins).
    SettingDefaults defaults() const;
    /// The settings label v runs with: the suite's entry with the defaults added
    /// (settings_with_defaults, the runner's rule); recorded in the run's identity.
    nlohmann::json settings_of(size_t v) const;
    /// What a job's result depends on (runner.hpp run_identity); needs hash_snapshots().
    nlohmann::json identity_of(size_t s, size_t v) const;
    /// The content hash of every snapshot this shard needs (null when it cannot be read: its runs
    /// fail on loading and are retried next time).
    void hash_snapshots();
    const nlohmann::json& hash(size_t s) const { return m_hashes[s]; }
    /// Why each stored run cannot be reused ("" = reusable; "missing" = not run yet).
    void find_stale();
    const std::string& stale(size_t s, size_t v) const { return m_stale[s][v]; }
    /// Which jobs run: `force` all, chains whole per label, others when stale. Counts the jobs.
    void choose(bool force);
    bool todo(size_t s, size_t v) const { return m_todo[s][v]; }
    bool any_todo() const;
    bool any_todo(size_t s) const;
    size_t total() const { return m_total; }
    const std::vector<std::vector<bool>>& todo_table() const { return m_todo; }

private:
    const Suite& m_suite;
    std::vector<SuiteSnapshot> m_snapshots;
    Shard m_shard;
    std::string m_out;
    nlohmann::json m_options_entry;
    std::vector<nlohmann::json> m_hashes;
    std::vector<std::vector<std::string>> m_stale;
    std::vector<std::vector<bool>> m_todo;
    size_t m_total = 0;
};

}  // namespace cb
