// `contactbench solve SNAP --solver NAME`: one solver on one snapshot, a short human summary,
// optionally the per-run JSON (--json) and the solution (--save-solution).
#include "harness/cli.hpp"
#include "harness/commands.hpp"
#include "harness/length_scale.hpp"
#include "harness/results.hpp"
#include "harness/runner.hpp"
#include "harness/set_arguments.hpp"
#include "problems/format_sniff.hpp"
#include "problems/output_folder.hpp"
#include "problems/qpsnap.hpp"
#include "solvers/core/format_number.hpp"
#include "solvers/core/registry.hpp"

#include <cstdio>
#include <filesystem>
#include <future>
#include <iomanip>
#include <iostream>
#include <sstream>

namespace cb {

namespace {

const char* const SOLVE_USAGE =
    "contactbench solve SNAP --solver NAME [--set key=value ...] [--json FILE] [--save-solution DIR]\n"
    "                   [--history] [--decouple auto|none|authors|random|depth] [--decouple-seed S]\n"
    "                   [--repeat k] [--time-limit SECONDS] [--length-scale L]";

/// A dense vector in Matrix Market array format (%.17g), written atomically.
void write_solution_vector(const std::string& path, const Vec& v)
{
    std::string text = "%%MatrixMarket matrix array real general\n";
    text += std::to_string(v.size()) + " 1\n";
    char buffer[40];
    for (Eigen::Index i = 0; i < v.size(); ++i) {
        std::snprintf(buffer, sizeof(buffer), "%.17g\n", v[i]);
        text += buffer;
    }
    write_file_atomic(path, text);
}

void print_solver_list(std::ostream& out)
{
    const auto& registry = builtin_registry();
    out << "usage: " << SOLVE_USAGE << "\n\nsolvers (contactbench solve --solver NAME --help for settings):\n";
    size_t width = 0;
    for (const auto& name : registry.names()) width = std::max(width, name.size());
    for (const auto& name : registry.names())
        out << "  " << std::left << std::setw(static_cast<int>(width) + 2) << name << registry.entry(name).description
            << "\n";
}

void print_solver_settings(std::ostream& out, const std::string& name)
{
    const SolverEntry& entry = builtin_registry().entry(name);  // InputError when unknown
    out << name << ": " << entry.description << "\n\nsettings (--set key=value; defaults in brackets):\n";
    std::vector<SettingDoc> docs = common_setting_docs();
    docs.insert(docs.end(), entry.settings.begin(), entry.settings.end());
    size_t width = 0;
    for (const auto& d : docs) width = std::max(width, d.key.size() + d.default_value.size() + 3);
    for (const auto& d : docs)
        out << "  " << std::left << std::setw(static_cast<int>(width) + 2) << (d.key + " [" + d.default_value + "]")
            << d.doc << "\n";
}

}  // namespace

int cmd_solve(const Args& args)
{
    const CommandLine cl("solve", args,
                         {"--solver", "--set", "--json", "--save-solution", "--decouple", "--decouple-seed", "--repeat",
                          "--time-limit", "--length-scale"},
                         {"--history"});
    if (cl.help()) {
        if (cl.has("--solver"))
            print_solver_settings(std::cout, cl.value("--solver"));
        else
            print_solver_list(std::cout);
        return 0;
    }
    cl.expect_positional(1, 1, SOLVE_USAGE);
    if (!cl.has("--solver")) throw_input_error("solve", "--solver", "missing; usage: " + std::string(SOLVE_USAGE));
    const std::string snap = cl.positional()[0];
    const std::string name = cl.value("--solver");
    if (!builtin_registry().contains(name)) builtin_registry().entry(name);  // throws the named InputError
    // Output names are checked before the solve, so a bad one does not cost a solve.
    cl.path("--json");
    const std::string solution_dir = cl.path("--save-solution");
    if (!solution_dir.empty() && std::filesystem::exists(solution_dir) && !std::filesystem::is_directory(solution_dir))
        throw_input_error(solution_dir, "--save-solution",
                          "exists and is not a folder (x.mtx and lambda.mtx are written into a folder)");
    if (!solution_dir.empty())  // never written through a planted link (problems/output_folder.hpp)
        for (const char* file : {"/x.mtx", "/lambda.mtx", "/lambda_t.mtx"}) check_output_entry(solution_dir + file);

    RunOptions options;
    options.record_history = cl.has("--history");
    options.decouple = cl.value("--decouple", "auto");
    static const char* const orders[] = {"auto", "none", "authors", "random", "depth"};
    if (std::find(std::begin(orders), std::end(orders), options.decouple) == std::end(orders))
        throw_input_error("solve", "--decouple",
                          "expected one of auto, none, authors, random, depth, got '" + options.decouple + "'");
    const long seed = cl.integer("--decouple-seed", 0);
    if (seed < 0) throw_input_error("solve", "--decouple-seed", "must be >= 0");
    options.decouple_seed = static_cast<std::uint64_t>(seed);
    const long repeat = cl.integer("--repeat", 1);
    if (repeat < 1 || repeat > 1000)
        throw_input_error("solve", "--repeat", "must be in 1..1000, got " + std::to_string(repeat));
    options.repeat = static_cast<int>(repeat);
    options.time_limit_s = cl.number("--time-limit", 0.0);
    if (options.time_limit_s < 0) throw_input_error("solve", "--time-limit", "must be >= 0");
    const nlohmann::json settings = settings_from_assignments(cl.values("--set"));
    GivenLength given;
    if (cl.has("--length-scale")) given = {parse_length_scale("solve", cl.value("--length-scale")), "given"};

    expect_qpsnap(snap, "solve");  // an FCLIB, .dat or .npy file is named, with how to convert it
    // The content hash is a serial byte-by-byte pass over the whole file (about the load's own time
    // on a large snapshot): it runs on a second thread while the reader loads, before any solver starts.
    std::future<std::string> hashing = std::async(std::launch::async, qpsnap_content_hash, snap);
    Qp qp = read_qpsnap(snap);
    const std::string hash = hashing.get();
    fix_length_scale(qp, snap, hash, given);
    const nlohmann::json info = {{"id", std::filesystem::path(snap).stem().string()},
                                 {"path", snap},
                                 {"hash", hash},
                                 {"n", qp.n()},
                                 {"m", qp.m()},
                                 {"meta", qp.meta}};
    const RunOutcome run = run_solver(qp, name, settings, options, info);
    const nlohmann::json& r = run.record;

    std::ostringstream out;
    out << "snapshot    " << snap << " (n " << qp.n() << ", m " << qp.m() << ")\n";
    out << "solver      " << name;
    if (r["decouple"].value("applied", false))
        out << " (decoupled " << r["decouple"]["order"].get<std::string>() << ": " << r["decouple"]["rows_before"]
            << " -> " << r["decouple"]["rows_after"] << " rows)";
    out << "\n";
    out << "status      " << run.status;
    if (!r["criterion"].get<std::string>().empty()) out << " (" << r["criterion"].get<std::string>() << ")";
    if (run.status != to_string(run.result.status)) out << "; the solver said " << to_string(run.result.status);
    if (run.status == STATUS_SOLVED_RELAXATION)
        out << "  (tol met on the problem it solved, " << run.m_solved << " of " << qp.m()
            << " rows, not on the original QP)";
    if (!run.status_confirmed) out << "  NOT CONFIRMED by the accuracy measure";
    out << "\n";
    out << "iterations  " << run.result.iterations << ", A-products " << run.result.counters.a_products << "\n";
    out << "error       " << format_g(run.accuracy.max(), 3)
        << " of the scene size l = " << format_g(run.scale.length, 3) << " (" << run.scale.length_source
        << "); stationarity " << format_g(run.accuracy.stationarity, 3) << ", primal "
        << format_g(run.accuracy.primal, 3) << ", dual " << format_g(run.accuracy.dual, 3) << ", complementarity "
        << format_g(run.accuracy.complementarity, 3) << ", gap " << format_g(run.accuracy.gap, 3)
        << (r["lambda_fitted"].get<bool>() ? ", lambda fitted" : "") << "; tol "
        << format_g(r["accuracy_tol"].get<double>(), 3) << "\n";
    if (r.contains("accuracy_solved"))
        out << "solved QP   error " << format_g(run.accuracy_solved.max(), 3) << " on the "
            << r["solved_problem"].get<std::string>() << " QP (" << run.m_solved << " of " << qp.m() << " rows)\n";
    out << "objective   " << std::setprecision(10) << run.objective << ", violation " << format_g(run.violation, 3)
        << ", native residual " << format_g(run.result.native_residual, 3) << "\n";
    out << "time        setup " << format_g(r["time"]["setup_s"].get<double>(), 3) << " s, solve "
        << format_g(r["time"]["solve_s"].get<double>(), 3) << " s";
    if (options.repeat > 1) out << " (median of " << options.repeat << ")";
    out << "\n";
    if (run.nonfinite) out << "warning     NaN/Inf seen in an iterate\n";
    if (!run.monotone) out << "warning     objective increased between feasible iterates\n";
    if (!run.result.message.empty()) out << "message     " << run.result.message << "\n";
    std::cout << out.str();

    if (cl.has("--json")) write_json_atomic(cl.path("--json"), r);
    if (cl.has("--save-solution")) {
        const std::string& dir = solution_dir;
        std::error_code ec;
        std::filesystem::create_directories(dir, ec);
        if (ec) throw_input_error(dir, "--save-solution", "cannot create the folder: " + ec.message());
        write_solution_vector(dir + "/x.mtx", run.result.x);
        write_solution_vector(dir + "/lambda.mtx", run.lambda_full);  // one entry per row of the snapshot's J
        // A frictional solver's tangential multipliers (rows of T), for `judge` to measure the friction.
        if (run.lambda_t.size())
            write_solution_vector(dir + "/lambda_t.mtx", run.lambda_t);
        else
            std::filesystem::remove(dir + "/lambda_t.mtx", ec);  // an earlier run's would be judged with this x
    }
    return 0;
}

}  // namespace cb
