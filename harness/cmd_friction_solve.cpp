// contactbench friction-solve: an FCLIB frictional problem, local (W, q, mu) or global (M, H, f, w,
// mu), solved with its friction by our NSGS or Siconos' fc3d/gfc3d solvers, each judged by the
// FCLIB relative error the harness computes.
#include "harness/cli.hpp"
#include "harness/commands.hpp"
#include "harness/results.hpp"
#include "problems/fclib_io.hpp"
#include "problems/format_sniff.hpp"
#include "problems/siconos_dat.hpp"
#include "solvers/core/format_number.hpp"
#include "solvers/core/stopwatch.hpp"
#include "solvers/friction/friction_global_nsgs.hpp"
#include "solvers/friction/friction_nsgs.hpp"
#include "solvers/friction/mprgp_tresca.hpp"
#include "solvers/measure/friction_error.hpp"
#include "solvers/peers/siconos_fc3d.hpp"
#include "solvers/peers/siconos_gfc3d.hpp"

#include <nlohmann/json.hpp>
#include <algorithm>
#include <cstdio>
#include <iostream>
#include <optional>

namespace cb {

namespace {

const char* const FRICTION_SOLVE_USAGE =
    "contactbench friction-solve FILE.hdf5|FILE.dat [--solver S ...]\n"
    "                            (S: "
    "nsgs|mprgp-tresca-fp|mprgp+ica-friction|siconos-nsgs|siconos-nsn|siconos-prox|siconos-admm)\n"
    "                            [--tol T] [--max-iterations N] [--time-limit S] [--json FILE]";

const std::vector<std::string> SOLVERS = {"nsgs",        "mprgp-tresca-fp", "mprgp+ica-friction", "siconos-nsgs",
                                          "siconos-nsn", "siconos-prox",    "siconos-admm"};
/// Ours: built always; the rest are Siconos' (a child process each).
bool is_ours(const std::string& solver)
{
    return solver == "nsgs" || solver == "mprgp-tresca-fp" || solver == "mprgp+ica-friction";
}

struct Settings {
    double tol = 1e-8;
    long max_iterations = 10000;
    double time_limit = 60.0;
};

FrictionNsgsSettings nsgs_settings(const Settings& s)
{
    FrictionNsgsSettings settings;
    settings.tol = s.tol;
    settings.max_iterations = s.max_iterations;
    settings.time_limit_s = s.time_limit;
    return settings;
}

/// One row of the table and of the JSON.
void report(const std::string& solver, const FrictionRun& run, double second_error, std::string& table,
            nlohmann::json& row)
{
    char line[256];
    std::snprintf(line, sizeof line, "%-14s %-15s %8ld %10.4f %12.3e %12.3e\n", solver.c_str(), run.status.c_str(),
                  run.iterations, run.seconds, run.error, second_error);
    table += line;
    row = {{"solver", solver},
           {"status", run.status},
           {"iterations", run.iterations},
           {"seconds", run.seconds},
           {"fclib_error", run.error}};
    if (run.native_error >= 0.0) row["native_error"] = run.native_error;
    if (!run.note.empty()) row["note"] = run.note;
}

/// Our solvers of a local problem (nsgs and the two MPRGP-based ones); an empty `solver` for a peer.
FrictionRun our_local_run(const FrictionLocal& problem, const std::string& solver, const Settings& s)
{
    if (solver == "nsgs") return friction_nsgs(problem, nsgs_settings(s));
    if (solver == "mprgp-tresca-fp") {
        MprgpTrescaSettings settings;
        settings.tol = s.tol;
        settings.max_inner = s.max_iterations;
        settings.time_limit_s = s.time_limit;
        return mprgp_tresca_fp(problem, settings).run;
    }
    if (solver == "mprgp+ica-friction") {
        MprgpIcaFrictionSettings settings;
        settings.tol = s.tol;
        settings.max_mprgp = s.max_iterations;
        settings.max_sweeps = s.max_iterations;
        settings.time_limit_s = s.time_limit;
        return mprgp_ica_friction(problem, settings);
    }
    return {};
}

void solve_local(const FrictionLocal& problem, const std::vector<std::string>& solvers, const Settings& s,
                 std::string& table, nlohmann::json& out)
{
    out["error_definition"] = "||r - P_K(r - (u + mu ||u_T|| e_n))||_2 / ||q||_2, u = W r + q";
    out["siconos_scaled_error_definition"] =
        "the same numerator / max(||q||, ||u||, ||r||) (Siconos 4.4's fc3d_compute_error)";
    char line[256];
    std::snprintf(line, sizeof line, "%-14s %-15s %8s %10s %12s %12s\n", "solver", "status", "iters", "time_s",
                  "fclib_error", "siconos_err");
    table += line;
    for (const std::string& solver : solvers) {
        FrictionRun run = our_local_run(problem, solver, s);
        if (run.solver.empty())
            run = siconos_fc3d_solve(problem, solver.substr(8), s.max_iterations, s.tol, s.time_limit);
        nlohmann::json row;
        const double siconos_scaled = siconos_relative_error(problem, run.r);
        report(solver, run, siconos_scaled, table, row);
        row["siconos_scaled_error"] = siconos_scaled;
        out["runs"].push_back(row);
    }
}

void solve_global(const FrictionGlobal& problem, const std::vector<std::string>& solvers, const Settings& s,
                  std::string& table, nlohmann::json& out)
{
    out["unknowns"] = problem.unknowns();
    out["error_definition"] = "||f + H r - M v|| / max(||f||, ||M v||, ||H r||) + ||r - P_K(r - (u + mu ||u_T|| "
                              "e_n))|| / max(||u||, ||r||), u = H' v + w (Siconos 4.4's gfc3d_compute_error)";
    out["reduced_error_definition"] =
        "||F_nat(r)|| / ||q|| on the reduced problem W = H' M^-1 H, q = w + H' M^-1 f (u = W r + q)";
    Stopwatch watch;
    watch.start();
    const GlobalReduction reduction(problem);  // M factored once; every row's reduced error uses it
    watch.pause();
    out["reduction_seconds"] = watch.seconds();
    char line[256];
    std::snprintf(line, sizeof line, "%-14s %-15s %8s %10s %12s %12s\n", "solver", "status", "iters", "time_s",
                  "fclib_error", "reduced_err");
    table += line;
    for (const std::string& solver : solvers) {
        FrictionRun run;
        if (solver == "mprgp-tresca-fp" || solver == "mprgp+ica-friction") {
            // On the reduced problem, judged like nsgs on the global one: the global error at (r, v).
            run = our_local_run(reduction.local(), solver, s);
            if (run.r.size() == reduction.local().q.size() && run.r.allFinite()) {
                const double reduced_error = run.error;
                run.error = global_relative_error(problem, run.r, reduction.velocity(run.r), &run.u);
                run.note += std::string(run.note.empty() ? "" : "; ") + "on the reduced problem W = H' M^-1 H (error " +
                            format_g(reduced_error) + "), v = M^-1 (H r + f)";
                if (run.status == "converged" && !(run.error <= s.tol)) run.status = "stalled";
            }
        } else if (solver == "nsgs") {
            run = friction_nsgs_global(problem, reduction, nsgs_settings(s)).run;
        } else {
            run = siconos_gfc3d_solve(problem, solver.substr(8), s.max_iterations, s.tol, s.time_limit).run;
        }
        const double reduced = run.r.size() == reduction.local().q.size() && run.r.allFinite()
                                   ? fclib_relative_error(reduction.local(), run.r)
                                   : INFINITY;
        nlohmann::json row;
        report(solver, run, reduced, table, row);
        row["reduced_error"] = reduced;
        out["runs"].push_back(row);
    }
}

}  // namespace

int cmd_friction_solve(const Args& args)
{
    const CommandLine cl("friction-solve", args, {"--solver", "--tol", "--max-iterations", "--time-limit", "--json"},
                         {});
    if (cl.help()) {
        std::cout
            << "usage: " << FRICTION_SOLVE_USAGE
            << "\n  Solves an FCLIB frictional problem with its friction by each --solver (default: all seven),\n"
               "  starting from r = 0, and prints the FCLIB relative error computed by the harness, iterations\n"
               "  and wall time. converged: that error <= --tol (default 1e-8).\n"
               "  fclib_local (u = W r + q): fclib_error = ||F_nat(r)|| / ||q|| (Acary et al. 2018);\n"
               "    siconos_err: the same numerator over max(||q||, ||u||, ||r||), as Siconos 4.4 scales it.\n"
               "  fclib_global (M v = H r + f, u = H'v + w): fclib_error = Siconos 4.4's gfc3d_compute_error\n"
               "    (equilibrium + complementarity); reduced_err: ||F_nat(r)|| / ||q|| on the reduced problem\n"
               "    W = H' M^-1 H, q = w + H' M^-1 f (sparse Cholesky of M).\n"
               "  nsgs: ours (solvers/friction/friction_nsgs.hpp; on a global file, on its reduced problem);\n"
               "  mprgp-tresca-fp: Coulomb as a fixed point on Tresca's slip bounds over MPGP; mprgp+ica-friction:\n"
               "  frictionless MPRGP on W_NN, then nsgs from it (on a global file, on its reduced problem;\n"
               "  docs/friction.md).\n"
               "  siconos-*: Siconos' fc3d (local) or gfc3d (global) NSGS, NSN_AC, PROX and ADMM in a child\n"
               "  process (docs/peers.md).\n";
        return 0;
    }
    cl.expect_positional(1, 1, FRICTION_SOLVE_USAGE);
    const std::string path = cl.positional()[0];
    Settings s;
    s.tol = cl.number("--tol", 1e-8);
    s.max_iterations = cl.integer("--max-iterations", 10000);
    s.time_limit = cl.number("--time-limit", 60.0);
    if (!(s.tol > 0.0)) throw InputError("--tol: must be > 0");
    if (s.max_iterations < 1) throw InputError("--max-iterations: must be >= 1");
    if (!(s.time_limit >= 0.0)) throw InputError("--time-limit: must be >= 0");
    std::vector<std::string> solvers = cl.values("--solver");
    if (solvers.empty()) solvers = SOLVERS;
    for (const std::string& solver : solvers)
        if (std::find(SOLVERS.begin(), SOLVERS.end(), solver) == SOLVERS.end())
            throw InputError("--solver: unknown frictional solver '" + solver +
                             "' (nsgs, mprgp-tresca-fp, mprgp+ica-friction, siconos-nsgs, siconos-nsn, "
                             "siconos-prox, siconos-admm)");
    if (cl.has("--json")) cl.path("--json");
    for (const std::string& solver : solvers)
        if (!is_ours(solver) && !siconos_fc3d_built())
            throw InputError("--solver: " + solver +
                             " is not built (install libsiconos-numerics-dev and reconfigure with CB_PEERS=ON)");

    FrictionLocal local;
    FrictionGlobal global;
    std::string kind;
    if (sniff_format(path) == FileFormat::SICONOS_DAT) {
        local = read_siconos_dat_friction(path);
        kind = "siconos_dat_local";
    } else {
        kind = read_fclib_friction(path, local, global);
    }
    const bool is_global = kind == "fclib_global";
    const Vec& mu = is_global ? global.mu : local.mu;
    nlohmann::json out = {{"file", path},
                          {"kind", kind},
                          {"contacts", mu.size()},
                          {"mu_min", mu.minCoeff()},
                          {"mu_max", mu.maxCoeff()},
                          {"tol", s.tol},
                          {"runs", nlohmann::json::array()}};
    // The table is printed whole at the end: a solver that refuses the problem (nsgs on a W_ii
    // that is not positive definite, an M that is not) leaves no partial output.
    std::string table;
    if (is_global)
        solve_global(global, solvers, s, table, out);
    else
        solve_local(local, solvers, s, table, out);
    if (cl.has("--json")) write_json_atomic(cl.path("--json"), out);
    std::cout << table;
    return 0;
}

}  // namespace cb
