#pragma once
/// Chain comparison (`contactbench chains`): the same scene stepped from the same start by several
/// chains at once (each its own solver, settings and decoupling order), compared frame by frame
/// with a reference chain: penetration, rows dropped, the distance between the chains' positions
/// and the energies. docs/simulator.md "The price of decoupling" says what each figure means.
#include "sim/simulator.hpp"

#include <csignal>
#include <functional>
#include <iosfwd>
#include <string>
#include <vector>

namespace cb::sim {

/// One chain: a stepping solver, its settings (merged over the scene's when the solver is the
/// scene's) and the decoupling order (auto | none | authors | random | depth).
struct ChainSpec {
    std::string label, solver;
    nlohmann::json settings = nlohmann::json::object();
    std::string decouple = "auto";
    /// A frictional scene (mu > 0) only. true: the simulator's frictional step (sim/friction_step, the
    /// scene's friction_settings; `solver` names its method, `settings` may set only its "tol").
    /// false: each step's frictional QP goes to `solver`, a registry entry (mprgp+bmf03; a frictionless
    /// solver solves it with mu = 0).
    bool friction_step = false;
};

struct ChainOptions {
    std::string out_dir;  ///< chains.csv, chains.json, <scene>_largest_difference.png
    long frames = -1;     ///< the scene's when < 0
    double h = 0;         ///< time step override (SimulatorOptions::h)
    std::uint64_t decouple_seed = 0;
    std::vector<ChainSpec> chains;
    std::string reference;     ///< label of the chain the others are measured against
    std::string render_chain;  ///< the chain whose largest distance (and penetration) picks the pictured frames
    StepSolver solve_step;
    std::ostream* progress = nullptr;
    std::string data_dir;  ///< recorded in chains.json
    bool fresh = false;    ///< discard an earlier run's outputs in out_dir (without it: refused)
    /// Set (to the signal's number) by a SIGINT/SIGTERM handler: the chains stop after the frame
    /// being stepped; chains.csv then holds every chain's whole frames and no chains.json is written.
    const volatile std::sig_atomic_t* stop = nullptr;
};

/// Bump when what `chains` writes for the same inputs changes (caches key on it with the
/// simulator's version).
// 2: the picture at the largest penetration; 3: exact = mprgp-coupled; 4: vertices_inside;
// 5: frictional scenes (friction_step chains), travel_rel and drift_rel
constexpr int CHAINS_VERSION = 5;

/// Mean of the vertices' positions (the centroid of equal weights; NaN when not finite).
Vec3 vertex_mean(const Vec& x);

/// Per-vertex distance between two position vectors of the same mesh: RMS and max over vertices.
struct ChainDistance {
    double rms = 0, max = 0;
};
ChainDistance chain_distance(const Vec& a, const Vec& b);

/// Runs every chain in lockstep, each on its own copy of the scene from `load_scene` (scenes own
/// their obstacles, so they are loaded, not copied), and writes the outputs (through AtomicFile: temporaries
/// until whole, then renamed; chains.json last). Returns false when some chain blew up (it stops;
/// the rest go on). An earlier run's outputs in out_dir are refused unless options.fresh. Stopped
/// by options.stop, it sets `frames_done` to the frames whole in chains.csv (else to all of them).
bool run_chains(const std::function<Scene()>& load_scene, const ChainOptions& options, long* frames_done = nullptr);

}  // namespace cb::sim
