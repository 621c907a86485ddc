#include "harness/perf_record.hpp"

#include "harness/record_schema.hpp"
#include "harness/results.hpp"
#include "problems/io_util.hpp"
#include "solvers/core/types.hpp"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

namespace cb {

namespace {

enum class Kind { TEXT, INTEGER, REAL };

const std::map<std::string, Kind>& column_kinds()
{
    static const std::map<std::string, Kind> kinds = {{"snapshot", Kind::TEXT},
                                                      {"label", Kind::TEXT},
                                                      {"status", Kind::TEXT},
                                                      {"iterations", Kind::INTEGER},
                                                      {"a_products", Kind::INTEGER},
                                                      {"a_products_harness", Kind::INTEGER},
                                                      {"cholmod_factorizations", Kind::INTEGER},
                                                      {"precond_applications", Kind::INTEGER},
                                                      {"work", Kind::REAL},
                                                      {"accuracy", Kind::REAL},
                                                      {"tol", Kind::REAL},
                                                      {"instructions", Kind::INTEGER},
                                                      {"time_min_s", Kind::REAL},
                                                      {"time_noise", Kind::REAL},
                                                      {"time_samples", Kind::INTEGER},
                                                      {"work_counted", Kind::INTEGER}};
    return kinds;
}

std::vector<std::string> split_csv_line(const std::string& line)
{
    std::vector<std::string> cells;
    std::string cell;
    std::istringstream in(line);
    while (std::getline(in, cell, ',')) cells.push_back(cell);
    if (!line.empty() && line.back() == ',') cells.emplace_back();
    return cells;
}

nlohmann::json parse_cell(const std::string& text, Kind kind, const std::string& where, const std::string& column)
{
    if (text.empty()) return nullptr;
    if (kind == Kind::TEXT) return text;
    errno = 0;
    char* end = nullptr;
    if (kind == Kind::INTEGER) {
        const long long v = std::strtoll(text.c_str(), &end, 10);
        if (errno || end == text.c_str() || *end != '\0' || v < 0)
            throw_input_error(where, "column " + column, "expected a count (integer >= 0), got '" + text + "'");
        return static_cast<std::int64_t>(v);
    }
    const double v = std::strtod(text.c_str(), &end);
    if (errno || end == text.c_str() || *end != '\0')
        throw_input_error(where, "column " + column, "expected a number, got '" + text + "'");
    if (!std::isfinite(v))  // NaN compares false both ways: a NaN counter would pass as equal
        throw_input_error(where, "column " + column, "expected a finite number, got '" + text + "'");
    return v;
}

}  // namespace

const std::vector<std::string>& perf_record_columns()
{
    static const std::vector<std::string> columns = {"snapshot",
                                                     "label",
                                                     "status",
                                                     "iterations",
                                                     "a_products",
                                                     "a_products_harness",
                                                     "cholmod_factorizations",
                                                     "precond_applications",
                                                     "work",
                                                     "accuracy",
                                                     "tol",
                                                     "instructions",
                                                     "time_min_s",
                                                     "time_noise",
                                                     "time_samples",
                                                     "work_counted"};
    return columns;
}

std::vector<nlohmann::json> read_perf_record(const std::string& csv_path)
{
    require_regular_file(csv_path);  // a FIFO or a device: refused without blocking
    std::ifstream in(csv_path);
    if (!in) throw_input_error(csv_path, "", "cannot open the performance record");
    std::string line;
    if (!std::getline(in, line) || line.empty()) throw_input_error(csv_path, "line 1", "empty; expected a CSV header");
    if (line.back() == '\r') line.pop_back();
    const std::vector<std::string> written = split_csv_line(line);  // as in the file, for the messages
    std::vector<std::string> header;                                // current names (old ones with a notice)
    header.reserve(written.size());
    for (const auto& column : written) header.push_back(current_column_name(column, csv_path));
    std::set<std::string> seen;
    for (const auto& column : header) {
        if (!column_kinds().count(column)) throw_input_error(csv_path, "line 1", "unknown column '" + column + "'");
        if (!seen.insert(column).second) throw_input_error(csv_path, "line 1", "column '" + column + "' appears twice");
    }
    for (const char* required : {"snapshot", "label", "status"})
        if (!seen.count(required))
            throw_input_error(csv_path, "line 1", std::string("missing column '") + required + "'");

    std::vector<nlohmann::json> runs;
    std::set<std::pair<std::string, std::string>> keys;
    long number = 1;
    while (std::getline(in, line)) {
        ++number;
        if (line.size() > MAX_PERF_RECORD_LINE)
            throw_input_error(csv_path + ": line " + std::to_string(number), "",
                              "longer than " + std::to_string(MAX_PERF_RECORD_LINE) + " characters");
        if (!line.empty() && line.back() == '\r') line.pop_back();
        if (line.empty()) continue;
        const std::string where = csv_path + ": line " + std::to_string(number);
        const std::vector<std::string> cells = split_csv_line(line);
        if (cells.size() != header.size())
            throw_input_error(
                where, "", "expected " + std::to_string(header.size()) + " cells, got " + std::to_string(cells.size()));
        std::map<std::string, nlohmann::json> row;
        for (size_t i = 0; i < header.size(); ++i)
            row[header[i]] = parse_cell(cells[i], column_kinds().at(header[i]), where, written[i]);
        for (const char* required : {"snapshot", "label", "status"})
            if (row[required].is_null()) throw_input_error(where, std::string("column ") + required, "empty");
        const std::string snapshot = row["snapshot"], label = row["label"];
        if (!keys.insert({snapshot, label}).second)
            throw_input_error(where, "",
                              std::string("run ").append(snapshot).append("/").append(label).append(" appears twice"));

        nlohmann::json run = {{"snapshot", {{"id", snapshot}}}, {"label", label}, {"status", row["status"]}};
        nlohmann::json counters = nlohmann::json::object();
        for (const char* c :
             {"a_products", "a_products_harness", "cholmod_factorizations", "precond_applications", "work"})
            if (row.count(c) && !row[c].is_null()) counters[c] = row[c];
        run["counters"] = counters;
        if (row.count("iterations") && !row["iterations"].is_null()) run["iterations"] = row["iterations"];
        // 0: an external program's run, whose work is not counted (empty work cells are not a loss).
        if (row.count("work_counted") && !row["work_counted"].is_null())
            run["work_counted"] = row["work_counted"].get<long>() != 0;
        if (row.count("accuracy") && !row["accuracy"].is_null()) run["accuracy"] = {{"max", row["accuracy"]}};
        if (row.count("tol") && !row["tol"].is_null()) run["tol"] = row["tol"];
        if (row.count("instructions") && !row["instructions"].is_null()) run["instructions"] = row["instructions"];
        if (row.count("time_min_s") && !row["time_min_s"].is_null()) {
            nlohmann::json time = {{"min_total_s", row["time_min_s"]}};
            if (row.count("time_noise") && !row["time_noise"].is_null()) time["noise"] = row["time_noise"];
            if (row.count("time_samples") && !row["time_samples"].is_null()) time["samples"] = row["time_samples"];
            run["time"] = time;
        }
        runs.push_back(std::move(run));
        if (runs.size() > MAX_PERF_RECORD_RUNS)
            throw_input_error(csv_path + ": line " + std::to_string(number), "",
                              "more than " + std::to_string(MAX_PERF_RECORD_RUNS) +
                                  " runs: not a performance record of a suite (memory is bounded)");
    }
    if (runs.empty()) throw_input_error(csv_path, "", "no runs (only a header)");
    return runs;
}

std::string machine_file_for(const std::string& csv_path)
{
    const std::filesystem::path p(csv_path);
    return (p.parent_path() / (p.stem().string() + "-machine.json")).string();
}

nlohmann::json machine_fingerprint(const nlohmann::json& provenance)
{
    nlohmann::json fingerprint = nlohmann::json::object();
    for (const char* key : {"cpu", "blas", "suitesparse", "compiler"}) {
        std::string value = "unknown";
        if (provenance.is_object() && provenance.contains(key) && provenance[key].is_string())
            value = provenance[key].get<std::string>();
        fingerprint[key] = value;
    }
    return fingerprint;
}

std::string describe_machine(const nlohmann::json& fingerprint)
{
    if (!fingerprint.is_object() || fingerprint.empty()) return "unknown machine";
    auto field = [&](const char* key) {
        return fingerprint.contains(key) && fingerprint[key].is_string() ? fingerprint[key].get<std::string>()
                                                                         : std::string("unknown");
    };
    // The BLAS alternative is a library path; its folder names the flavour (openblas-pthread ...).
    std::string blas = field("blas");
    const std::filesystem::path blas_path(blas);
    if (blas_path.has_parent_path() && blas_path.filename().string().rfind("libblas", 0) == 0)
        blas = blas_path.parent_path().filename().string();
    return field("cpu") + ", " + blas + ", SuiteSparse " + field("suitesparse") + ", " + field("compiler");
}

}  // namespace cb
