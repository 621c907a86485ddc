// contactbench simulate SCENE.json [--frames N] [--out DIR] [--data DIR] [--solver NAME] [--decouple ORDER]
//                       [--decouple-seed S] [--h SECONDS] [--no-snapshots] [--fresh]
#include "harness/cli.hpp"
#include "harness/command_solver.hpp"
#include "harness/commands.hpp"
#include "harness/run_lock.hpp"
#include "harness/sim_step_solver.hpp"
#include "harness/stop_signals.hpp"
#include "harness/suite.hpp"
#include "sim/simulator.hpp"

#include <iostream>

namespace cb {

int cmd_simulate(const Args& args)
{
    const CommandLine cl("simulate", args,
                         {"--frames", "--out", "--data", "--solver", "--decouple", "--decouple-seed", "--h"},
                         {"--no-snapshots", "--version", "--allow-commands", "--fresh"});
    const std::string usage =
        "usage: contactbench simulate SCENE.json [--frames N] [--out DIR] [--data DIR] [--solver NAME]\n"
        "       [--decouple ORDER] [--decouple-seed S] [--h SECONDS] [--no-snapshots] [--allow-commands] [--fresh]\n"
        "  SCENE.json     a scene (keys: scenes/README.md), or one of the authors' .ini scene files\n"
        "  --frames N     simulate N frames instead of the scene's \"frames\"\n"
        "  --out DIR      output folder (default results/sim/<scene name>): snapshots/*.qpsnap (one per\n"
        "                 Newton step), steps.csv, frames.csv, <scene>_strip.png, frames/*.obj\n"
        "  --data DIR     the authors' data folder (resolves \"data:\" mesh paths; default:\n"
        "                 $CB_CACHE/paper-data when `make paper-data` has written it, else none, so\n"
        "                 scenes use their CGAL-data stand-ins)\n"
        "  --solver NAME  stepping solver (default: the scene's, else mprgp); another solver than the scene's\n"
        "                 gets its own defaults plus the scene's common settings (a native stop and its\n"
        "                 tol are the scene solver's own and are not passed on)\n"
        "  --decouple ORDER  which rows a step keeps: auto (default: the authors' order when the solver\n"
        "                 needs decoupled rows, else all), none, authors, random, depth (deepest first)\n"
        "  --decouple-seed S  seed of the random order (step s uses S + s; default 0)\n"
        "  --h SECONDS    time step instead of the scene's; a frame keeps its duration, so it must be a\n"
        "                 whole number of steps (e.g. half the scene's step: two steps per frame)\n"
        "  --no-snapshots write no .qpsnap files\n"
        "  --allow-commands  run a `command` solver (an external program) that the scene names; the scene\n"
        "                 must also say \"allow_commands\": true\n"
        "  --fresh        discard an earlier simulation's output in DIR first\n"
        "  --version      print the simulator version (the key of cached simulations) and exit\n"
        "DIR is locked while the simulation runs (a second one into it exits 2). Without --fresh an earlier\n"
        "output in DIR is never deleted: a run of the same inputs interrupted (or with fewer frames) is\n"
        "resumed from its last whole frame (DIR/resume.state), giving the frames of an uninterrupted run\n"
        "bit for bit; one of the same frames is left as it is; anything else is refused (exit 2).\n"
        "While it runs the tables are steps.csv.partial and frames.csv.partial (rows appended a whole frame\n"
        "at a time); at the end they are renamed and simulation.json (scene, mesh files, data folder,\n"
        "frames, version) is written last. SIGINT or SIGTERM stop it after the frame being stepped, which\n"
        "says where it stopped (exit 128 + the signal): the same command resumes it.\n"
        "The progress line of a frame gives each stage's time and peak resident memory (detection,\n"
        "assembly, snapshot writing, solve; steps.csv has them per Newton step: docs/INTERFACES.md).\n"
        "Each step is judged as `solve` judges a snapshot: status converged only when the error e on the\n"
        "QP with every detected row meets the tolerance, solved_relaxation when only the kept rows do.\n";
    if (cl.has("--version")) {
        std::cout << "simulator " << sim::SIMULATOR_VERSION << "\n";
        return 0;
    }
    if (cl.help()) {
        std::cout << usage;
        return 0;
    }
    cl.expect_positional(1, 1, usage);
    const std::string scene_path = cl.positional()[0];
    // The authors' data: --data, else where `make paper-data` puts it, else none (stand-in meshes).
    const std::string data = paper_data_dir(cl.has("--data"), cl.value("--data"));
    const bool no_data = !cl.has("--data") && data.empty();
    sim::Scene scene = sim::load_scene(scene_path, sim::default_path_roots(scene_path, data));
    if (cl.has("--solver")) {  // another solver gets its own defaults, not the scene solver's settings
        const std::string solver = cl.value("--solver");
        const ReplacedSolverSettings replaced = settings_for_solver(scene.solver, scene.solver_settings, solver);
        if (!replaced.dropped.empty()) {
            std::cerr << "simulate: --solver " << solver << ": the scene's settings for " << scene.solver
                      << " not passed on:";
            for (const std::string& key : replaced.dropped) std::cerr << " " << key;
            std::cerr << " (" << solver << "'s defaults apply; docs/simulator.md)\n";
        }
        scene.solver_settings = replaced.settings;
    }
    require_command_opt_in(cl.value("--solver", scene.solver), scene_path, scene.allow_commands,
                           cl.has("--allow-commands"));
    if (no_data)  // said once the scene is known to be valid, so that an input error stands alone
        std::cerr << "simulate: no authors' data in " << paper_data_cache()
                  << " (`make paper-data` writes it); \"data:\" meshes use their stand-ins\n";
    sim::SimulatorOptions opt;
    opt.out_dir = cl.path("--out", "results/sim/" + scene.name);
    opt.solver = cl.value("--solver");
    opt.data_dir = data;  // the folder actually used, for simulation.json and the caches keyed on it
    opt.snapshots = !cl.has("--no-snapshots");
    opt.frames = cl.integer("--frames", -1);
    if (cl.has("--frames") && opt.frames < 0) throw_input_error("--frames", "", "must be >= 0");
    opt.fresh = cl.has("--fresh");
    opt.progress = &std::cerr;
    opt.solve_step = harness_step_solver();
    opt.decouple = cl.value("--decouple", "auto");
    opt.decouple_seed = static_cast<std::uint64_t>(cl.integer("--decouple-seed", 0));
    if (cl.integer("--decouple-seed", 0) < 0) throw_input_error("--decouple-seed", "", "must be >= 0");
    if (opt.decouple != "auto" && opt.decouple != "none" && opt.decouple != "authors" && opt.decouple != "random" &&
        opt.decouple != "depth")
        throw_input_error("--decouple", "",
                          "expected auto, none, authors, random or depth, got '" + opt.decouple + "'");
    if (cl.has("--h")) {
        opt.h = cl.number("--h", 0.0);
        if (!(opt.h > 0)) throw_input_error("--h", "", "must be > 0 seconds");
    }
    for (const auto& b : scene.bodies)
        std::cerr << scene.name << ": body " << b.name << ": " << b.mesh.vertices() << " vertices, "
                  << b.mesh.tet_count() << " tets from " << b.source << (b.quality.empty() ? "" : "; " + b.quality)
                  << "\n";
    sim::Simulator simulator(std::move(scene), opt);
    std::cerr << simulator.scene().name << ": " << simulator.vertices() << " vertices, " << simulator.dofs()
              << " DOFs, " << simulator.tets() << " tets, solver " << simulator.solver_name() << ", output in "
              << opt.out_dir << "\n";
    if (const sim::FrictionSettings& f = simulator.scene().friction; f.mu > 0.0)
        std::cerr << simulator.scene().name << ": Coulomb friction mu " << f.mu << ": every step solves the contacts' "
                  << "frictional problem with " << f.solver << " to FCLIB error " << f.tol << " (the solver "
                  << simulator.solver_name() << ", --solver and --decouple apply to frictionless steps only)\n";
    lock_output_folder(opt.out_dir, "simulate");
    const volatile std::sig_atomic_t* stop = catch_stop_signals();
    simulator.set_stop(stop);
    simulator.run();
    if (simulator.interrupted()) {
        std::cerr << "simulate: stopped by signal " << *stop << " after frame " << simulator.frames_done() - 1 << ": "
                  << simulator.frames_done() << " whole frames in " << opt.out_dir
                  << " (steps.csv.partial, frames.csv.partial); the same command resumes it\n";
        return stopped_exit_status(*stop);
    }
    return 0;
}

}  // namespace cb
