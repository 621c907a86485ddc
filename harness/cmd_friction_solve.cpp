// contactbench friction-solve: an FCLIB local problem solved with its friction (W, q, mu), by our
// NSGS or Siconos' fc3d solvers, each judged by the FCLIB relative error the harness computes.
#include "harness/cli.hpp"
#include "harness/commands.hpp"
#include "harness/results.hpp"
#include "problems/fclib_io.hpp"
#include "solvers/friction_error.hpp"
#include "solvers/friction_nsgs.hpp"
#include "solvers/mprgp_tresca.hpp"
#include "solvers/peers/siconos_fc3d.hpp"

#include <nlohmann/json.hpp>
#include <algorithm>
#include <cstdio>
#include <iostream>

namespace cb {

namespace {

const char* const USAGE =
    "contactbench friction-solve FILE.hdf5 [--solver nsgs|siconos-nsgs|siconos-nsn|mprgp-tresca-fp|\n"
    "                            mprgp+ica-friction ...] [--tol T]\n"
    "                            [--max-iterations N] [--time-limit S] [--json FILE]";

}  // namespace

int cmd_friction_solve(const Args& args)
{
    const CommandLine cl("friction-solve", args, {"--solver", "--tol", "--max-iterations", "--time-limit", "--json"},
                         {});
    if (cl.help()) {
        std::cout << "usage: " << USAGE
                  << "\n  Solves an FCLIB fclib_local problem with its friction (u = W r + q, Coulomb's law per\n"
                     "  contact) by each --solver (default: all five), starting from r = 0, and prints the\n"
                     "  FCLIB relative natural-map error ||F_nat(r)|| / ||q|| computed by the harness (Acary et\n"
                     "  al. 2018), iterations and wall time. converged: that error <= --tol (default 1e-8).\n"
                     "  siconos_err: the same numerator over max(||q||, ||u||, ||r||), as Siconos 4.4 scales it.\n"
                     "  nsgs: ours (solvers/friction_nsgs.hpp); siconos-nsgs, siconos-nsn: Siconos' fc3d NSGS\n"
                     "  and NSN_AC in a child process (docs/peers.md); mprgp-tresca-fp: Coulomb as a fixed point on\n"
                     "  Tresca's slip bounds over MPGP; mprgp+ica-friction: frictionless MPRGP on W_NN, then\n"
                     "  nsgs from it (solvers/mprgp_tresca.hpp, docs/friction.md).\n";
        return 0;
    }
    cl.expect_positional(1, 1, USAGE);
    const std::string path = cl.positional()[0];
    const double tol = cl.number("--tol", 1e-8);
    const long max_iterations = cl.integer("--max-iterations", 10000);
    const double time_limit = cl.number("--time-limit", 60.0);
    if (!(tol > 0.0)) throw InputError("--tol: must be > 0");
    if (max_iterations < 1) throw InputError("--max-iterations: must be >= 1");
    if (!(time_limit >= 0.0)) throw InputError("--time-limit: must be >= 0");
    std::vector<std::string> solvers = cl.values("--solver");
    const std::vector<std::string> ours = {"nsgs", "mprgp-tresca-fp", "mprgp+ica-friction"};
    auto is_ours = [&](const std::string& s) { return std::find(ours.begin(), ours.end(), s) != ours.end(); };
    if (solvers.empty()) solvers = {"nsgs", "siconos-nsgs", "siconos-nsn", "mprgp-tresca-fp", "mprgp+ica-friction"};
    for (const std::string& s : solvers)
        if (!is_ours(s) && s != "siconos-nsgs" && s != "siconos-nsn")
            throw InputError("--solver: unknown frictional solver '" + s +
                             "' (nsgs, siconos-nsgs, siconos-nsn, mprgp-tresca-fp, mprgp+ica-friction)");
    if (cl.has("--json")) cl.path("--json");
    for (const std::string& s : solvers)
        if (!is_ours(s) && !siconos_fc3d_built())
            throw InputError("--solver: " + s +
                             " is not built (install libsiconos-numerics-dev and reconfigure with CB_PEERS=ON)");

    const FrictionLocal problem = read_fclib_local_friction(path);
    nlohmann::json out = {{"file", path},
                          {"contacts", problem.contacts()},
                          {"mu_min", problem.mu.minCoeff()},
                          {"mu_max", problem.mu.maxCoeff()},
                          {"tol", tol},
                          {"error_definition", "||r - P_K(r - (u + mu ||u_T|| e_n))||_2 / ||q||_2, u = W r + q"},
                          {"siconos_scaled_error_definition", "the same numerator / max(||q||, ||u||, ||r||) "
                                                              "(Siconos 4.4's fc3d_compute_error)"},
                          {"runs", nlohmann::json::array()}};
    // The table is printed whole at the end: a solver that refuses the problem (nsgs on a W_ii
    // that is not positive definite) leaves no partial output.
    std::string table;
    char line[256];
    std::snprintf(line, sizeof line, "%-14s %-15s %8s %10s %12s %12s\n", "solver", "status", "iters", "time_s",
                  "fclib_error", "siconos_err");
    table += line;
    for (const std::string& s : solvers) {
        FrictionRun run;
        if (s == "nsgs") {
            FrictionNsgsSettings settings;
            settings.tol = tol;
            settings.max_iterations = max_iterations;
            settings.time_limit_s = time_limit;
            run = friction_nsgs(problem, settings);
        } else if (s == "mprgp-tresca-fp") {
            MprgpTrescaSettings settings;
            settings.tol = tol;
            settings.max_inner = max_iterations;
            settings.time_limit_s = time_limit;
            run = mprgp_tresca_fp(problem, settings).run;
        } else if (s == "mprgp+ica-friction") {
            MprgpIcaFrictionSettings settings;
            settings.tol = tol;
            settings.max_mprgp = max_iterations;
            settings.max_sweeps = max_iterations;
            settings.time_limit_s = time_limit;
            run = mprgp_ica_friction(problem, settings);
        } else {
            run = siconos_fc3d_solve(problem, s.substr(8), max_iterations, tol, time_limit);
        }
        const double siconos_scaled = siconos_relative_error(problem, run.r);
        std::snprintf(line, sizeof line, "%-14s %-15s %8ld %10.4f %12.3e %12.3e\n", s.c_str(), run.status.c_str(),
                      run.iterations, run.seconds, run.error, siconos_scaled);
        table += line;
        nlohmann::json row = {{"solver", s},
                              {"status", run.status},
                              {"iterations", run.iterations},
                              {"seconds", run.seconds},
                              {"fclib_error", run.error}};
        if (run.native_error >= 0.0) row["native_error"] = run.native_error;
        if (!run.note.empty()) row["note"] = run.note;
        out["runs"].push_back(row);
    }
    if (cl.has("--json")) write_json_atomic(cl.path("--json"), out);
    std::cout << table;
    return 0;
}

}  // namespace cb
