#include "harness/results.hpp"

#include "harness/record_schema.hpp"
#include "problems/io_util.hpp"
#include "solvers/core/types.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <unistd.h>

namespace cb {

namespace fs = std::filesystem;

void write_json_atomic(const std::string& path, const nlohmann::json& value)
{
    // nlohmann writes NaN/Inf as null; replace invalid UTF-8 rather than throwing.
    write_file_atomic(path, value.dump(1, ' ', false, nlohmann::json::error_handler_t::replace) + "\n");
}

nlohmann::json read_json_file(const std::string& path)
{
    // A regular file only (a FIFO would block), nesting bounded (deep JSON would overflow the stack).
    return read_json_checked(path);
}

std::string run_file_name(const std::string& snapshot_id, const std::string& label)
{
    return snapshot_id + "__" + label + ".json";
}

std::vector<nlohmann::json> read_runs(const std::string& dir)
{
    std::vector<std::string> files;
    const fs::path runs = fs::path(dir) / "runs";
    if (fs::is_directory(runs))
        for (const auto& entry : fs::directory_iterator(runs))
            if (entry.is_regular_file() && entry.path().extension() == ".json") files.push_back(entry.path().string());
    std::sort(files.begin(), files.end());
    std::vector<nlohmann::json> out;
    for (const auto& f : files) {
        nlohmann::json run = read_json_file(f);
        run["_file"] = fs::path(f).filename().string();
        out.push_back(std::move(run));
    }
    return out;
}

const std::vector<std::string>& summary_columns()
{
    static const std::vector<std::string> columns = {"suite",
                                                     "snapshot",
                                                     "label",
                                                     "solver",
                                                     "status",
                                                     "solver_status",
                                                     "criterion",
                                                     "status_confirmed",
                                                     "iterations",
                                                     "a_products",
                                                     "work",
                                                     "cholmod_factorizations",
                                                     "accuracy",
                                                     "stationarity",
                                                     "primal",
                                                     "dual",
                                                     "complementarity",
                                                     "gap",
                                                     "accuracy_solved",
                                                     "m_solved",
                                                     "objective",
                                                     "energy_gap",
                                                     "violation",
                                                     "native_residual",
                                                     "nonfinite",
                                                     "monotone",
                                                     "setup_s",
                                                     "solve_s",
                                                     "time_s",
                                                     "peak_rss_mb",
                                                     "n",
                                                     "m",
                                                     "tol",
                                                     "length_scale",
                                                     "length_scale_source",
                                                     "fclib_error",
                                                     "solved_problem",
                                                     "mu_min",
                                                     "mu_max"};
    return columns;
}

namespace {

std::string csv_escape(const std::string& s)
{
    if (s.find_first_of(",\"\n") == std::string::npos) return s;
    std::string out = "\"";
    for (char ch : s) {
        if (ch == '"') out += '"';
        out += ch;
    }
    return out + "\"";
}

std::string cell(const nlohmann::json& v)
{
    if (v.is_null()) return "";
    if (v.is_boolean()) return v.get<bool>() ? "true" : "false";
    if (v.is_number_integer() || v.is_number_unsigned()) return v.dump();
    if (v.is_number_float()) {
        const double d = v.get<double>();
        if (!std::isfinite(d)) return "";
        char buffer[40];
        std::snprintf(buffer, sizeof(buffer), "%.17g", d);
        return buffer;
    }
    if (v.is_string()) return csv_escape(v.get<std::string>());
    return csv_escape(v.dump());
}

const nlohmann::json& at(const nlohmann::json& j, std::initializer_list<const char*> path)
{
    static const nlohmann::json null_value;
    const nlohmann::json* p = &j;
    for (const char* key : path) {
        if (!p->is_object() || !p->contains(key)) return null_value;
        p = &(*p)[key];
    }
    return *p;
}

}  // namespace

std::string summary_row(const nlohmann::json& run, const std::string& suite_name)
{
    // Run files of an older version use an old name (harness/record_schema.hpp, read with a notice).
    const nlohmann::json& accuracy = accuracy_object(run, run.value("_file", std::string("run record")));
    auto part = [&](const char* name) -> const nlohmann::json& { return at(accuracy, {name}); };
    const std::vector<nlohmann::json> values = {
        suite_name,
        at(run, {"snapshot", "id"}),
        at(run, {"label"}),
        at(run, {"solver"}),
        at(run, {"status"}),
        at(run, {"solver_status"}),
        at(run, {"criterion"}),
        at(run, {"status_confirmed"}),
        at(run, {"iterations"}),
        at(run, {"counters", "a_products"}),
        at(run, {"counters", "work"}),
        at(run, {"counters", "cholmod_factorizations"}),
        part("max"),
        part("stationarity"),
        part("primal"),
        part("dual"),
        part("complementarity"),
        part("gap"),
        run.contains("accuracy_solved") ? at(run, {"accuracy_solved", "max"}) : part("max"),
        run.contains("m_solved") ? at(run, {"m_solved"}) : at(run, {"snapshot", "m"}),
        at(run, {"objective"}),
        at(run, {"energy_gap"}),
        at(run, {"violation"}),
        at(run, {"native_residual"}),
        at(run, {"nonfinite"}),
        at(run, {"monotone"}),
        at(run, {"time", "setup_s"}),
        at(run, {"time", "solve_s"}),
        at(run, {"time", "total_s"}),
        at(run, {"memory", "peak_rss_mb"}),
        at(run, {"snapshot", "n"}),
        at(run, {"snapshot", "m"}),
        at(run, {"tol"}),
        at(run, {"length_scale"}),
        at(run, {"length_scale_source"}),
        // Friction (issue 48): empty for a frictionless run; solved_problem also names other relaxations.
        at(run, {"fclib_error"}),
        at(run, {"solved_problem"}),
        at(run, {"friction", "mu_min"}),
        at(run, {"friction", "mu_max"}),
    };
    std::string line;
    for (size_t i = 0; i < values.size(); ++i) line += (i ? "," : "") + cell(values[i]);
    return line;
}

std::string summary_csv(const std::vector<nlohmann::json>& runs, const std::string& suite_name)
{
    std::string text;
    for (size_t i = 0; i < summary_columns().size(); ++i) text += (i ? "," : "") + summary_columns()[i];
    text += "\n";
    for (const auto& run : runs) text += summary_row(run, suite_name) + "\n";
    return text;
}

size_t write_summary(const std::string& dir, const std::string& suite_name)
{
    const auto runs = read_runs(dir);
    write_file_atomic((fs::path(dir) / "summary.csv").string(), summary_csv(runs, suite_name));
    return runs.size();
}

}  // namespace cb
