#pragma once
/// The table `contactbench run` ends with (issue 46): one line per solver label with the runs
/// solved at tol, the count of each status and the shifted geometric mean of the run times.
#include <nlohmann/json.hpp>

#include <ostream>
#include <string>
#include <vector>

namespace cb {

/// The table of the run records given. Solved: status `converged` (e <= tol on the original QP)
/// of the runs judged (all but not_applicable). Time: the run's total (setup + solve); a run not
/// solved counts at `penalty_s` (the suite's time limit; the largest time seen when <= 0); the
/// shift is 10% of the median time of the solved runs (plots/profiles.py's rule), printed.
std::string run_summary_table(const std::vector<nlohmann::json>& runs, double penalty_s);

/// The end of `run`: this table of DIR/runs/*.json, then the HTML report (html_report.hpp).
void print_run_end(const std::string& dir, double time_limit_s, std::ostream& out);

}  // namespace cb
