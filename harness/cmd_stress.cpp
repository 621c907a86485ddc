// `contactbench stress`: every solver x every stress case, a stability table (harness/stress.hpp).
#include "harness/cli.hpp"
#include "harness/commands.hpp"
#include "harness/html_report.hpp"
#include "harness/stress.hpp"
#include "problems/output_folder.hpp"

#include <iostream>
#include <sstream>

namespace cb {

namespace {

const char* const STRESS_USAGE =
    "contactbench stress [--out DIR] [--time-limit S] [--tol T] [--solvers a,b] [--cases x,y] [--quick] "
    "[--no-isolate] [--list]";

std::vector<std::string> split_list(const std::string& text)
{
    std::vector<std::string> out;
    std::stringstream s(text);
    std::string item;
    while (std::getline(s, item, ','))
        if (!item.empty()) out.push_back(item);
    return out;
}

}  // namespace

int cmd_stress(const Args& args)
{
    const CommandLine cl("stress", args, {"--out", "--time-limit", "--tol", "--solvers", "--cases"},
                         {"--quick", "--no-isolate", "--list"});
    if (cl.help()) {
        std::cout
            << "usage: " << STRESS_USAGE << "\n\n"
            << "Runs every registered solver plus cg:precond=ichol and mprgp:precond=ichol (or --solvers;\n"
            << "a solver may carry settings: NAME:key=value[:key=value...]) on every stress case (or --cases: ids or\n"
            << "families) with a time limit per run (default 5 s), each run in a child process so that\n"
            << "a crash or hang is recorded. Writes DIR/stability.csv, DIR/stability.md and\n"
            << "DIR/runs/<case>__<solver>.json (default DIR: results/stress). --quick: 4 cases.\n"
            << "--list prints the cases. The stiff families (stiffness, stiff-slab, stiff-dino) keep their\n"
            << "histories in runs/ for the error-against-time figure of `python3 -m plots.stability DIR`.\n";
        return 0;
    }
    cl.expect_positional(0, 0, STRESS_USAGE);
    StressOptions options;
    options.quick = cl.has("--quick");
    if (cl.has("--list")) {
        for (const StressCase& c : stress_cases(options.quick))
            std::cout << c.id << "\t" << c.family << "\tseverity " << c.severity << "\t" << c.description << "\n";
        return 0;
    }
    options.out_dir = cl.path("--out", "results/stress");
    if (!options.out_dir.empty()) {  // checked before the first case, not after it (problems/output_folder.hpp)
        make_output_subfolder(options.out_dir, "runs");
        for (const char* file : {"/stability.csv", "/stability.md"}) check_output_entry(options.out_dir + file);
    }
    options.time_limit_s = cl.number("--time-limit", 5.0);
    if (!(options.time_limit_s > 0)) throw_input_error("stress", "--time-limit", "must be > 0");
    options.tol = cl.number("--tol", 1e-6);
    if (!(options.tol > 0)) throw_input_error("stress", "--tol", "must be > 0");
    options.solvers = split_list(cl.value("--solvers"));
    options.cases = split_list(cl.value("--cases"));
    options.isolate = !cl.has("--no-isolate");
    options.progress = &std::cerr;
    const StressReport report = run_stress(options);
    long wrong = 0;
    for (const StressRow& r : report.rows) wrong += r.honest() ? 0 : 1;
    std::cout << "stress: " << report.rows.size() << " runs in " << report.wall_s << " s; " << wrong
              << " wrong statuses; wrote " << options.out_dir << "/stability.csv and stability.md\n";
    report_at_end(options.out_dir, std::cout);
    return 0;
}

}  // namespace cb
