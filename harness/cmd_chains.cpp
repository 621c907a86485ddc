// contactbench chains SCENE.json [--frames N] [--out DIR] [--data DIR] [--exact NAME] [--orders LIST]
//                     [--h SECONDS] [--decouple-seed S] [--fresh]
// The price of decoupling along whole chains (docs/simulator.md "The price of decoupling").
#include "harness/cli.hpp"
#include "harness/command_solver.hpp"
#include "harness/commands.hpp"
#include "harness/run_lock.hpp"
#include "harness/sim_step_solver.hpp"
#include "harness/stop_signals.hpp"
#include "harness/suite.hpp"
#include "sim/chains.hpp"
#include "solvers/core/format_number.hpp"
#include "solvers/core/registry.hpp"

#include <filesystem>
#include <iostream>
#include <sstream>

namespace cb {

namespace {
/// The exact chains' tolerances on e: the reference, and the looser one whose distance to it is
/// the noise floor (what a tolerance change alone does to a chaotic chain).
constexpr double REFERENCE_TOL = 1e-8, NOISE_TOL = 1e-6;

/// Runs the chains (locked output folder, signals) and reports a stop; the exit status.
int run_locked_chains(const std::string& scene_path, const sim::PathRoots& roots, sim::ChainOptions& opt)
{
    lock_output_folder(opt.out_dir, "chains");
    opt.stop = catch_stop_signals();
    long frames_done = 0;
    sim::run_chains([&] { return sim::load_scene(scene_path, roots); }, opt, &frames_done);
    if (*opt.stop != 0 &&
        !std::filesystem::exists(opt.out_dir + "/chains.json")) {  // not a signal after the last frame
        std::cerr << "chains: stopped by signal " << *opt.stop << " after frame " << frames_done - 1 << ": "
                  << opt.out_dir << "/chains.csv holds frames 0 to " << frames_done - 1
                  << " of every chain; no chains.json (the same command resumes them)\n";
        return stopped_exit_status(*opt.stop);
    }
    return 0;
}

/// A frictional scene's chains: the exact frictional step against the paper's two baselines and no
/// friction at all (docs/friction.md "The price along a chain").
int run_frictional_chains(const CommandLine& cl, const std::string& scene_path, const sim::PathRoots& roots,
                          const sim::Scene& scene, sim::ChainOptions& opt)
{
    for (const char* flag : {"--exact", "--orders", "--control"})
        if (cl.has(flag))
            throw_input_error(flag, "",
                              "applies to frictionless scenes; " + scene.name +
                                  " has mu = " + format_g(scene.friction.mu) +
                                  ", whose chains are exact, exact-tol1e-6, bmf03, ica-friction and frictionless");
    sim::ChainSpec exact{"exact", scene.friction.solver, {{"tol", scene.friction.tol}}, "none"};
    exact.friction_step = true;
    sim::ChainSpec noise{"exact-tol1e-6", scene.friction.solver, {{"tol", NOISE_TOL}}, "none"};
    noise.friction_step = true;
    opt.chains = {exact, noise, {"bmf03", "mprgp+bmf03", {{"tol", REFERENCE_TOL}}, "none"}};
    if (builtin_registry().contains("mprgp+ica-friction"))
        opt.chains.push_back({"ica-friction", "mprgp+ica-friction", {{"tol", REFERENCE_TOL}}, "none"});
    opt.chains.push_back({"frictionless", "mprgp-coupled", {{"tol", REFERENCE_TOL}}, "none"});
    opt.reference = "exact";
    opt.render_chain = "bmf03";
    std::cerr << scene.name << ": frictional chains exact (" << scene.friction.solver << ", FCLIB error "
              << format_g(scene.friction.tol) << "), exact-tol1e-6";
    for (size_t c = 2; c < opt.chains.size(); ++c)
        std::cerr << ", " << opt.chains[c].label << " (" << opt.chains[c].solver << ")";
    std::cerr << "; output in " << opt.out_dir << "\n";
    return run_locked_chains(scene_path, roots, opt);
}

}  // namespace

int cmd_chains(const Args& args)
{
    const CommandLine cl("chains", args,
                         {"--frames", "--out", "--data", "--exact", "--orders", "--h", "--decouple-seed"},
                         {"--control", "--allow-commands", "--fresh"});
    const std::string usage =
        "usage: contactbench chains SCENE.json [--frames N] [--out DIR] [--data DIR] [--exact NAME]\n"
        "       [--orders LIST] [--h SECONDS] [--decouple-seed S] [--control] [--allow-commands] [--fresh]\n"
        "Steps the scene from the same start with several chains at once and compares them frame by frame:\n"
        "  exact          the exact solver on every detected row, tol 1e-8 (the reference)\n"
        "  exact-tol1e-6  the same at tol 1e-6: its distance to the reference is the noise floor\n"
        "  ORDER          the scene's solver (mprgp) with its settings on the rows the order keeps, for\n"
        "                 each ORDER of --orders (default authors,random,depth)\n"
        "  --frames N     frames (default: the scene's)\n"
        "  --out DIR      output folder (default results/chains/<scene name>): chains.csv (one row per\n"
        "                 frame and chain), chains.json (written last), <scene>_largest_difference.png\n"
        "                 and <scene>_largest_penetration.png (every chain side by side, in the order\n"
        "                 above, at the frame where the authors' chain is farthest from the reference,\n"
        "                 and where it penetrates deepest)\n"
        "  --data DIR     the authors' data folder (as for simulate)\n"
        "  --exact NAME   the exact solver (default mprgp-coupled: MPRGP on every detected row, any J;\n"
        "                 converged at tol 1e-8 and 1e-6 on every step of the paper scenes' chains; its\n"
        "                 tol acts on e, so the noise floor means something, except in free fall at a\n"
        "                 small step, where a start point within tol 1e-6 is returned and the 1e-6 chain\n"
        "                 does not fall (docs/simulator.md). pgs: projected Gauss-Seidel on the exact\n"
        "                 dual, up to 2000 rows; the direct active-set gives the same chain at both\n"
        "                 tolerances)\n"
        "  --h SECONDS    time step instead of the scene's (a frame keeps its duration)\n"
        "  --decouple-seed S  seed of the random order (step s uses S + s; default 0)\n"
        "  --control      one more chain, authors-exact: the exact solver (tol 1e-8) on the rows the\n"
        "                 authors' order keeps, which separates the price of the dropped rows from the\n"
        "                 decoupled solver's own error\n"
        "  --allow-commands  run a `command` solver (an external program) that the scene names; the scene\n"
        "                 must also say \"allow_commands\": true\n"
        "  --fresh        discard an earlier chains run's outputs in DIR (without it they are refused, exit 2)\n"
        "On a scene with friction (mu > 0) the chains are instead (docs/friction.md \"The price along a chain\"):\n"
        "  exact          the simulator's frictional step (the scene's friction_settings; the reference)\n"
        "  exact-tol1e-6  the same at FCLIB error 1e-6: the noise floor\n"
        "  bmf03          mprgp+bmf03: frictionless mprgp-coupled (tol 1e-8), then BMF03's velocity update\n"
        "  ica-friction   mprgp+ica-friction, when this build registers it on snapshots\n"
        "  frictionless   mprgp-coupled (tol 1e-8) on the step's QP with mu = 0: friction's whole price\n"
        "  and --exact, --orders and --control are refused.\n"
        "DIR is locked while the chains run (a second command into it exits 2). While they run the table is\n"
        "DIR/chains.csv.partial, and after each whole frame every chain's state is saved in DIR/chains.state\n"
        "(removed once chains.json is written), so a killed run resumes too. SIGINT or SIGTERM\n"
        "stop them after the frame being stepped: chains.csv then holds every chain's whole frames, no\n"
        "chains.json is written, and the exit status is 128 + the signal. The same command resumes them from\n"
        "the last whole frame, giving chains.csv and chains.json bit for bit as an uninterrupted run; a run\n"
        "of other inputs (scene file content, frames, orders, h, seed, exact solver) in DIR is refused with\n"
        "exit 2 naming what changed, and so is a finished run (chains.json): --fresh runs them again.\n";
    if (cl.help()) {
        std::cout << usage;
        return 0;
    }
    cl.expect_positional(1, 1, usage);
    const std::string scene_path = cl.positional()[0];
    const std::string data = paper_data_dir(cl.has("--data"), cl.value("--data"));
    const sim::PathRoots roots = sim::default_path_roots(scene_path, data);
    const sim::Scene scene = sim::load_scene(scene_path, roots);  // validated once, before any chain

    sim::ChainOptions opt;
    opt.out_dir = cl.value("--out", "results/chains/" + scene.name);
    opt.frames = cl.integer("--frames", -1);
    if (cl.has("--frames") && opt.frames < 0) throw_input_error("--frames", "", "must be >= 0");
    if (cl.has("--h")) {
        opt.h = cl.number("--h", 0.0);
        if (!(opt.h > 0)) throw_input_error("--h", "", "must be > 0 seconds");
    }
    const long seed = cl.integer("--decouple-seed", 0);
    if (seed < 0) throw_input_error("--decouple-seed", "", "must be >= 0");
    opt.decouple_seed = static_cast<std::uint64_t>(seed);
    opt.solve_step = harness_step_solver();
    opt.progress = &std::cerr;
    opt.data_dir = data;
    opt.fresh = cl.has("--fresh");

    if (scene.friction.mu > 0.0) return run_frictional_chains(cl, scene_path, roots, scene, opt);
    const std::string exact = cl.value("--exact", "mprgp-coupled");
    if (!builtin_registry().contains(exact))
        throw_input_error("--exact", "", "no solver named '" + exact + "' (contactbench solvers lists them)");
    opt.chains.push_back({"exact", exact, {{"tol", REFERENCE_TOL}}, "none"});
    opt.chains.push_back({"exact-tol1e-6", exact, {{"tol", NOISE_TOL}}, "none"});
    opt.reference = "exact";
    std::stringstream orders(cl.value("--orders", "authors,random,depth"));
    std::string order;
    while (std::getline(orders, order, ',')) {
        if (order != "authors" && order != "random" && order != "depth")
            throw_input_error("--orders", "",
                              "expected a comma-separated list of authors, random, depth; got '" + order + "'");
        opt.chains.push_back({order, scene.solver, scene.solver_settings, order});
        if (opt.render_chain.empty() || order == "authors") opt.render_chain = order;
    }
    if (cl.has("--control")) opt.chains.push_back({"authors-exact", exact, {{"tol", REFERENCE_TOL}}, "authors"});
    for (const auto& chain : opt.chains)
        require_command_opt_in(chain.solver, scene_path, scene.allow_commands, cl.has("--allow-commands"));
    std::cerr << scene.name << ": chains exact (" << exact << ", tol 1e-8), exact-tol1e-6 (" << exact << ")";
    for (size_t c = 2; c < opt.chains.size(); ++c)
        std::cerr << ", " << opt.chains[c].label << " (" << opt.chains[c].solver << ")";
    std::cerr << "; output in " << opt.out_dir << "\n";
    return run_locked_chains(scene_path, roots, opt);
}

}  // namespace cb
