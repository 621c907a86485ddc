#pragma once
/// `run --jobs N` with "reference": true: the reference solutions (active-set F*, untimed work)
/// are computed N snapshots at a time before the runs, into the reference cache the runs then
/// read, so that a timed suite's runs, which go one at a time, no longer wait for them.
#include "harness/suite.hpp"

#include <string>
#include <vector>

namespace cb {

/// Computes (or finds cached) the references of every snapshot s with a job to do (todo[s][v]
/// for some label v), one child process per snapshot, `jobs` at a time. Returns the number of
/// snapshots handled; throws std::runtime_error when a child failed. Bad snapshots and bad
/// solver settings are skipped here: the runs report them.
size_t prefetch_references(const Suite& suite, const std::vector<SuiteSnapshot>& snapshots,
                           const std::vector<std::vector<bool>>& todo, long jobs);

}  // namespace cb
