// The summary table at the end of `run`: see run_summary_table.hpp.
#include "harness/run_summary_table.hpp"

#include "harness/html_report.hpp"
#include "harness/results.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>

namespace cb {

namespace {

struct LabelRow {
    size_t runs = 0, judged = 0, solved = 0;
    std::map<std::string, size_t> statuses;
    std::vector<double> times;  // total time of each judged run; NaN when not solved
};

double total_time(const nlohmann::json& run)
{
    const nlohmann::json& t = run.value("time", nlohmann::json::object());
    const auto it = t.find("total_s");
    return it != t.end() && it->is_number() ? it->get<double>() : NAN;
}

std::string text(const char* format, double v)
{
    char buffer[48];
    std::snprintf(buffer, sizeof buffer, format, v);
    return buffer;
}

}  // namespace

std::string run_summary_table(const std::vector<nlohmann::json>& runs, double penalty_s)
{
    std::vector<std::string> order;
    std::map<std::string, LabelRow> rows;
    std::vector<double> solved_times;
    double largest = 0.0;
    for (const nlohmann::json& run : runs) {
        const std::string label = run.value("label", run.value("solver", std::string("?")));
        if (!rows.count(label)) order.push_back(label);
        LabelRow& row = rows[label];
        const std::string status = run.value("status", std::string("?"));
        ++row.runs;
        ++row.statuses[status];
        if (status == "not_applicable") continue;  // n/a: neither a success nor a failure
        ++row.judged;
        const double t = total_time(run);
        if (std::isfinite(t)) largest = std::max(largest, t);
        const bool solved = status == "converged" && std::isfinite(t);
        row.solved += solved ? 1 : 0;
        row.times.push_back(solved ? t : NAN);
        if (solved) solved_times.push_back(t);
    }
    const double penalty = penalty_s > 0 ? penalty_s : largest;
    double shift = 1e-6;
    if (!solved_times.empty()) {
        std::sort(solved_times.begin(), solved_times.end());
        const size_t k = solved_times.size();
        const double median = k % 2 ? solved_times[k / 2] : 0.5 * (solved_times[k / 2 - 1] + solved_times[k / 2]);
        if (median > 0) shift = 0.1 * median;
    }
    size_t width = 5;
    for (const std::string& label : order) width = std::max(width, label.size());
    std::string out = "summary: solved = status converged (e <= tol on the original QP) of the runs judged (n/a left "
                      "out);\n         sgm = shifted geometric mean of setup + solve time, unsolved runs at " +
                      text("%.3g", penalty) + " s, shift " + text("%.3g", shift) + " s\n";
    out += "  " + std::string("label") + std::string(width - 5, ' ') + "  solved      sgm [s]  statuses\n";
    for (const std::string& label : order) {
        const LabelRow& row = rows[label];
        std::string statuses;
        for (const auto& [status, count] : row.statuses)
            statuses += (statuses.empty() ? "" : ", ") + status + " " + std::to_string(count);
        double log_sum = 0.0;
        for (double t : row.times) log_sum += std::log((std::isfinite(t) ? t : penalty) + shift);
        const std::string sgm =
            row.times.empty() ? "-" : text("%.3g", std::exp(log_sum / double(row.times.size())) - shift);
        std::string solved = std::to_string(row.solved) + "/" + std::to_string(row.judged);
        out += "  " + label + std::string(width - label.size(), ' ') + "  " + solved +
               std::string(solved.size() < 8 ? 8 - solved.size() : 0, ' ') +
               std::string(11 - std::min<size_t>(11, sgm.size()), ' ') + sgm + "  " + statuses + "\n";
    }
    return out;
}

void print_run_end(const std::string& dir, double time_limit_s, std::ostream& out)
{
    try {
        std::vector<nlohmann::json> runs = read_runs(dir);
        // The suite's order of labels (file names sort "mprgp-box" before "mprgp").
        std::map<std::string, size_t> order;
        nlohmann::json suite = nlohmann::json::object();
        try {
            suite = read_json_file(dir + "/suite.json");
        } catch (const std::exception&) {  // no suite.json: the runs' own order
        }
        for (const nlohmann::json& sv : suite.value("solvers", nlohmann::json::array()))
            if (sv.is_object() && sv.contains("label") && sv["label"].is_string())
                order.emplace(sv["label"].get<std::string>(), order.size());
            else if (sv.is_string())
                order.emplace(sv.get<std::string>(), order.size());
        auto rank = [&](const nlohmann::json& run) {
            const auto it = order.find(run.value("label", std::string()));
            return it == order.end() ? order.size() : it->second;
        };
        std::stable_sort(runs.begin(), runs.end(),
                         [&](const nlohmann::json& a, const nlohmann::json& b) { return rank(a) < rank(b); });
        out << run_summary_table(runs, time_limit_s);
    } catch (const std::exception& e) {  // the runs are written; a table that cannot be made is only noted
        out << "summary: not shown: " << e.what() << "\n";
    }
    report_at_end(dir, out);
}

}  // namespace cb
