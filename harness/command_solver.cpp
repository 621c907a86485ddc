// `command`: an external program as a solver (command_solver.hpp, docs/INTERFACES.md).
#include "harness/command_solver.hpp"
#include "harness/temp_folder.hpp"

#include "harness/printable_text.hpp"
#include "harness/program_run.hpp"
#include "harness/results.hpp"
#include "problems/io_util.hpp"
#include "problems/matrix_market.hpp"
#include "problems/qpsnap.hpp"
#include "problems/solution_io.hpp"
#include "solvers/core/peak_memory.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <optional>
#include <sstream>

namespace cb {

namespace {

namespace fs = std::filesystem;

const SettingsTable<CommandSettings>& command_settings_table()
{
    static const SettingsTable<CommandSettings> table =
        SettingsTable<CommandSettings>()
            .choice("accepts", &CommandSettings::accepts, {"any", "decoupled"},
                    "any | decoupled: what J the program takes; with decoupled the harness decouples a coupled J "
                    "first and judges on the original QP")
            .choice("time", &CommandSettings::time, {"harness", "self"},
                    "harness | self: the run's solve time is the harness's wall time of the child (start-up "
                    "included) or the program's self-reported solve_s; both are recorded")
            .boolean("keep_files", &CommandSettings::keep_files,
                     "keep the work folder (snapshot, settings.json, out/, stdout.txt, stderr.txt)");
    return table;
}

std::vector<std::string> read_argv(const nlohmann::json& settings)
{
    const auto it = settings.find("argv");
    if (it == settings.end())
        throw_input_error(
            "command", "/argv",
            "missing: the program and its arguments, e.g. [\"python3\", \"my_solver.py\", \"{settings}\"]");
    nlohmann::json argv = *it;
    if (argv.is_string()) {  // --set argv='["python3", ...]' arrives as a string
        try {
            argv = nlohmann::json::parse(argv.get<std::string>());
        } catch (const nlohmann::json::exception&) {
            throw_input_error("command", "/argv",
                              "expected a JSON array of strings, got the string " + it->dump() +
                                  " (no shell splits it: write [\"prog\", \"arg\", ...])");
        }
    }
    if (!argv.is_array() || argv.empty())
        throw_input_error("command", "/argv", "expected a non-empty array of strings, got " + argv.dump());
    std::vector<std::string> out;
    bool names_problem = false, names_output = false;
    for (size_t i = 0; i < argv.size(); ++i) {
        if (!argv[i].is_string())
            throw_input_error("command", "/argv/" + std::to_string(i), "expected a string, got " + argv[i].dump());
        out.push_back(argv[i].get<std::string>());
        const std::string& a = out.back();
        if (a.find("{settings}") != std::string::npos) names_problem = names_output = true;
        if (a.find("{snapshot}") != std::string::npos || a.find("{mtx}") != std::string::npos) names_problem = true;
        if (a.find("{out}") != std::string::npos) names_output = true;
    }
    if (out[0].empty()) throw_input_error("command", "/argv/0", "the program is empty");
    if (!names_problem || !names_output)
        throw_input_error("command", "/argv",
                          "must name {settings}, or {snapshot} (or {mtx}) and {out}: the program would not know what "
                          "to solve or where to write x");
    return out;
}

/// Arguments that name an existing file or folder relative to where contactbench was started
/// are made absolute, since the program starts in its work folder (argv[0] only when it has a
/// '/': a bare name is looked up in PATH). Arguments with a placeholder become absolute paths
/// or numbers anyway.
std::vector<std::string> absolute_arguments(const std::vector<std::string>& argv)
{
    std::vector<std::string> out;
    for (size_t i = 0; i < argv.size(); ++i) {
        const std::string& a = argv[i];
        std::error_code ec;
        const bool candidate = !a.empty() && a[0] != '/' && a.find('{') == std::string::npos &&
                               (i > 0 || a.find('/') != std::string::npos);
        if (candidate && fs::exists(fs::symlink_status(a, ec))) {
            const fs::path absolute = fs::absolute(a, ec);
            out.push_back(ec ? a : absolute.lexically_normal().string());
        } else {
            out.push_back(a);
        }
    }
    return out;
}

/// The last `max_chars` of a text file on one line, made printable (for messages and records).
std::string tail_of(const fs::path& path, size_t max_chars = 300)
{
    std::string text;
    try {
        text = read_regular_file(path.string(), std::uint64_t(1) << 26);
    } catch (const InputError&) {
        return "";
    }
    text = printable_text(text);
    while (!text.empty() && (text.back() == '\n' || text.back() == ' ')) text.pop_back();
    if (text.size() > max_chars) {  // cut at a character boundary, not inside a UTF-8 sequence
        size_t from = text.size() - max_chars;
        while (from < text.size() && (static_cast<unsigned char>(text[from]) & 0xC0) == 0x80) ++from;
        text = "..." + text.substr(from);
    }
    for (auto& ch : text)
        if (ch == '\n' || ch == '\r' || ch == '\t') ch = ' ';
    return text;
}

/// More history rows than this is garbage: a program's record of its iterations is not a way to
/// make the harness work (each row with x costs a read and a measure).
constexpr size_t HISTORY_ROWS_MAX = 20000;

/// "2.5 s" in messages.
std::string seconds(double s)
{
    char buffer[40];
    std::snprintf(buffer, sizeof buffer, "%.6g s", s);
    return buffer;
}

double seconds_since(std::chrono::steady_clock::time_point t0)
{
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

/// What the program reported in result.json (every field optional).
struct ProgramReport {
    bool has_status = false;
    SolveStatus status = SolveStatus::CONVERGED;
    std::string status_text;
    long iterations = 0;
    double solve_s = std::numeric_limits<double>::quiet_NaN();
    double setup_s = std::numeric_limits<double>::quiet_NaN();
    double residual = std::numeric_limits<double>::quiet_NaN();
    std::string message;
    nlohmann::json history = nlohmann::json::array();
};

double number_field(const nlohmann::json& j, const char* key, const std::string& where, bool non_negative)
{
    const auto& v = j[key];
    if (!v.is_number() || !std::isfinite(v.get<double>()) || (non_negative && v.get<double>() < 0))
        throw_input_error(where, std::string("/") + key,
                          std::string("expected a finite ") + (non_negative ? "number >= 0" : "number") + ", got " +
                              v.dump());
    return v.get<double>();
}

ProgramReport read_report(const fs::path& path)
{
    ProgramReport report;
    if (!fs::exists(path)) return report;
    const std::string where = path.string();
    const nlohmann::json j = read_json_checked(where);
    if (!j.is_object()) throw_input_error(where, "", "expected a JSON object");
    static const char* const known[] = {"status", "iterations", "solve_s", "setup_s", "residual", "message", "history"};
    for (const auto& item : j.items())
        if (std::find_if(std::begin(known), std::end(known), [&](const char* k) { return item.key() == k; }) ==
            std::end(known))
            throw_input_error(where, "/" + item.key(),
                              "unknown key; known: status, iterations, solve_s, setup_s, residual, message, history");
    if (j.contains("status")) {
        if (!j["status"].is_string())
            throw_input_error(where, "/status", "expected a string, got " + j["status"].dump());
        report.status_text = j["status"].get<std::string>();
        try {
            report.status = solve_status_from_string(report.status_text);
        } catch (const InputError&) {
            throw_input_error(where, "/status",
                              "unknown status '" + report.status_text +
                                  "'; known: converged, max_iterations, time_limit, stalled, diverged, infeasible, "
                                  "invalid_input, not_applicable");
        }
        report.has_status = true;
    }
    if (j.contains("iterations")) {
        if (!j["iterations"].is_number_integer() || j["iterations"].get<long>() < 0)
            throw_input_error(where, "/iterations", "expected an integer >= 0, got " + j["iterations"].dump());
        report.iterations = j["iterations"].get<long>();
    }
    if (j.contains("solve_s")) report.solve_s = number_field(j, "solve_s", where, true);
    if (j.contains("setup_s")) report.setup_s = number_field(j, "setup_s", where, true);
    if (j.contains("residual")) report.residual = number_field(j, "residual", where, false);
    if (j.contains("message")) {
        if (!j["message"].is_string())
            throw_input_error(where, "/message", "expected a string, got " + j["message"].dump());
        report.message = printable_text(j["message"].get<std::string>());
    }
    if (j.contains("history")) {
        if (!j["history"].is_array()) throw_input_error(where, "/history", "expected an array of objects");
        if (j["history"].size() > HISTORY_ROWS_MAX)
            throw_input_error(where, "/history",
                              std::to_string(j["history"].size()) + " rows, more than the " +
                                  std::to_string(HISTORY_ROWS_MAX) + " a program may report");
        for (size_t k = 0; k < j["history"].size(); ++k) {
            const auto& row = j["history"][k];
            const std::string at = where + ": /history/" + std::to_string(k);
            if (!row.is_object()) throw_input_error(at, "", "expected an object {iteration, time_s, residual, x}");
            for (const auto& item : row.items())
                if (item.key() != "iteration" && item.key() != "time_s" && item.key() != "residual" &&
                    item.key() != "x")
                    throw_input_error(at, "/" + item.key(), "unknown key; known: iteration, time_s, residual, x");
            if (row.contains("iteration") &&
                (!row["iteration"].is_number_integer() || row["iteration"].get<long>() < 0))
                throw_input_error(at, "/iteration", "expected an integer >= 0, got " + row["iteration"].dump());
            if (row.contains("time_s")) number_field(row, "time_s", at, true);
            if (row.contains("residual")) number_field(row, "residual", at, false);
            if (row.contains("x") && !row["x"].is_string())
                throw_input_error(at, "/x", "expected a file name in {out}, got " + row["x"].dump());
        }
        report.history = j["history"];
    }
    return report;
}

/// A Matrix Market x or lambda whose size line declares other than `expected` entries is refused
/// before it is read: a coordinate file of a few bytes may declare 2^31 rows, which the reader
/// would allocate (zeroed) before finding that the length is wrong.
void check_declared_size(const fs::path& path, long expected, const char* field)
{
    if (expected == 0 || !fs::is_regular_file(path)) return;
    std::ifstream in(path);
    std::string line;
    long number = 0;
    while (std::getline(in, line) && number < 10000) {
        ++number;
        if (line.empty() || line[0] == '%') continue;
        std::istringstream sizes(line);
        long long rows = -1, cols = -1;
        sizes >> rows >> cols;
        const bool column = rows == expected && cols == 1, row = rows == 1 && cols == expected;
        if (!sizes || !(column || row))
            throw_input_error(path.string(), std::string(field) + ": line " + std::to_string(number),
                              "the size line declares '" + line + "', expected " + std::to_string(expected) +
                                  " x 1 (refused before reading)");
        return;
    }
}

/// The program's own times cannot exceed the child's wall time measured by the harness: a
/// setup_s + solve_s or a history time_s beyond it is refused (InputError naming the field).
/// Returns the latest history time_s (0 without one).
double check_times(const ProgramReport& report, const fs::path& path, double wall_s)
{
    const std::string where = path.string();
    auto wall = [&] { return seconds(wall_s); };
    const double self =
        (std::isfinite(report.solve_s) ? report.solve_s : 0.0) + (std::isfinite(report.setup_s) ? report.setup_s : 0.0);
    if (self > wall_s)
        throw_input_error(where, std::isfinite(report.solve_s) ? "/solve_s" : "/setup_s",
                          "setup_s + solve_s = " + seconds(self) +
                              " exceeds the child's wall time measured by the harness, " + wall());
    double latest = 0.0;
    for (size_t k = 0; k < report.history.size(); ++k) {
        const double t = report.history[k].value("time_s", 0.0);
        const double bound = std::isfinite(report.solve_s) ? report.solve_s : wall_s;
        if (t > bound)
            throw_input_error(where, "/history/" + std::to_string(k) + "/time_s",
                              seconds(t) + " is beyond " +
                                  (std::isfinite(report.solve_s) ? "the program's solve_s, " + seconds(bound)
                                                                 : "the child's wall time, " + wall()));
        latest = std::max(latest, t);
    }
    return latest;
}

/// The program's iterates, measured by the harness's monitor (time axis: the program's time_s).
/// `offset_s` moves the program's time_s (from the start of its solve) onto the run's clock.
/// Replaying stops at the run's time limit (`deadline`, on the harness's clock since `t0`; 0: none):
/// the history is cut there and the output refused (an InputError), however many rows remain.
void replay_history(const ProgramReport& report, const fs::path& out, const QpView& qp, const SolveContext& context,
                    double offset_s, nlohmann::json& program_history, std::chrono::steady_clock::time_point t0,
                    double deadline)
{
    for (const auto& row : report.history) {
        if (deadline > 0.0 && seconds_since(t0) > deadline)
            throw_input_error((out / "result.json").string(), "/history",
                              "replaying its " + std::to_string(report.history.size()) +
                                  " rows passed the time limit of " + seconds(deadline) + " after " +
                                  std::to_string(program_history.size()) + " rows (cut there)");
        program_history.push_back({{"iteration", row.value("iteration", 0L)},
                                   {"time_s", row.contains("time_s") ? row["time_s"] : nlohmann::json()},
                                   {"residual", row.contains("residual") ? row["residual"] : nlohmann::json()}});
        if (!context.monitor || !row.contains("x")) continue;
        const std::string name = row["x"].get<std::string>();
        if (name.find('/') != std::string::npos || name.find("..") != std::string::npos)
            throw_input_error((out / "result.json").string(), "/history/x",
                              "expected a file name inside {out}, got '" + name + "'");
        const fs::path file = out / name;
        const Vec x = read_vector_file(file.string(), "x");
        if (x.size() != qp.n())
            throw_input_error(file.string(), "x",
                              "expected " + std::to_string(qp.n()) + " entries, got " + std::to_string(x.size()));
        IterationInfo info;
        info.iteration = row.value("iteration", 0L);
        info.step = StepKind::OUTER;
        info.x = &x;
        info.native_residual = row.value("residual", std::numeric_limits<double>::quiet_NaN());
        info.elapsed_s = offset_s + row.value("time_s", 0.0);
        context.monitor->on_iteration(info);
    }
}

void write_text_vector(const fs::path& path, const Vec& v)
{
    std::string text;
    char buffer[40];
    for (Eigen::Index i = 0; i < v.size(); ++i) {
        std::snprintf(buffer, sizeof buffer, "%.17g\n", v[i]);
        text += buffer;
    }
    write_file_atomic(path.string(), text);
}

}  // namespace

std::string expand_placeholders(const std::string& arg, const std::vector<std::pair<std::string, std::string>>& values)
{
    std::string out;
    for (size_t i = 0; i < arg.size();) {
        bool replaced = false;
        if (arg[i] == '{')
            for (const auto& [name, value] : values)
                if (arg.compare(i, name.size(), name) == 0) {
                    out += value;  // never scanned again: a value holding "{out}" stays as it is
                    i += name.size();
                    replaced = true;
                    break;
                }
        if (!replaced) out += arg[i++];
    }
    return out;
}

CommandSettings CommandSettings::from_json(const nlohmann::json& settings_in)
{
    const nlohmann::json settings = settings_in.is_null() ? nlohmann::json::object() : settings_in;
    if (!settings.is_object()) throw_input_error("command", "", "settings must be a JSON object");
    CommandSettings s;
    s.argv = read_argv(settings);
    nlohmann::json rest = settings;
    rest.erase("argv");
    SettingsReader reader(rest, "command");
    s.common = reader.common();
    command_settings_table().read(reader, s);
    reader.finish();
    return s;
}

nlohmann::json CommandSettings::to_json() const
{
    nlohmann::json j = common.to_json();
    j["argv"] = argv;
    command_settings_table().write(*this, j);
    return j;
}

SolverResult CommandSolver::solve(const QpView& qp, const SolveContext& context)
{
    const auto t0 = std::chrono::steady_clock::now();
    SolverResult result;
    result.native_residual = std::numeric_limits<double>::quiet_NaN();
    const CommonSettings& common = m_settings.common;
    // No limit asked for: the program still gets one, so that a hung program cannot hold the harness.
    const double time_limit_s = common.time_limit_s > 0.0 ? common.time_limit_s : DEFAULT_COMMAND_TIME_LIMIT_S;
    std::optional<TempFolder> folder;
    try {
        folder.emplace("contactbench-command", m_settings.keep_files);
    } catch (const std::exception& e) {
        // No place to hand the problem over: the run fails, it does not end the harness.
        result.status = SolveStatus::DIVERGED;
        result.message = std::string("command: ") + e.what();
        return result;
    }
    // Absolute (a relative $TMPDIR too): the program starts inside it, and argv names its files.
    const fs::path work_dir = fs::absolute(folder->path());
    const fs::path snapshot = work_dir / "problem.qpsnap", settings_path = work_dir / "settings.json",
                   out = work_dir / "out";
    fs::create_directories(out);

    // The problem exactly as this solver is given it (decoupled rows when the harness decoupled),
    // with its friction when it has some (snapshot version 2).
    Qp problem{qp.A, qp.b, qp.J, qp.c, qp.x0, {}, {{"source", "contactbench command solver"}}, {}, {}};
    if (qp.friction) problem.friction = *qp.friction;
    const long tangent_rows = long(problem.friction.T.rows());
    write_qpsnap(snapshot.string(), problem);
    nlohmann::json settings_file = {{"protocol", COMMAND_PROTOCOL_VERSION},
                                    {"snapshot", snapshot.string()},
                                    {"out", out.string()},
                                    {"n", qp.n()},
                                    {"m", qp.m()},
                                    {"tol", common.tol},
                                    {"stop", to_string(common.stop)},
                                    {"max_iterations", common.max_iterations},
                                    {"time_limit_s", time_limit_s},
                                    {"seed", common.seed},
                                    {"accepts", m_settings.accepts},
                                    {"frictional", problem.frictional()},
                                    {"x0", "the snapshot's array x0"},
                                    {"lambda0", nullptr},
                                    {"mtx", nullptr}};
    if (context.lambda0 && context.lambda0->size() == qp.m()) {
        write_text_vector(work_dir / "lambda0.txt", *context.lambda0);
        settings_file["lambda0"] = (work_dir / "lambda0.txt").string();
    }
    // The same problem as a Matrix Market folder, only for a program that names {mtx}.
    bool wants_mtx = false;
    for (const auto& a : m_settings.argv) wants_mtx = wants_mtx || a.find("{mtx}") != std::string::npos;
    if (wants_mtx) {
        write_matrix_market_folder((work_dir / "problem_mtx").string(), problem);
        settings_file["mtx"] = (work_dir / "problem_mtx").string();
    }
    write_json_atomic(settings_path.string(), settings_file);
    auto number = [](double v) {
        char buffer[40];
        std::snprintf(buffer, sizeof buffer, "%.17g", v);
        return std::string(buffer);
    };
    const std::vector<std::pair<std::string, std::string>> placeholders = {
        {"{snapshot}", snapshot.string()},
        {"{settings}", settings_path.string()},
        {"{out}", out.string()},
        {"{mtx}", (work_dir / "problem_mtx").string()},
        {"{tol}", number(common.tol)},
        {"{max_iterations}", std::to_string(common.max_iterations)},
        {"{time_limit_s}", number(time_limit_s)},
        {"{seed}", std::to_string(common.seed)}};
    std::vector<std::string> argv;
    for (const auto& a : absolute_arguments(m_settings.argv)) argv.push_back(expand_placeholders(a, placeholders));
    const double prepare_s = seconds_since(t0);

    ProgramOptions options;
    options.time_limit_s = time_limit_s;
    options.workdir = work_dir.string();  // relative writes of the program stay in its work folder
    const ProgramOutcome run =
        run_program(argv, (work_dir / "stdout.txt").string(), (work_dir / "stderr.txt").string(), options);
    if (run.interrupted != 0) {  // Ctrl-C or a kill of the harness: the program is gone, so is its folder
        std::cerr << "command: " << strsignal(run.interrupted) << " received: the program's process group was "
                  << "signalled, its work folder " << (m_settings.keep_files ? "kept: " : "removed: ")
                  << work_dir.string() << "\n";
        folder.reset();
        end_by_signal(run.interrupted);
    }
    if (run.peak_rss_bytes >= 0) note_child_peak_memory(run.peak_rss_bytes);  // in the record's peak
    nlohmann::json info = {
        {"argv", argv},
        {"time_child_wall_s", run.wall_s},
        {"time_prepare_s", prepare_s},
        {"time_self_s", nullptr},
        {"time_source", "harness"},
        {"exit_status", run.exit_status},
        {"signal", run.signal},
        {"time_limit_s", time_limit_s},
        {"peak_rss_mb", run.peak_rss_bytes >= 0 ? nlohmann::json(run.peak_rss_bytes / 1048576.0) : nlohmann::json()},
        {"peak_floor_mb",
         run.start_rss_bytes >= 0 ? nlohmann::json(run.start_rss_bytes / 1048576.0) : nlohmann::json()},
        {"orphans_killed", run.orphans_killed},
        {"stdout_bytes", run.stdout_bytes},
        {"stderr_bytes", run.stderr_bytes},
        {"output_capped", run.stdout_capped || run.stderr_capped},
        {"crashed", false},
        {"garbage", false},
        {"timed_out", run.timed_out}};
    if (m_settings.keep_files) info["workdir"] = work_dir.string();
    const std::string stderr_tail = tail_of(work_dir / "stderr.txt");
    result.setup_s = prepare_s;
    result.solve_s = run.wall_s;
    auto finish = [&](SolveStatus status, const std::string& message) {
        result.status = status;
        result.message = message;
        result.info["command"] = info;
        return result;
    };
    if (run.timed_out)
        return finish(SolveStatus::TIME_LIMIT,
                      "command: killed at the time limit of " + nlohmann::json(time_limit_s).dump() +
                          " s (harness wall time of the child" +
                          (common.time_limit_s > 0.0 ? std::string(")")
                                                     : std::string("; the command solver's default "
                                                                   "when time_limit_s is 0)")));
    if (!run.failure().empty()) {
        info["crashed"] = true;
        return finish(SolveStatus::DIVERGED, "command: the program " + run.failure() +
                                                 (stderr_tail.empty() ? "" : "; stderr: " + stderr_tail));
    }
    ProgramReport report;
    SolutionPoint point;
    nlohmann::json program_history = nlohmann::json::array();
    try {
        report = read_report(out / "result.json");
        check_declared_size(out / "x.mtx", qp.n(), "x");
        check_declared_size(out / "lambda.mtx", qp.m(), "lambda");
        check_declared_size(out / "lambda_t.mtx", tangent_rows, "lambda_t");
        point = read_solution(out.string(), qp.n(), qp.m(), "", "", tangent_rows);
        // On the harness's clock the program's solve ends with the child (start-up before it);
        // on its own clock, after its setup.
        // Its times never beyond the child's wall time: refused otherwise (check_times). On the
        // harness's clock the solve ends with the child, so the latest reported time lands at
        // prepare_s + wall_s.
        const double latest = check_times(report, out / "result.json", run.wall_s);
        const bool self_time = m_settings.time == "self" && std::isfinite(report.solve_s);
        const double offset_s =
            self_time ? (std::isfinite(report.setup_s) ? report.setup_s : 0.0)
                      : prepare_s + run.wall_s - (std::isfinite(report.solve_s) ? report.solve_s : latest);
        replay_history(report, out, qp, context, offset_s, program_history, t0, common.time_limit_s);
    } catch (const std::exception& e) {
        // Unusable output (an InputError naming the file and field, or a size that exhausts memory)
        // is the program's failure, final: never an internal error retried on every resume.
        info["garbage"] = true;
        info["garbage_reason"] = e.what();
        info["program_history"] = program_history;
        result.x = Vec();
        return finish(SolveStatus::DIVERGED, std::string("command: the program's output is unusable: ") + e.what());
    }
    result.x = point.x;
    result.lambda = point.lambda;
    result.lambda_t = point.lambda_t;  // empty: judged as solving the frictionless relaxation
    result.iterations = report.iterations;
    result.counters.iterations = report.iterations;
    result.native_residual = report.residual;
    info["program_status"] = report.has_status ? nlohmann::json(report.status_text) : nlohmann::json();
    info["program_history"] = program_history;
    if (std::isfinite(report.solve_s))
        info["time_self_s"] = report.solve_s + (std::isfinite(report.setup_s) ? report.setup_s : 0.0);
    std::string message = report.message;
    if (m_settings.time == "self") {
        if (std::isfinite(report.solve_s)) {
            result.setup_s = std::isfinite(report.setup_s) ? report.setup_s : 0.0;
            result.solve_s = report.solve_s;
            info["time_source"] = "self";
        } else {
            message += std::string(message.empty() ? "" : "; ") +
                       "time=self but the program reported no solve_s: the harness's wall time is used";
        }
    }
    // A program that exits 0 without a status claims it solved the problem: the measure checks it.
    const SolveStatus status = report.has_status ? report.status : SolveStatus::CONVERGED;
    if (status == SolveStatus::CONVERGED) result.criterion = StopCriterion::PROGRAM;
    return finish(status, message.empty() ? "command: the program exited normally" : message);
}

void require_command_opt_in(const std::string& solver, const std::string& scene_file, bool scene_allows,
                            bool flag_given)
{
    if (solver != "command" || (scene_allows && flag_given)) return;
    const std::string rule = "'command' runs an external program: it runs only when the scene says "
                             "\"allow_commands\": true and the command line gives --allow-commands";
    if (!scene_allows) throw_input_error(scene_file, "/allow_commands", "missing; " + rule);
    throw_input_error(scene_file, "/solver", rule + " (--allow-commands not given)");
}

SolverEntry command_entry()
{
    SolverEntry entry;
    entry.make = [](const nlohmann::json& settings) {
        return std::make_unique<CommandSolver>(CommandSettings::from_json(settings));
    };
    entry.description = "an external program in any language (docs/INTERFACES.md \"The command protocol\")";
    entry.settings = {
        {"argv", "(required)", "the program and its arguments, no shell: {snapshot}, {settings}, {out} become paths"}};
    const auto rows = command_settings_table().docs();
    entry.settings.insert(entry.settings.end(), rows.begin(), rows.end());
    entry.applies_to = "what its program declares: any J, or decoupled rows only (setting accepts)";
    entry.needs_settings = true;
    return entry;
}

namespace {

void register_command(SolverRegistry& registry) { registry.add("command", command_entry()); }

}  // namespace

void install_command_solver()
{
    static const bool installed = [] {
        add_builtin_registration(register_command);
        return true;
    }();
    (void)installed;
}

}  // namespace cb
