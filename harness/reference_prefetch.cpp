#include "harness/reference_prefetch.hpp"

#include "harness/process_pool.hpp"
#include "harness/reference.hpp"
#include "problems/qpsnap.hpp"
#include "solvers/decouple.hpp"
#include "solvers/registry.hpp"

#include <map>
#include <stdexcept>

namespace cb {

namespace {

/// The rows a solver keeps of `qp` under the suite's decoupling, as run_solver decides it;
/// false when it sees the whole QP.
bool decoupled_rows(const Qp& qp, const Suite& suite, const SuiteSolver& sv, DecoupleOrder& order,
                    std::vector<int>& kept)
{
    bool want = false;
    order = DecoupleOrder::AUTHORS;
    if (suite.decouple == "auto") {
        nlohmann::json settings = sv.settings;
        if (!settings.contains("tol")) settings["tol"] = suite.tol;
        if (!settings.contains("time_limit_s")) settings["time_limit_s"] = suite.time_limit_s;
        want = builtin_registry().create(sv.solver, settings)->requires_decoupled() && qp.m() > 0 &&
               !is_decoupled(qp.J);
    } else if (suite.decouple != "none") {
        order = decouple_order_from_string(suite.decouple);
        want = qp.m() > 0;
    }
    if (!want) return false;
    const DecoupleReport report = decouple_rows(qp.view(), qp.contacts, order, suite.decouple_seed);
    if (report.already_decoupled || static_cast<long>(report.kept_rows.size()) >= qp.m()) return false;
    kept = report.kept_rows;
    return true;
}

void prefetch_snapshot(const Suite& suite, const SuiteSnapshot& snap, const std::vector<bool>& todo)
{
    Qp qp;
    std::string hash;
    try {
        qp = read_qpsnap(snap.path);
        hash = qpsnap_content_hash(snap.path);
    } catch (const InputError&) {
        return;  // the runs of this snapshot fail with the message
    }
    std::map<std::string, std::vector<int>> keys;  // key -> kept rows (empty: all)
    for (size_t v = 0; v < suite.solvers.size(); ++v) {
        if (!todo[v]) continue;
        const SuiteSolver& sv = suite.solvers[v];
        if (!builtin_registry().contains(sv.solver)) continue;
        try {
            DecoupleOrder order = DecoupleOrder::AUTHORS;
            std::vector<int> kept;
            const bool decoupled = decoupled_rows(qp, suite, sv, order, kept);
            keys[reference_cache_key(hash, decoupled, to_string(order), suite.decouple_seed)] = kept;
        } catch (const InputError&) {
            // bad settings: the run reports them
        }
    }
    for (const auto& [key, kept] : keys) {
        if (kept.empty()) reference_solution(qp, key);
        else reference_solution(select_rows(qp, kept), key);
    }
}

} // namespace

std::string reference_cache_key(const std::string& content_hash, bool decoupled, const std::string& order,
                                std::uint64_t seed)
{
    return decoupled ? content_hash + "-" + order + "-" + nlohmann::json(seed).dump() : content_hash;
}

size_t prefetch_references(const Suite& suite, const std::vector<SuiteSnapshot>& snapshots,
                           const std::vector<std::vector<bool>>& todo, long jobs)
{
    ProcessPool pool(jobs);
    size_t handled = 0;
    for (size_t s = 0; s < snapshots.size(); ++s) {
        bool any = false;
        for (const bool t : todo[s]) any = any || t;
        if (!any) continue;
        ++handled;
        if (pool.delegate()) continue;  // a child computes this snapshot's references
        prefetch_snapshot(suite, snapshots[s], todo[s]);
        pool.job_done();
    }
    if (const size_t failed = pool.wait_all())
        throw std::runtime_error(std::to_string(failed) + " reference computation(s) failed");
    return handled;
}

} // namespace cb
