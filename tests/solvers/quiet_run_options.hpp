#pragma once
/// Run options without the per-iteration history (the tests that read only the final result).
#include "harness/runner.hpp"

namespace cb::test {

inline RunOptions quiet_run_options()
{
    RunOptions options;
    options.record_history = false;
    return options;
}

}  // namespace cb::test
