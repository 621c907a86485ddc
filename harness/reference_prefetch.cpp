#include "harness/reference_prefetch.hpp"

#include "harness/length_scale.hpp"
#include "harness/process_pool.hpp"
#include "harness/reference.hpp"
#include "problems/qpsnap.hpp"

#include <stdexcept>

namespace cb {

namespace {

void prefetch_snapshot(const SuiteSnapshot& snap, const Suite& suite)
{
    try {
        // The reference is the ORIGINAL QP's (docs/accuracy.md), whatever a solver keeps of it,
        // solved with the scale the runs will use (a problem without geometry: its own reference
        // extent, harness/length_scale.hpp, which computes and caches the reference first).
        Qp qp = read_qpsnap(snap.path);
        const std::string key = qpsnap_content_hash(snap.path);
        fix_length_scale(qp, snap.path, key, GivenLength{suite.length_scale, suite.length_scale_source});
        reference_solution(qp, key);
    } catch (const InputError&) {
        // the runs of this snapshot fail with the message
    }
}

}  // namespace

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
        prefetch_snapshot(snapshots[s], suite);
        pool.job_done();
    }
    if (const size_t failed = pool.wait_all())
        throw std::runtime_error(std::to_string(failed) + " reference computation(s) failed");
    return handled;
}

}  // namespace cb
