#include "harness/compare.hpp"

#include "harness/results.hpp"
#include "solvers/types.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <sstream>

namespace cb {

namespace {

using Key = std::pair<std::string, std::string>;

Key key_of(const nlohmann::json& run)
{
    std::string snapshot, label;
    if (run.contains("snapshot") && run["snapshot"].is_object()) snapshot = run["snapshot"].value("id", "");
    label = run.value("label", run.value("solver", ""));
    return {snapshot, label};
}

/// A counter of a run: "iterations" is the top-level count, the others live in "counters".
nlohmann::json counter(const nlohmann::json& run, const std::string& name)
{
    if (name == "iterations" && run.contains("iterations")) return run["iterations"];
    if (run.contains("counters") && run["counters"].is_object() && run["counters"].contains(name))
        return run["counters"][name];
    return nullptr;
}

nlohmann::json kkt_rel(const nlohmann::json& run)
{
    if (run.contains("kkt_relative") && run["kkt_relative"].is_object() && run["kkt_relative"].contains("max"))
        return run["kkt_relative"]["max"];
    return nullptr;
}

double total_time(const nlohmann::json& run)
{
    if (run.contains("time") && run["time"].is_object()) {
        const auto& t = run["time"];
        if (t.contains("total_s") && t["total_s"].is_number()) return t["total_s"].get<double>();
    }
    return 0.0;
}

std::string format_g(double v, int digits = 2)
{
    char buffer[40];
    std::snprintf(buffer, sizeof(buffer), "%.*g", digits, v);
    return buffer;
}

std::string value_text(const nlohmann::json& v)
{
    if (v.is_null()) return "-";
    if (v.is_number_float()) return format_g(v.get<double>());
    return v.is_string() ? v.get<std::string>() : v.dump();
}

std::string change_text(const nlohmann::json& b, const nlohmann::json& n)
{
    if (b == n) return value_text(b);
    std::string text = value_text(b) + " -> " + value_text(n);
    if (b.is_number() && n.is_number() && b.get<double>() != 0.0) {
        const double pct = 100.0 * (n.get<double>() - b.get<double>()) / std::abs(b.get<double>());
        text += " (" + std::string(pct >= 0 ? "+" : "") + format_g(pct, 3) + "%)";
    }
    return text;
}

} // namespace

const std::vector<std::string>& compared_counters()
{
    static const std::vector<std::string> names = {"iterations", "a_products", "cholmod_factorizations",
                                                   "precond_applications"};
    return names;
}

CompareReport compare_runs(const std::vector<nlohmann::json>& base, const std::vector<nlohmann::json>& next,
                           const CompareOptions& options)
{
    std::map<Key, const nlohmann::json*> base_by_key, new_by_key;
    for (const auto& r : base) base_by_key[key_of(r)] = &r;
    for (const auto& r : next) new_by_key[key_of(r)] = &r;
    CompareReport report;
    for (const auto& [key, b] : base_by_key) {
        CompareRow row;
        row.snapshot = key.first;
        row.label = key.second;
        row.base_status = b->value("status", "");
        const auto it = new_by_key.find(key);
        for (const auto& c : compared_counters()) row.base[c] = counter(*b, c);
        row.base["kkt_rel"] = kkt_rel(*b);
        row.base["total_s"] = total_time(*b);
        if (it == new_by_key.end()) {
            row.verdict = "missing";
            ++report.missing;
            report.rows.push_back(std::move(row));
            continue;
        }
        const nlohmann::json& n = *it->second;
        row.new_status = n.value("status", "");
        for (const auto& c : compared_counters()) row.next[c] = counter(n, c);
        row.next["kkt_rel"] = kkt_rel(n);
        row.next["total_s"] = total_time(n);
        for (const auto& c : compared_counters()) {
            const auto& bv = row.base[c];
            const auto& nv = row.next[c];
            if (!bv.is_number() || !nv.is_number()) {
                if (bv != nv) row.regressed.push_back(c);  // a counter appeared or vanished
                continue;
            }
            if (nv.get<double>() > bv.get<double>()) row.regressed.push_back(c);
            else if (nv.get<double>() < bv.get<double>()) row.improved.push_back(c);
        }
        const double tol = n.value("tol", b->value("tol", 0.0));
        const auto& bk = row.base["kkt_rel"];
        const auto& nk = row.next["kkt_rel"];
        if (nk.is_number() && bk.is_number()) {
            const double bkv = bk.get<double>(), nkv = nk.get<double>();
            if (nkv > bkv * (1.0 + options.kkt_rtol) && nkv > tol) row.regressed.push_back("kkt_rel");
            else if (nkv * (1.0 + options.kkt_rtol) < bkv && bkv > tol) row.improved.push_back("kkt_rel");
        } else if (bk.is_number() && !nk.is_number()) {
            row.regressed.push_back("kkt_rel");  // NaN or absent now
        }
        const double bt = row.base["total_s"].get<double>(), nt = row.next["total_s"].get<double>();
        if (bt > 0.0) {
            row.time_ratio = nt / bt;
            row.time_ratio_min = row.time_ratio_max = row.time_ratio;
            const auto& bs = (*b)["time"].value("samples_total_s", nlohmann::json::array());
            const auto& ns = n["time"].value("samples_total_s", nlohmann::json::array());
            if (bs.size() > 1 || ns.size() > 1) {
                // Spread: the extreme ratios of NEW's samples against BASE's median and vice versa.
                const double bmin = (*b)["time"].value("min_total_s", bt), bmax = (*b)["time"].value("max_total_s", bt);
                const double nmin = n["time"].value("min_total_s", nt), nmax = n["time"].value("max_total_s", nt);
                if (bmax > 0.0 && bmin > 0.0) {
                    row.time_ratio_min = nmin / bmax;
                    row.time_ratio_max = nmax / bmin;
                }
            }
        }
        if (row.new_status != row.base_status) {
            row.verdict = "status-changed";
            ++report.status_changed;
        } else if (!row.regressed.empty()) {
            row.verdict = "regressed";
            ++report.regressed;
        } else if (!row.improved.empty()) {
            row.verdict = "improved";
            ++report.improved;
        } else {
            row.verdict = "equal";
            ++report.equal;
        }
        report.rows.push_back(std::move(row));
    }
    for (const auto& [key, n] : new_by_key) {
        if (base_by_key.count(key)) continue;
        CompareRow row;
        row.snapshot = key.first;
        row.label = key.second;
        row.new_status = n->value("status", "");
        row.verdict = "new";
        ++report.added;
        report.rows.push_back(std::move(row));
    }
    return report;
}

CompareReport compare_folders(const std::string& base_dir, const std::string& new_dir, const CompareOptions& options)
{
    if (!std::filesystem::is_directory(base_dir)) throw_input_error(base_dir, "", "no such results folder");
    if (!std::filesystem::is_directory(new_dir)) throw_input_error(new_dir, "", "no such results folder");
    const auto base = read_runs(base_dir);
    if (base.empty()) throw_input_error(base_dir, "runs/", "no run files (*.json) to compare against");
    const auto next = read_runs(new_dir);
    return compare_runs(base, next, options);
}

std::string CompareReport::table() const
{
    std::vector<std::vector<std::string>> cells;
    cells.push_back({"snapshot", "label", "status", "iterations", "a_products", "factorizations", "precond",
                     "kkt_rel", "time new/base", "verdict"});
    for (const auto& r : rows) {
        std::vector<std::string> line = {r.snapshot, r.label};
        if (r.verdict == "missing") {
            line.push_back(r.base_status + " -> (missing)");
            for (int i = 0; i < 6; ++i) line.push_back("");
            line.push_back("FAIL missing in NEW");
            cells.push_back(line);
            continue;
        }
        if (r.verdict == "new") {
            line.push_back("(new) " + r.new_status);
            for (int i = 0; i < 6; ++i) line.push_back("");
            line.push_back("new (not judged)");
            cells.push_back(line);
            continue;
        }
        line.push_back(r.base_status == r.new_status ? r.new_status : r.base_status + " -> " + r.new_status);
        for (const auto& c : compared_counters()) line.push_back(change_text(r.base[c], r.next[c]));
        line.push_back(change_text(r.base["kkt_rel"], r.next["kkt_rel"]));
        std::string time = r.time_ratio > 0.0 ? format_g(r.time_ratio, 3) + "x" : "-";
        if (r.time_ratio_min != r.time_ratio_max)
            time += " [" + format_g(r.time_ratio_min, 3) + ".." + format_g(r.time_ratio_max, 3) + "]";
        line.push_back(time);
        std::string verdict;
        if (r.verdict == "status-changed") verdict = "FAIL status changed";
        else if (r.verdict == "regressed") verdict = "FAIL regressed:";
        else if (r.verdict == "improved") verdict = "improved:";
        else verdict = "equal";
        if (r.verdict == "regressed" || r.verdict == "status-changed")
            for (const auto& q : r.regressed) verdict += " " + q;
        if (r.verdict == "improved")
            for (const auto& q : r.improved) verdict += " " + q;
        line.push_back(verdict);
        cells.push_back(line);
    }
    std::vector<size_t> width(cells[0].size(), 0);
    for (const auto& line : cells)
        for (size_t i = 0; i < line.size(); ++i) width[i] = std::max(width[i], line[i].size());
    std::ostringstream out;
    for (const auto& line : cells) {
        std::string text;
        for (size_t i = 0; i < line.size(); ++i) {
            text += line[i];
            if (i + 1 < line.size()) text += std::string(width[i] - line[i].size() + 2, ' ');
        }
        while (!text.empty() && text.back() == ' ') text.pop_back();
        out << text << "\n";
    }
    return out.str();
}

std::string CompareReport::verdict() const
{
    const long judged = equal + improved + regressed + status_changed + missing;
    std::ostringstream out;
    out << "verdict: " << (failed() ? "FAIL" : "PASS") << " (" << judged << " runs compared: " << equal << " equal, "
        << improved << " improved, " << regressed << " regressed, " << status_changed << " status changed, " << missing
        << " missing in NEW; " << added << " new)";
    return out.str();
}

nlohmann::json CompareReport::to_json() const
{
    nlohmann::json rows_json = nlohmann::json::array();
    for (const auto& r : rows)
        rows_json.push_back({{"snapshot", r.snapshot}, {"label", r.label}, {"base_status", r.base_status},
                             {"new_status", r.new_status}, {"verdict", r.verdict}, {"regressed", r.regressed},
                             {"improved", r.improved}, {"base", r.base}, {"new", r.next},
                             {"time_ratio", r.time_ratio}, {"time_ratio_min", r.time_ratio_min},
                             {"time_ratio_max", r.time_ratio_max}});
    return {{"failed", failed()}, {"equal", equal}, {"improved", improved}, {"regressed", regressed},
            {"status_changed", status_changed}, {"missing", missing}, {"new", added},
            {"verdict", verdict()}, {"rows", rows_json}};
}

} // namespace cb
