#include "harness/stress.hpp"

#include "harness/length_scale.hpp"
#include "harness/results.hpp"
#include "harness/runner.hpp"
#include "harness/set_arguments.hpp"
#include "solvers/core/format_number.hpp"
#include "solvers/core/registry.hpp"

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <iomanip>
#include <map>
#include <ostream>
#include <poll.h>
#include <sstream>
#include <sys/wait.h>
#include <unistd.h>

namespace cb {

bool StressRow::honest() const
{
    if (status == "crashed" || status == "hung" || status == "error") return false;
    if (status == "unconfirmed") return false;
    return status_confirmed;
}

namespace {

using nlohmann::json;
using Clock = std::chrono::steady_clock;

/// Non-finite numbers travel as strings so that NaN and Inf survive the JSON round trip.
json number_json(double v)
{
    if (std::isfinite(v)) return v;
    return std::isnan(v) ? "nan" : (v > 0 ? "inf" : "-inf");
}
double json_number(const json& j)
{
    if (j.is_number()) return j.get<double>();
    if (j.is_string()) {
        const std::string s = j.get<std::string>();
        if (s == "inf") return INFINITY;
        if (s == "-inf") return -INFINITY;
    }
    return NAN;
}

json row_to_json(const StressRow& r)
{
    return {{"solver", r.solver},
            {"case", r.case_id},
            {"family", r.family},
            {"severity", r.severity},
            {"status", r.status},
            {"accuracy", number_json(r.accuracy)},
            {"tol", r.tol},
            {"violation", number_json(r.violation)},
            {"nonfinite", r.nonfinite},
            {"monotone", r.monotone},
            {"time_s", number_json(r.time_s)},
            {"iterations", r.iterations},
            {"status_confirmed", r.status_confirmed},
            {"message", r.message},
            {"n", r.n},
            {"m", r.m},
            {"criterion", r.criterion},
            {"m_solved", r.m_solved},
            {"solver_status", r.solver_status},
            {"accuracy_solved", number_json(r.accuracy_solved)},
            {"primal", number_json(r.primal)},
            {"energy_gap", number_json(r.energy_gap)}};
}
StressRow row_from_json(const json& j)
{
    StressRow r;
    r.solver = j.at("solver");
    r.case_id = j.at("case");
    r.family = j.at("family");
    r.severity = j.at("severity");
    r.status = j.at("status");
    r.accuracy = json_number(j.at("accuracy"));
    r.tol = j.at("tol");
    r.violation = json_number(j.at("violation"));
    r.nonfinite = j.at("nonfinite");
    r.monotone = j.at("monotone");
    r.time_s = json_number(j.at("time_s"));
    r.iterations = j.at("iterations");
    r.status_confirmed = j.at("status_confirmed");
    r.message = j.at("message");
    r.n = j.at("n");
    r.m = j.at("m");
    r.criterion = j.at("criterion");
    r.m_solved = j.at("m_solved");
    r.solver_status = j.at("solver_status");
    r.accuracy_solved = json_number(j.at("accuracy_solved"));
    r.primal = json_number(j.at("primal"));
    r.energy_gap = json_number(j.at("energy_gap"));
    return r;
}

StressRow blank_row(const StressCase& c, const std::string& solver, const StressOptions& options, long n, long m)
{
    StressRow r;
    r.solver = solver;
    r.case_id = c.id;
    r.family = c.family;
    r.severity = c.severity;
    r.tol = options.tol;
    r.n = n;
    r.m = m;
    r.m_solved = m;
    r.accuracy = NAN;
    r.accuracy_solved = NAN;
    r.violation = NAN;
    r.primal = NAN;
    r.energy_gap = NAN;
    return r;
}

/// The reference of every case: F* of the ORIGINAL QP for the energy gap.
/// A stress solver spec: a registry name, optionally followed by settings, "mprgp:precond=ichol"
/// (several separated by ':'); values are typed as `solve --set` types them (harness/set_arguments.hpp), and
/// the stress tol is a default that a spec's own `tol` overrides. The whole spec is
/// the run's label (the column of the tables).
std::pair<std::string, json> parse_solver_spec(const std::string& spec)
{
    std::pair<std::string, json> out{spec.substr(0, spec.find(':')), json::object()};
    size_t start = spec.find(':');
    while (start != std::string::npos) {
        const size_t end = spec.find(':', start + 1);
        const std::string item = spec.substr(start + 1, end == std::string::npos ? std::string::npos : end - start - 1);
        const size_t eq = item.find('=');
        if (eq == std::string::npos || eq == 0)
            throw InputError(std::string("stress: --solvers: '")
                                 .append(spec)
                                 .append("': expected NAME[:key=value...], got '")
                                 .append(item)
                                 .append("'"));
        out.second[item.substr(0, eq)] = setting_from_text(item.substr(eq + 1));  // the --set rule
        start = end;
    }
    return out;
}

const char* const REFERENCE_SOLVER = "active-set";
constexpr double REFERENCE_TOL = 1e-10;

/// One run in this process. Returns the row and the per-run record (without history).
std::pair<StressRow, json> run_one(const Qp& qp, const StressCase& c, const std::string& solver,
                                   const StressOptions& options)
{
    StressRow row = blank_row(c, solver, options, qp.n(), qp.m());
    RunOptions ro;
    ro.time_limit_s = options.time_limit_s;
    ro.history_max = 200;  // enough for the monotonicity and NaN checks
    ro.decouple = "auto";
    const json info = {{"id", c.id}, {"path", ""}, {"hash", ""}, {"n", qp.n()}, {"m", qp.m()}, {"meta", qp.meta}};
    json record;
    try {
        const auto spec = parse_solver_spec(solver);
        json settings = spec.second;
        ro.defaults.tol = options.tol;  // a spec's own tol wins
        if (solver == REFERENCE_SOLVER && options.tol <= REFERENCE_TOL) settings["max_iterations"] = 100000;
        const RunOutcome out = run_solver(qp, spec.first, settings, ro, info);
        row.status = out.status;
        row.solver_status = to_string(out.result.status);
        row.criterion = to_string(out.result.criterion);
        row.accuracy = out.accuracy.max();
        row.accuracy_solved = out.accuracy_solved.max();
        row.violation = out.violation;
        row.primal = out.accuracy.primal;
        row.nonfinite = out.nonfinite;
        row.monotone = out.monotone;
        row.time_s = out.result.setup_s + out.result.solve_s;
        row.iterations = out.result.iterations;
        row.status_confirmed = out.status_confirmed;
        row.message = out.record.value("message", out.result.message);
        if (out.result.status == SolveStatus::INVALID_INPUT && row.message.empty())
            row.message = "(invalid_input without a message)";
        record = out.record;
        // The stiff families keep their (<= 200-row) histories for the stiff figure
        // (plots/stability.py draws error against time from them).
        if (c.family.rfind("stiff", 0) != 0) record.erase("history");
        row.m_solved = out.m_solved;
    } catch (const InputError& e) {
        // A refusal through an exception: still an answer with a message.
        row.status = to_string(SolveStatus::INVALID_INPUT);
        row.solver_status = row.status;
        row.message = std::string("refused with an exception: ") + e.what();
    } catch (const std::exception& e) {
        row.status = "error";
        row.status_confirmed = false;
        row.message = std::string("exception: ") + e.what();
    }
    return {row, record};
}

/// Writes all of `data` to fd (the child's result pipe).
void write_all(int fd, const std::string& data)
{
    size_t done = 0;
    while (done < data.size()) {
        const ssize_t k = ::write(fd, data.data() + done, data.size() - done);
        if (k < 0 && errno == EINTR) continue;
        if (k <= 0) return;
        done += static_cast<size_t>(k);
    }
}

/// One run in a forked child: a crash (signal) or a hang past the hard deadline becomes a row.
std::pair<StressRow, json> run_isolated(const Qp& qp, const StressCase& c, const std::string& solver,
                                        const StressOptions& options)
{
    int fds[2];
    if (::pipe(fds) != 0) return run_one(qp, c, solver, options);
    const pid_t pid = ::fork();
    if (pid < 0) {
        ::close(fds[0]);
        ::close(fds[1]);
        return run_one(qp, c, solver, options);
    }
    if (pid == 0) {
        ::close(fds[0]);
        int code = 0;
        try {
            const auto result = run_one(qp, c, solver, options);
            write_all(fds[1], json{{"row", row_to_json(result.first)}, {"record", result.second}}.dump());
        } catch (...) {
            code = 3;
        }
        ::close(fds[1]);
        ::_exit(code);
    }
    ::close(fds[1]);
    // Hard deadline: well past the solver's own limit (which covers its setup too).
    const double deadline_s = 3.0 * options.time_limit_s + 20.0;
    const auto started = Clock::now();
    std::string data;
    bool killed = false;
    for (;;) {
        const double elapsed = std::chrono::duration<double>(Clock::now() - started).count();
        if (elapsed > deadline_s) {
            ::kill(pid, SIGKILL);
            killed = true;
            break;
        }
        pollfd p{fds[0], POLLIN, 0};
        const int ready = ::poll(&p, 1, 200);
        if (ready < 0 && errno == EINTR) continue;
        if (ready > 0) {
            char buffer[65536];
            const ssize_t k = ::read(fds[0], buffer, sizeof buffer);
            if (k > 0)
                data.append(buffer, static_cast<size_t>(k));
            else if (k == 0)
                break;  // EOF: the child closed its end
            else if (errno != EINTR)
                break;
        }
    }
    ::close(fds[0]);
    int wstatus = 0;
    while (::waitpid(pid, &wstatus, 0) < 0 && errno == EINTR) {}
    StressRow row = blank_row(c, solver, options, qp.n(), qp.m());
    row.status_confirmed = false;
    if (killed) {
        row.status = "hung";
        std::ostringstream s;
        s << "no result within " << deadline_s << " s (time limit " << options.time_limit_s << " s); killed";
        row.message = s.str();
        row.time_s = deadline_s;
        return {row, json::object()};
    }
    if (WIFSIGNALED(wstatus)) {
        row.status = "crashed";
        row.message = std::string("killed by signal ") + std::to_string(WTERMSIG(wstatus)) + " (" +
                      strsignal(WTERMSIG(wstatus)) + ")";
        return {row, json::object()};
    }
    try {
        const json j = json::parse(data);
        return {row_from_json(j.at("row")), j.at("record")};
    } catch (const std::exception& e) {
        row.status = "error";
        row.message = "child exited with status " + std::to_string(WEXITSTATUS(wstatus)) + " without a readable result";
        return {row, json::object()};
    }
}

/// The stress tables print NaN as nan whatever its sign bit (printf writes -nan for x86's default NaN).
std::string csv_number(double v) { return std::isnan(v) ? "nan" : format_g(v); }

std::string csv_field(const std::string& s)
{
    if (s.find_first_of(",\"\n\r") == std::string::npos) return s;
    std::string out = "\"";
    for (char ch : s) {
        if (ch == '"')
            out += "\"\"";
        else if (ch == '\n' || ch == '\r')
            out += ' ';
        else
            out += ch;
    }
    return out + "\"";
}

std::string short_status(const StressRow& r)
{
    static const std::map<std::string, std::string> names = {{"converged", "ok"},
                                                             {"max_iterations", "maxit"},
                                                             {"time_limit", "time"},
                                                             {"solved_relaxation", "relax"},
                                                             {"unconfirmed", "unconf"},
                                                             {"stalled", "stalled"},
                                                             {"diverged", "diverged"},
                                                             {"infeasible", "infeas"},
                                                             {"invalid_input", "refused"},
                                                             {"not_applicable", "n/a"},
                                                             {"stopped_by_monitor", "stopped"},
                                                             {"crashed", "CRASH"},
                                                             {"hung", "HUNG"},
                                                             {"error", "ERROR"}};
    const auto it = names.find(r.status);
    return it == names.end() ? r.status : it->second;
}

std::string sci(double v) { return std::isnan(v) ? "nan" : format_e(v, 1); }

std::string md_cell(const std::string& s)
{
    std::string out;
    for (char ch : s) out += (ch == '|') ? std::string("\\|") : (ch == '\n' ? std::string(" ") : std::string(1, ch));
    return out;
}

}  // namespace

StressReport run_stress(const StressOptions& options)
{
    const auto started = Clock::now();
    std::vector<std::string> solvers = options.solvers;
    if (solvers.empty()) {
        // Every registered solver, plus the ichol variants so that the stiff section shows the
        // preconditioner's effect (docs/preconditioners.md).
        for (const auto& name : builtin_registry().names())
            if (!builtin_registry().entry(name).needs_settings) solvers.push_back(name);  // not command
        for (const char* variant : {"cg:precond=ichol", "mprgp:precond=ichol"})
            if (builtin_registry().contains(parse_solver_spec(variant).first)) solvers.push_back(variant);
    }
    for (const auto& s : solvers) {
        const auto spec = parse_solver_spec(s);
        builtin_registry().create(spec.first, spec.second);  // throws the named InputError (name or setting)
    }
    const std::vector<StressCase> cases = select_stress_cases(stress_cases(options.quick), options.cases);

    StressReport report;
    report.time_limit_s = options.time_limit_s;
    report.tol = options.tol;
    const size_t total = cases.size() * solvers.size();
    size_t done = 0;
    for (const StressCase& c : cases) {
        Qp qp;
        std::string generation_error;
        try {
            qp = make_stress_qp(c);
            fix_length_scale(qp, c.id, qp_content_key(qp), GivenLength{});  // before any solver, as `run` does
        } catch (const std::exception& e) {
            generation_error = e.what();
        }
        // F* of the original QP (active-set on every row), isolated like any run.
        double f_star = NAN, energy = NAN;
        if (options.reference && generation_error.empty()) {
            StressOptions ref_options = options;
            ref_options.tol = REFERENCE_TOL;
            const auto ref = options.isolate ? run_isolated(qp, c, REFERENCE_SOLVER, ref_options)
                                             : run_one(qp, c, REFERENCE_SOLVER, ref_options);
            const bool usable =
                ref.first.status == "converged" || (ref.first.solver_status == "stalled" && ref.first.accuracy <= 1e-7);
            if (usable && ref.second.value("objective", json()).is_number()) {
                f_star = ref.second["objective"].get<double>();
                const double l = ref.second.value("length_scale", NAN);
                energy = ref.second.value("stiffness_scale", NAN) * l * l;
            }
        }
        for (const std::string& solver : solvers) {
            ++done;
            std::pair<StressRow, json> result;
            if (!generation_error.empty()) {
                result.first = blank_row(c, solver, options, 0, 0);
                result.first.status = "error";
                result.first.status_confirmed = false;
                result.first.message = "case generation failed: " + generation_error;
            } else {
                result = options.isolate ? run_isolated(qp, c, solver, options) : run_one(qp, c, solver, options);
            }
            StressRow& row = result.first;
            if (std::isfinite(f_star) && result.second.value("objective", json()).is_number()) {
                row.energy_gap = std::abs(result.second["objective"].get<double>() - f_star) / energy;
                result.second["energy_gap"] = number_json(row.energy_gap);
                result.second["reference_objective"] = f_star;
            }
            if (options.progress) {
                *options.progress << "[" << done << "/" << total << "] " << solver << " x " << c.id << ": "
                                  << row.status << (row.honest() ? "" : " (WRONG)") << " accuracy=" << sci(row.accuracy)
                                  << " viol=" << sci(row.violation) << " t=" << std::fixed << std::setprecision(2)
                                  << row.time_s << "s" << std::defaultfloat << "\n";
                options.progress->flush();
            }
            if (!options.out_dir.empty() && !result.second.empty())
                write_json_atomic(options.out_dir + "/runs/" + run_file_name(c.id, solver), result.second);
            report.rows.push_back(row);
        }
    }
    report.wall_s = std::chrono::duration<double>(Clock::now() - started).count();
    if (!options.out_dir.empty()) {
        write_file_atomic(options.out_dir + "/stability.csv", stability_csv(report.rows));
        write_file_atomic(options.out_dir + "/stability.md", stability_markdown(report));
    }
    return report;
}

std::string stability_csv(const std::vector<StressRow>& rows)
{
    std::ostringstream s;
    s << "solver,case,severity,status,accuracy,tol,violation,nonfinite,monotone,time_s,iterations,status_confirmed,"
         "message,family,n,m,criterion,m_solved,solver_status,accuracy_solved,primal,energy_gap\n";
    for (const StressRow& r : rows) {
        s << csv_field(r.solver) << ',' << csv_field(r.case_id) << ',' << r.severity << ',' << r.status << ','
          << csv_number(r.accuracy) << ',' << csv_number(r.tol) << ',' << csv_number(r.violation) << ','
          << (r.nonfinite ? "true" : "false") << ',' << (r.monotone ? "true" : "false") << ',' << csv_number(r.time_s)
          << ',' << r.iterations << ',' << (r.status_confirmed ? "true" : "false") << ',' << csv_field(r.message) << ','
          << csv_field(r.family) << ',' << r.n << ',' << r.m << ',' << csv_field(r.criterion) << ',' << r.m_solved
          << ',' << csv_field(r.solver_status) << ',' << csv_number(r.accuracy_solved) << ',' << csv_number(r.primal)
          << ',' << csv_number(r.energy_gap) << '\n';
    }
    return s.str();
}

std::string stability_markdown(const StressReport& report)
{
    std::vector<std::string> solvers, cases;
    std::map<std::pair<std::string, std::string>, const StressRow*> cell;
    std::map<std::string, const StressRow*> case_row;
    for (const StressRow& r : report.rows) {
        if (std::find(solvers.begin(), solvers.end(), r.solver) == solvers.end()) solvers.push_back(r.solver);
        if (std::find(cases.begin(), cases.end(), r.case_id) == cases.end()) cases.push_back(r.case_id);
        cell[{r.case_id, r.solver}] = &r;
        case_row[r.case_id] = &r;
    }
    std::ostringstream s;
    s << "# Stability table\n\n"
      << report.rows.size() << " runs (" << cases.size() << " cases x " << solvers.size() << " solvers), time limit "
      << report.time_limit_s << " s per run, tol " << report.tol
      << " on the accuracy error e (docs/accuracy.md: residual lengths as a fraction of the scene size, "
         "measured on the original QP); wall time "
      << std::fixed << std::setprecision(1) << report.wall_s << " s.\n\n"
      << std::defaultfloat
      << "Cell: the run's status and the error e reached on the original QP (ok = converged: the solver "
         "said so and e <= tol; relax = solved_relaxation: tol met only on the problem the solver changed "
         "(decoupled rows, or J ignored), not on the original; maxit, time, infeas, refused = invalid_input, "
         "n/a = not_applicable (a problem class the solver does not take), ...). **bold!** = a wrong status "
         "(unconf = the solver said converged and e disagrees on its own problem, or a crash/hang); NaN = non-finite "
         "values seen; nm = objective not monotone over feasible iterates; (k rows) = the harness decoupled J for this "
         "solver, which then solved a QP with k of the m rows.\n\n";
    s << "| case | sev | n | m |";
    for (const auto& sv : solvers) s << ' ' << sv << " |";
    s << "\n|---|---|---|---|";
    for (size_t k = 0; k < solvers.size(); ++k) s << "---|";
    s << '\n';
    for (const auto& c : cases) {
        const StressRow* any = case_row[c];
        s << "| " << c << " | " << any->severity << " | " << any->n << " | " << any->m << " |";
        for (const auto& sv : solvers) {
            const auto it = cell.find({c, sv});
            if (it == cell.end()) {
                s << "  |";
                continue;
            }
            const StressRow& r = *it->second;
            std::string text = short_status(r) + " " + sci(r.accuracy);
            if (r.nonfinite) text += " NaN";
            if (!r.monotone) text += " nm";
            if (r.m_solved != r.m) text += " (" + std::to_string(r.m_solved) + " rows)";
            if (!r.honest()) text = std::string("**").append(text).append("!**");
            s << ' ' << text << " |";
        }
        s << '\n';
    }
    // The stiff families: time and iterations side by side, and the error-against-time figure.
    std::vector<std::string> stiff_cases;
    for (const auto& c : cases)
        if (case_row[c]->family.rfind("stiff", 0) == 0) stiff_cases.push_back(c);
    if (!stiff_cases.empty()) {
        s << "\n## Stiff families: time and iterations\n\nPer run: the time in s (setup + solve) / iterations / "
             "status. `python3 -m plots.stability DIR` draws the error e against time for every solver from the "
             "runs' histories (kept for the stiff families in runs/<case>__<solver>.json); a solver given as "
             "`NAME:key=value` runs with that setting, e.g. `--solvers cg,cg:precond=ichol,mprgp,"
             "mprgp:precond=ichol` shows the preconditioners (docs/preconditioners.md).\n\n"
             "![error against time on the stiff families](figures/stiff_family.png)\n\n| case | n | m |";
        for (const auto& sv : solvers) s << ' ' << sv << " |";
        s << "\n|---|---|---|";
        for (size_t k = 0; k < solvers.size(); ++k) s << "---|";
        s << '\n';
        for (const auto& c : stiff_cases) {
            const StressRow* any = case_row[c];
            s << "| " << c << " | " << any->n << " | " << any->m << " |";
            for (const auto& sv : solvers) {
                const auto it = cell.find({c, sv});
                if (it == cell.end()) {
                    s << "  |";
                    continue;
                }
                const StressRow& r = *it->second;
                std::ostringstream t;
                t << std::setprecision(3) << r.time_s << " / " << r.iterations << " / " << short_status(r);
                s << ' ' << t.str() << " |";
            }
            s << '\n';
        }
    }
    s << "\n## Summary per solver\n\n| solver | runs | converged | solved relaxation | wrong statuses | "
         "refused or n/a | infeasible | time limit | max iterations | other | non-finite | non-monotone |\n"
         "|---|---|---|---|---|---|---|---|---|---|---|---|\n";
    for (const auto& sv : solvers) {
        long runs = 0, ok = 0, relax = 0, wrong = 0, refused = 0, infeasible = 0, time = 0, maxit = 0, other = 0,
             nonfinite = 0, nonmonotone = 0;
        for (const StressRow& r : report.rows) {
            if (r.solver != sv) continue;
            ++runs;
            if (!r.honest())
                ++wrong;
            else if (r.status == "converged")
                ++ok;
            else if (r.status == "solved_relaxation")
                ++relax;
            else if (r.status == "invalid_input" || r.status == "not_applicable")
                ++refused;
            else if (r.status == "infeasible")
                ++infeasible;
            else if (r.status == "time_limit")
                ++time;
            else if (r.status == "max_iterations")
                ++maxit;
            else
                ++other;
            if (r.nonfinite) ++nonfinite;
            if (!r.monotone) ++nonmonotone;
        }
        s << "| " << sv << " | " << runs << " | " << ok << " | " << relax << " | " << wrong << " | " << refused << " | "
          << infeasible << " | " << time << " | " << maxit << " | " << other << " | " << nonfinite << " | "
          << nonmonotone << " |\n";
    }
    s << "\n## Wrong statuses\n\n";
    long wrong = 0;
    for (const StressRow& r : report.rows) {
        if (r.honest()) continue;
        ++wrong;
        s << "- " << r.solver << " on " << r.case_id << ": status " << r.status
          << (r.criterion.empty() ? "" : " (criterion " + r.criterion + ")") << ", error " << sci(r.accuracy)
          << " (on the problem it solved " << sci(r.accuracy_solved) << ")"
          << " vs tol " << sci(r.tol) << ", violation " << sci(r.violation) << ": " << md_cell(r.message) << "\n";
    }
    if (wrong == 0)
        s << "None: every solver's \"converged\" held under the accuracy measure on the problem it solved.\n";
    s << "\n## Accuracy of converged runs\n\nPer solver, over its runs with status converged: the error e "
         "(fraction of the scene size), the violation of the original rows (e's primal part, fraction of the "
         "scene size) and the energy gap |F - F*| / (d_ref l^2) against active-set's F* of the original QP "
         "(d_ref = mean diag(A), l = the scene size; - when no reference).\n\n"
         "| solver | converged | max e | violation (min - max) | energy gap (min - max) |\n|---|---|---|---|---|\n";
    for (const auto& sv : solvers) {
        long count = 0;
        double e_max = 0.0, v_min = INFINITY, v_max = 0.0, g_min = INFINITY, g_max = -INFINITY;
        for (const StressRow& r : report.rows) {
            if (r.solver != sv || r.status != "converged") continue;
            ++count;
            e_max = std::max(e_max, r.accuracy);
            v_min = std::min(v_min, r.primal);
            v_max = std::max(v_max, r.primal);
            if (std::isfinite(r.energy_gap)) {
                g_min = std::min(g_min, r.energy_gap);
                g_max = std::max(g_max, r.energy_gap);
            }
        }
        s << "| " << sv << " | " << count << " | " << (count ? sci(e_max) : "-") << " | "
          << (count ? sci(v_min) + " - " + sci(v_max) : "-") << " | "
          << (g_max >= 0.0 ? sci(g_min) + " - " + sci(g_max) : "-") << " |\n";
    }
    return s.str();
}

}  // namespace cb
