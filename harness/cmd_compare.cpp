// `contactbench compare BASE NEW`: the regression judge (harness/compare.hpp) between two results
// folders or compact performance records. Exit 0 pass, 3 regression, 2 bad input, 1 internal error.
#include "harness/cli.hpp"
#include "harness/commands.hpp"
#include "harness/compare.hpp"
#include "harness/results.hpp"

#include <iostream>

namespace cb {

namespace {

/// Exit status of a comparison that found a regression (2 and 1 are bad input and internal error).
constexpr int REGRESSION = 3;

}  // namespace

int cmd_compare(const Args& args)
{
    const char* const usage =
        "contactbench compare BASE NEW [--only-changes] [--filter REGEX] [--accuracy-rtol 0.1]\n"
        "                     [--instructions-rtol 0.03] [--time-ratio 1.5] [--cross-machine] [--json FILE]";
    const CommandLine cl("compare", args,
                         {"--accuracy-rtol", "--kkt-rtol", "--instructions-rtol", "--time-ratio", "--filter", "--json"},
                         {"--only-changes", "--cross-machine"});
    if (cl.help()) {
        std::cout << "usage: " << usage
                  << "\n\nBASE and NEW are results folders (runs/*.json) or compact performance records (.csv,\n"
                     "with the machine fingerprint NAME-machine.json beside them; tools/perf_gate.py writes\n"
                     "them). Every (snapshot, label) run of BASE is judged against NEW:\n"
                     "  status                     any change fails; a run missing in NEW fails\n"
                     "  work counters              iterations, a_products, a_products_harness (products counted\n"
                     "                             by the harness), cholmod_factorizations, precond_applications:\n"
                     "                             exact on the same machine (growth fails)\n"
                     "  accuracy                   the error e (docs/accuracy.md): fails when NEW > BASE *\n"
                     "                             (1 + accuracy-rtol) and above tol\n"
                     "  instructions               executed in the solve: fails beyond +instructions-rtol\n"
                     "  time                       NEW/BASE of the minimum times with a noise band (the sum of\n"
                     "                             both sides' median/min - 1): fails when NEW/BASE >\n"
                     "                             --time-ratio x (1 + band) (0: never judged; never on one sample)\n"
                     "When both machines are known and differ (or --cross-machine), counters may grow by 25% + 2\n"
                     "and instructions and time are shown, not judged. --only-changes prints the rows that\n"
                     "differ; --filter keeps the runs whose \"snapshot/label\" matches REGEX (e.g. '/mprgp$').\n"
                     "Exit status: 0 pass, 3 regression, 2 bad input, 1 internal error.\n";
        return 0;
    }
    cl.expect_positional(2, 2, usage);
    CompareOptions options;
    // --kkt-rtol: the option's old name, accepted for one release (harness/record_schema.hpp).
    const char* accuracy_flag = cl.has("--accuracy-rtol") || !cl.has("--kkt-rtol") ? "--accuracy-rtol" : "--kkt-rtol";
    if (std::string(accuracy_flag) == "--kkt-rtol")
        std::cerr << "notice: compare: read the old option '--kkt-rtol' as '--accuracy-rtol' (accepted until the "
                     "next release)\n";
    options.accuracy_rtol = cl.number(accuracy_flag, options.accuracy_rtol);
    if (!(options.accuracy_rtol >= 0.0)) throw_input_error("compare", accuracy_flag, "must be >= 0");
    options.instructions_rtol = cl.number("--instructions-rtol", options.instructions_rtol);
    if (!(options.instructions_rtol >= 0.0)) throw_input_error("compare", "--instructions-rtol", "must be >= 0");
    options.time_ratio_max = cl.number("--time-ratio", options.time_ratio_max);
    if (!(options.time_ratio_max == 0.0 || options.time_ratio_max >= 1.0))
        throw_input_error("compare", "--time-ratio", "must be 0 (not judged) or >= 1");
    options.cross_machine = cl.has("--cross-machine");
    const std::string base_path = cl.positional()[0], new_path = cl.positional()[1];
    const CompareInput base = read_compare_input(base_path);
    if (base.runs.empty()) throw_input_error(base_path, "runs/", "no run files (*.json) to compare against");
    const CompareInput next = read_compare_input(new_path);
    const CompareReport report = compare_inputs(base, next, options, cl.value("--filter"));
    std::cout << report.header() << "\n" << report.table(cl.has("--only-changes")) << "\n" << report.verdict() << "\n";
    if (cl.has("--json")) write_json_atomic(cl.path("--json"), report.to_json());
    return report.failed() ? REGRESSION : 0;
}

}  // namespace cb
