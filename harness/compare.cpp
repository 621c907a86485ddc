#include "harness/compare.hpp"

#include "harness/perf_record.hpp"
#include "harness/record_schema.hpp"
#include "harness/record_types.hpp"
#include "harness/results.hpp"
#include "harness/results_folder.hpp"
#include "solvers/core/types.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <regex>
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

/// The accuracy error e of a run (docs/accuracy.md); old names read through harness/record_schema.hpp.
nlohmann::json accuracy_of(const nlohmann::json& run, const std::string& source) { return accuracy_max(run, source); }

nlohmann::json instructions(const nlohmann::json& run)
{
    return run.contains("instructions") && run["instructions"].is_number() ? run["instructions"] : nlohmann::json();
}

/// Wall time of a run: the minimum over its samples and the relative spread median/min - 1
/// (-1 when there is a single sample: no noise estimate, so never judged).
struct TimeStats {
    double min = 0.0, noise = -1.0;
};

TimeStats time_stats(const nlohmann::json& run)
{
    TimeStats stats;
    if (!run.contains("time") || !run["time"].is_object()) return stats;
    const auto& t = run["time"];
    if (t.contains("samples_total_s") && t["samples_total_s"].is_array() && t["samples_total_s"].size() > 1) {
        std::vector<double> samples;
        for (const auto& v : t["samples_total_s"]) samples.push_back(v.get<double>());  // check_record_types
        std::sort(samples.begin(), samples.end());
        const size_t mid = samples.size() / 2;
        const double median = samples.size() % 2 ? samples[mid] : 0.5 * (samples[mid - 1] + samples[mid]);
        stats.min = samples.front();
        if (stats.min > 0.0) stats.noise = median / stats.min - 1.0;
        return stats;
    }
    if (t.contains("min_total_s") && t["min_total_s"].is_number()) {  // a compact record
        stats.min = t["min_total_s"].get<double>();
        if (t.contains("noise") && t["noise"].is_number() && t.contains("samples") && t["samples"].is_number() &&
            t["samples"].get<double>() > 1)
            stats.noise = t["noise"].get<double>();
        return stats;
    }
    if (t.contains("total_s") && t["total_s"].is_number()) stats.min = t["total_s"].get<double>();
    return stats;
}

std::string format_g(double v, int digits = 2)
{
    char buffer[40];
    std::snprintf(buffer, sizeof(buffer), "%.*g", digits, v);
    return buffer;
}

std::string format_fixed(double v, int decimals)
{
    char buffer[40];
    std::snprintf(buffer, sizeof(buffer), "%.*f", decimals, v);
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

/// "2.413M +0.000%": BASE's count and NEW's relative change (three decimals: unchanged code
/// must read +0.000%).
std::string instructions_text(const nlohmann::json& b, const nlohmann::json& n)
{
    auto count = [](const nlohmann::json& v) {
        if (!v.is_number()) return std::string("-");
        const double x = v.get<double>();
        if (x >= 1e9) return format_fixed(x / 1e9, 3) + "G";
        if (x >= 1e6) return format_fixed(x / 1e6, 3) + "M";
        if (x >= 1e3) return format_fixed(x / 1e3, 3) + "k";
        return format_g(x, 6);
    };
    if (!b.is_number() || !n.is_number()) return b.is_null() && n.is_null() ? "-" : count(b) + " -> " + count(n);
    const double bv = b.get<double>(), nv = n.get<double>();
    if (bv == 0.0) return count(b) + " -> " + count(n);
    const double pct = 100.0 * (nv - bv) / bv;
    return count(b) + " " + (pct >= 0 ? "+" : "") + format_fixed(pct, 3) + "%";
}

/// NaN compares false both ways, so a NaN counter would pass as "equal": refused instead (the
/// types were checked by check_record_types).
void require_finite(const std::string& source, const Key& key, const nlohmann::json& run)
{
    std::vector<std::pair<std::string, nlohmann::json>> values = {{"accuracy", accuracy_of(run, source)}};
    for (const auto& c : compared_counters()) values.emplace_back(c, counter(run, c));
    for (const auto& [name, value] : values)
        if (value.is_number_float() && !std::isfinite(value.get<double>()))
            throw_input_error(source, key.first + "/" + key.second + ": " + name,
                              "not a finite number (NaN or infinite): it cannot be judged");
}

/// A compact BASE that lacks a quantity NEW records would let NEW pass unjudged on it.
[[noreturn]] void unjudged(const std::string& source, const Key& key, const std::string& name)
{
    throw_input_error(source, key.first + "/" + key.second + ": " + name,
                      "not recorded in BASE but recorded in NEW, so it would not be judged (a baseline must record "
                      "every judged quantity: regenerate it)");
}

bool is_results_folder(const std::string& path)
{
    std::error_code ec;  // a link loop is no folder; read_compare_input names it
    return std::filesystem::is_directory(path, ec);
}

nlohmann::json folder_machine(const std::string& dir, const std::vector<nlohmann::json>& runs)
{
    const std::filesystem::path provenance = std::filesystem::path(dir) / "provenance.json";
    std::error_code ec;  // present but a FIFO or a link loop: read_json_file names it
    if (std::filesystem::exists(std::filesystem::symlink_status(provenance, ec)))
        return machine_fingerprint(read_json_file(provenance.string()));
    for (const auto& r : runs)
        if (r.contains("provenance") && r["provenance"].is_object()) return machine_fingerprint(r["provenance"]);
    return nlohmann::json::object();
}

bool machine_known(const nlohmann::json& m)
{
    if (!m.is_object() || m.empty()) return false;
    for (const auto& item : m.items())
        if (item.value() != "unknown") return true;
    return false;
}

}  // namespace

const std::vector<std::string>& compared_counters()
{
    // work: A-product equivalents with factorisations and triangular solves (docs/work.md)
    static const std::vector<std::string> names = {
        "iterations", "a_products", "a_products_harness", "cholmod_factorizations", "precond_applications", "work"};
    return names;
}

bool CompareRow::changed() const
{
    if (verdict != "equal") return true;
    for (const auto& c : compared_counters())
        if (base.value(c, nlohmann::json()) != next.value(c, nlohmann::json())) return true;
    return base.value("instructions", nlohmann::json()) != next.value("instructions", nlohmann::json());
}

CompareInput read_compare_input(const std::string& path)
{
    CompareInput input;
    input.source = path;
    if (is_results_folder(path)) {
        input.runs = read_finished_runs(path);  // complete, final, one record per job
        input.machine = folder_machine(path, input.runs);
        return input;
    }
    std::error_code ec;
    if (!std::filesystem::exists(std::filesystem::symlink_status(path, ec)))
        throw_input_error(path, "", "no such results folder or performance record (.csv)");
    if (std::filesystem::path(path).extension() != ".csv")
        throw_input_error(path, "", "expected a results folder or a performance record (.csv)");
    input.runs = read_perf_record(path);
    input.compact = true;
    const std::string machine_file = machine_file_for(path);
    if (std::filesystem::is_regular_file(machine_file)) {
        const nlohmann::json machine = read_json_file(machine_file);
        if (!machine.is_object())
            throw_input_error(machine_file, "", "expected a JSON object (the machine fingerprint)");
        input.machine = machine_fingerprint(machine);
    }
    return input;
}

CompareReport compare_runs(const std::vector<nlohmann::json>& base, const std::vector<nlohmann::json>& next,
                           const CompareOptions& options)
{
    CompareInput b, n;
    b.runs = base;
    n.runs = next;
    return compare_inputs(b, n, options);
}

CompareReport compare_inputs(const CompareInput& base_input, const CompareInput& next_input,
                             const CompareOptions& options, const std::string& filter)
{
    std::map<Key, const nlohmann::json*> base_by_key, new_by_key;
    std::regex pattern;
    try {
        pattern = std::regex(filter, std::regex::ECMAScript);
    } catch (const std::regex_error& e) {
        throw_input_error("compare", "--filter", "not a regular expression: '" + filter + "' (" + e.what() + ")");
    }
    auto selected = [&](const Key& key) {
        return filter.empty() || std::regex_search(key.first + "/" + key.second, pattern);
    };
    for (const auto& r : base_input.runs) check_record_types(r, base_input.source);
    for (const auto& r : next_input.runs) check_record_types(r, next_input.source);
    for (const auto& r : base_input.runs)
        if (selected(key_of(r))) base_by_key[key_of(r)] = &r;
    for (const auto& r : next_input.runs)
        if (selected(key_of(r))) new_by_key[key_of(r)] = &r;

    CompareReport report;
    report.options = options;
    report.base_source = base_input.source;
    report.new_source = next_input.source;
    report.base_machine = base_input.machine;
    report.new_machine = next_input.machine;
    report.cross_machine =
        options.cross_machine || (machine_known(base_input.machine) && machine_known(next_input.machine) &&
                                  base_input.machine != next_input.machine);
    const bool exact = !report.cross_machine;

    for (const auto& [key, b] : base_by_key) {
        CompareRow row;
        row.snapshot = key.first;
        row.label = key.second;
        row.base_status = b->value("status", "");
        const auto it = new_by_key.find(key);
        for (const auto& c : compared_counters()) row.base[c] = counter(*b, c);
        row.base["accuracy"] = accuracy_of(*b, base_input.source);
        row.base["instructions"] = instructions(*b);
        const TimeStats bt = time_stats(*b);
        row.base["time_min_s"] = bt.min;
        if (it == new_by_key.end()) {
            row.verdict = "missing";
            ++report.missing;
            report.rows.push_back(std::move(row));
            continue;
        }
        const nlohmann::json& n = *it->second;
        require_finite(base_input.source, key, *b);
        require_finite(next_input.source, key, n);
        row.new_status = n.value("status", "");
        for (const auto& c : compared_counters()) row.next[c] = counter(n, c);
        row.next["accuracy"] = accuracy_of(n, next_input.source);
        row.next["instructions"] = instructions(n);
        const TimeStats nt = time_stats(n);
        row.next["time_min_s"] = nt.min;

        // An external program's work is not counted (null): shown, never judged on either side.
        const bool uncounted = !b->value("work_counted", true) || !n.value("work_counted", true);
        for (const auto& c : compared_counters()) {
            const auto& bv = row.base[c];
            const auto& nv = row.next[c];
            if (uncounted && c != "iterations") continue;
            if (bv.is_null()) {
                if (base_input.compact && nv.is_number()) unjudged(base_input.source, key, c);
                continue;  // not recorded by BASE (an older binary): shown, not judged
            }
            if (!nv.is_number()) {
                row.regressed.push_back(c);  // recorded by BASE, vanished in NEW
                continue;
            }
            const double x = bv.get<double>(), y = nv.get<double>();
            const double allowed =
                exact ? x : x * (1.0 + options.counter_rtol) + static_cast<double>(options.counter_atol);
            const double better =
                exact ? x : (x - static_cast<double>(options.counter_atol)) / (1.0 + options.counter_rtol);
            if (y > allowed)
                row.regressed.push_back(c);
            else if (y < better)
                row.improved.push_back(c);
        }
        if (base_input.compact && row.base["accuracy"].is_null() && row.next["accuracy"].is_number())
            unjudged(base_input.source, key, "accuracy");
        const double tol = n.value("tol", b->value("tol", 0.0));
        const auto& bk = row.base["accuracy"];
        const auto& nk = row.next["accuracy"];
        if (nk.is_number() && bk.is_number()) {
            const double bkv = bk.get<double>(), nkv = nk.get<double>();
            if (nkv > bkv * (1.0 + options.accuracy_rtol) && nkv > tol)
                row.regressed.push_back("accuracy");
            else if (nkv * (1.0 + options.accuracy_rtol) < bkv && bkv > tol)
                row.improved.push_back("accuracy");
        } else if (bk.is_number() && !nk.is_number()) {
            row.regressed.push_back("accuracy");  // NaN or absent now
        }
        const auto& bi = row.base["instructions"];
        const auto& ni = row.next["instructions"];
        if (exact && base_input.compact && bi.is_null() && ni.is_number())
            unjudged(base_input.source, key, "instructions");
        if (exact && bi.is_number() && ni.is_number() && bi.get<double>() > 0.0) {
            const double change = ni.get<double>() / bi.get<double>() - 1.0;
            if (change > options.instructions_rtol)
                row.regressed.push_back("instructions");
            else if (change < -options.instructions_rtol)
                row.improved.push_back("instructions");
        }
        if (bt.min > 0.0 && nt.min > 0.0) {
            row.time_ratio = nt.min / bt.min;
            if (bt.noise >= 0.0 && nt.noise >= 0.0) row.time_band = bt.noise + nt.noise;
            // Beyond the threshold even after discounting the noise: ms-long runs of one binary
            // were seen 1.5x apart with a band of 0.3 on a 2-core machine.
            if (exact && options.time_ratio_max > 0.0 && row.time_band >= 0.0 &&
                row.time_ratio > options.time_ratio_max * (1.0 + row.time_band))
                row.regressed.push_back("time");
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
    const CompareInput base = read_compare_input(base_dir);
    if (base.runs.empty()) throw_input_error(base_dir, "runs/", "no run files (*.json) to compare against");
    const CompareInput next = read_compare_input(new_dir);
    return compare_inputs(base, next, options);
}

std::string CompareReport::header() const
{
    std::ostringstream out;
    const bool same = !cross_machine;
    out << "BASE  " << (base_source.empty() ? "(records)" : base_source) << "  measured on "
        << describe_machine(base_machine) << "\n";
    out << "NEW   " << (new_source.empty() ? "(records)" : new_source) << "  measured on "
        << (same && base_machine == new_machine && machine_known(new_machine) ? "the same machine"
                                                                              : describe_machine(new_machine))
        << "\n";
    if (same) {
        out << "rules (same machine): statuses equal; work counters exact (" << compared_counters().size()
            << " counters, lower is better); instructions in the solve within +"
            << format_g(100.0 * options.instructions_rtol, 3) << "%; accuracy within +"
            << format_g(100.0 * options.accuracy_rtol, 3) << "% above tol; wall time (min of the samples, NEW/BASE "
            << "with its noise band) ";
        if (options.time_ratio_max > 0.0)
            out << "judged beyond " << format_g(options.time_ratio_max, 3) << "x (1 + band)\n";
        else
            out << "shown, not judged\n";
    } else {
        const bool differ = machine_known(base_machine) && machine_known(new_machine) && base_machine != new_machine;
        out << (differ ? "machines DIFFER: " : "") << "across-machines rules"
            << (differ ? "" : " (asked for: the sides may come from different machines)")
            << ": statuses equal; work counters within +" << format_g(100.0 * options.counter_rtol, 3) << "% + "
            << options.counter_atol << "; accuracy within +" << format_g(100.0 * options.accuracy_rtol, 3)
            << "% above tol; instructions and wall time shown, not judged\n";
    }
    return out.str();
}

std::string CompareReport::table(bool only_changes) const
{
    std::vector<std::vector<std::string>> cells;
    cells.push_back({"snapshot", "label", "status", "iterations", "a_products", "a_products_harness", "factorizations",
                     "precond", "accuracy", "instructions", "time new/base", "verdict"});
    const size_t columns = cells[0].size();
    for (const auto& r : rows) {
        if (only_changes && !r.changed()) continue;
        std::vector<std::string> line = {r.snapshot, r.label};
        if (r.verdict == "missing" || r.verdict == "new") {
            line.push_back(r.verdict == "missing" ? r.base_status + " -> (missing)" : "(new) " + r.new_status);
            while (line.size() + 1 < columns) line.push_back("");
            line.push_back(r.verdict == "missing" ? "FAIL missing in NEW" : "new (not judged)");
            cells.push_back(line);
            continue;
        }
        line.push_back(r.base_status == r.new_status ? r.new_status : r.base_status + " -> " + r.new_status);
        for (const auto& c : compared_counters()) line.push_back(change_text(r.base[c], r.next[c]));
        line.push_back(change_text(r.base["accuracy"], r.next["accuracy"]));
        line.push_back(instructions_text(r.base["instructions"], r.next["instructions"]));
        std::string time = r.time_ratio > 0.0 ? format_fixed(r.time_ratio, 2) + "x" : "-";
        if (r.time_ratio > 0.0 && r.time_band >= 0.0) time += " ±" + format_fixed(r.time_band, 2);
        line.push_back(time);
        std::string verdict;
        if (r.verdict == "status-changed")
            verdict = "FAIL status changed";
        else if (r.verdict == "regressed")
            verdict = "FAIL regressed:";
        else if (r.verdict == "improved")
            verdict = "improved:";
        else
            verdict = "equal";
        const bool solver_counted =
            std::find(r.regressed.begin(), r.regressed.end(), "a_products") != r.regressed.end();
        if (r.verdict == "regressed" || r.verdict == "status-changed")
            for (const auto& q : r.regressed)
                verdict += " " + q + (q == "a_products_harness" && !solver_counted ? " (uncounted by the solver)" : "");
        if (r.verdict == "improved")
            for (const auto& q : r.improved) verdict += " " + q;
        line.push_back(verdict);
        cells.push_back(line);
    }
    std::vector<size_t> width(columns, 0);
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
    if (only_changes && cells.size() == 1) out << "(no run changed)\n";
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
        rows_json.push_back({{"snapshot", r.snapshot},
                             {"label", r.label},
                             {"base_status", r.base_status},
                             {"new_status", r.new_status},
                             {"verdict", r.verdict},
                             {"regressed", r.regressed},
                             {"improved", r.improved},
                             {"base", r.base},
                             {"new", r.next},
                             {"time_ratio", r.time_ratio},
                             {"time_band", r.time_band >= 0.0 ? nlohmann::json(r.time_band) : nlohmann::json()}});
    return {{"failed", failed()},
            {"equal", equal},
            {"improved", improved},
            {"regressed", regressed},
            {"status_changed", status_changed},
            {"missing", missing},
            {"new", added},
            {"base", {{"source", base_source}, {"machine", base_machine}}},
            {"next", {{"source", new_source}, {"machine", new_machine}}},
            {"cross_machine", cross_machine},
            {"rules",
             {{"accuracy_rtol", options.accuracy_rtol},
              {"instructions_rtol", options.instructions_rtol},
              {"time_ratio_max", options.time_ratio_max},
              {"counter_rtol", cross_machine ? options.counter_rtol : 0.0},
              {"counter_atol", cross_machine ? options.counter_atol : 0}}},
            {"verdict", verdict()},
            {"rows", rows_json}};
}

}  // namespace cb
