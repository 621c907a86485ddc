#pragma once
/// The HTML report of a results folder (issue 46): OUT/report/index.html, written by
/// plots/html_report.py with Debian's /usr/bin/python3 (argv, never a shell line). `contactbench
/// report OUT` runs it; `run` and `stress` run it at their end.
#include <ostream>
#include <string>

namespace cb {

struct HtmlReportOutcome {
    bool written = false;
    int exit_status = 1;  ///< the command's: 0 written, 2 the folder is refused, 1 Python or a package missing
    std::string path;     ///< OUT/report/index.html when written
    std::string message;  ///< why not, and how to write it (python3 and plots/ found? which package?)
};

/// The checkout whose plots/html_report.py is used: $CB_PLOTS_ROOT, else the source folder this
/// binary was built from, else the current folder; "" when none holds it.
std::string plots_root();

/// Runs /usr/bin/python3 -m plots.html_report FOLDER from plots_root().
HtmlReportOutcome write_html_report(const std::string& folder);

/// The end of `run` and `stress`: writes the report and prints "report: PATH (open it in a
/// browser)", or why it was not written and the command that writes it; never throws. CB_REPORT=0
/// in the environment leaves it out (a note says so).
void report_at_end(const std::string& folder, std::ostream& out);

}  // namespace cb
