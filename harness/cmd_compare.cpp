// `contactbench compare BASE NEW [--kkt-rtol 0.1] [--json FILE]`: the regression judge
// (harness/compare.hpp). Exit 1 on any regression, status change or missing run, 0 clean.
#include "harness/cli.hpp"
#include "harness/commands.hpp"
#include "harness/compare.hpp"
#include "harness/results.hpp"

#include <iostream>

namespace cb {

int cmd_compare(const Args& args)
{
    const char* const usage = "contactbench compare BASE NEW [--kkt-rtol 0.1] [--json FILE]";
    const CommandLine cl("compare", args, {"--kkt-rtol", "--json"}, {});
    if (cl.help()) {
        std::cout << "usage: " << usage
                  << "\n\nCompares every (snapshot, label) run of BASE/runs with NEW/runs: the counters iterations,\n"
                     "a_products, cholmod_factorizations, precond_applications exactly (lower is better),\n"
                     "kkt_rel (regressed when NEW > BASE * (1 + kkt-rtol) and above tol), the status\n"
                     "(any change fails) and the time ratio NEW/BASE (reported only). A run missing in NEW\n"
                     "fails. Exit status 1 on any failure, 0 clean, 2 bad input.\n";
        return 0;
    }
    cl.expect_positional(2, 2, usage);
    CompareOptions options;
    options.kkt_rtol = cl.number("--kkt-rtol", 0.1);
    if (!(options.kkt_rtol >= 0.0)) throw_input_error("compare", "--kkt-rtol", "must be >= 0");
    const CompareReport report = compare_folders(cl.positional()[0], cl.positional()[1], options);
    std::cout << report.table() << "\n" << report.verdict() << "\n";
    if (cl.has("--json")) write_json_atomic(cl.value("--json"), report.to_json());
    return report.failed() ? 1 : 0;
}

} // namespace cb
