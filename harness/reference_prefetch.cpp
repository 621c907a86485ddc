#include "harness/reference_prefetch.hpp"

#include "harness/process_pool.hpp"
#include "harness/reference.hpp"
#include "problems/qpsnap.hpp"

#include <stdexcept>

namespace cb {

namespace {

void prefetch_snapshot(const SuiteSnapshot& snap)
{
    try {
        // The reference is the ORIGINAL QP's (docs/accuracy.md), whatever a solver keeps of it.
        reference_solution(read_qpsnap(snap.path), qpsnap_content_hash(snap.path));
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
        prefetch_snapshot(snapshots[s]);
        pool.job_done();
    }
    if (const size_t failed = pool.wait_all())
        throw std::runtime_error(std::to_string(failed) + " reference computation(s) failed");
    return handled;
}

}  // namespace cb
