// `contactbench report OUT`: the HTML report of a results or reproduction folder (harness/html_report.hpp).
#include "harness/cli.hpp"
#include "harness/commands.hpp"
#include "harness/html_report.hpp"

#include <filesystem>
#include <iostream>

namespace cb {

int cmd_report(const Args& args)
{
    const char* usage = "contactbench report OUT";
    const CommandLine cl("report", args, {}, {});
    if (cl.help()) {
        std::cout << "usage: " << usage
                  << "\n\nWrites OUT/report/index.html (with d3.min.js, report.js and report.css beside it) for a\n"
                     "results folder (`contactbench run`, `stress`, a ladder) or a reproduction (`make reproduce`):\n"
                     "provenance, a sortable and filterable table of every run, the convergence histories per\n"
                     "snapshot, performance profiles and shifted geometric means, a reproduction's claims. The page\n"
                     "opens from disk with no network. Needs /usr/bin/python3 with numpy, pandas, matplotlib and\n"
                     "Debian's libjs-d3 (`make deps`); runs plots/html_report.py of this checkout (CB_PLOTS_ROOT\n"
                     "names another).\n";
        return 0;
    }
    cl.expect_positional(1, 1, usage);
    const std::string folder = cl.positional()[0];
    std::error_code ec;
    if (!std::filesystem::is_directory(folder, ec)) throw_input_error(folder, "", "not a folder");
    const HtmlReportOutcome r = write_html_report(folder);
    if (!r.written) {
        std::cerr << "contactbench report: " << (r.exit_status == 2 ? "error: " : "") << r.message << "\n";
        return r.exit_status;
    }
    std::cout << r.path << "\n";
    return 0;
}

}  // namespace cb
