#pragma once
/// The simulator behind `contactbench simulate`: steps a scene with backward Euler (one QP per
/// Newton step), detects collisions once per step, solves each QP with a registry solver, and
/// writes snapshots (.qpsnap), steps.csv, frames.csv, a PNG strip and OBJ frames. Each stage of a
/// step (detection, assembly, snapshot writing, solve) is timed and its peak resident memory read.
///
/// Detection happens once per time step at the start positions x_n (the authors' DCD), or at
/// the inertial prediction x_n + h v_n with "detection": {"at": "predicted"}; the rows found are
/// used by every Newton step of that time step.
#include "sim/collision/dcd.hpp"
#include "sim/fem_corotated.hpp"
#include "sim/integrator.hpp"
#include "sim/scene.hpp"
#include "solvers/core/solver.hpp"

#include <csignal>
#include <cstdint>
#include <functional>
#include <iosfwd>
#include <memory>
#include <optional>
#include <string>

namespace cb::sim {

/// One step's QP, to be solved and judged as `contactbench solve` judges a snapshot.
struct StepSolveRequest {
    const Qp* qp = nullptr;         ///< every detected row
    std::string solver;             ///< registry name
    nlohmann::json settings;        ///< the solver's settings
    std::string decouple = "auto";  ///< auto | none | authors | random | depth (harness/runner.hpp RunOptions)
    std::uint64_t decouple_seed = 0;
    Vec* eigenvector = nullptr;  ///< warm state carried from step to step
};

/// The step's result and its verdict on the ORIGINAL QP (all detected rows).
struct StepSolveOutcome {
    Vec x;
    std::string status;         ///< the run's status: converged, solved_relaxation, unconfirmed, or the solver's
    std::string solver_status;  ///< the solver's own word
    long iterations = 0;
    double accuracy = 0;         ///< the accuracy error e on the original QP
    double accuracy_solved = 0;  ///< e on the QP the solver solved (== accuracy when no row was dropped)
    long rows_solved = 0;
    double solve_s = 0;  ///< the solver's setup + solve
};

/// Solves and judges one step. The harness supplies one built on run_solver
/// (harness/sim_step_solver.hpp), so that `simulate` judges steps exactly as `solve` does; left
/// unset (stress families, solver tests), the step gets the solver's own status and no verdict.
using StepSolver = std::function<StepSolveOutcome(const StepSolveRequest&)>;

struct SimulatorOptions {
    std::string out_dir;               ///< empty: write nothing (tests)
    std::string solver;                ///< overrides the scene's solver when not empty
    bool snapshots = true;             ///< false: --no-snapshots
    long frames = -1;                  ///< overrides the scene's frame count when >= 0
    std::ostream* progress = nullptr;  ///< one line per frame
    std::string data_dir;              ///< --data (recorded in simulation.json)
    StepSolver solve_step;             ///< solves and judges each step's QP; unset: the solver's own status, no verdict
    std::string decouple =
        "auto";  ///< --decouple: auto (authors' order when the solver needs it) | none | authors | random | depth
    std::uint64_t decouple_seed = 0;  ///< --decouple-seed; step s uses seed + s
    double h = 0;  ///< --h: time step (s) when > 0; the frame keeps its duration (steps per frame scaled)
    /// mu > 0: each step's frictional QP (its friction fields set) goes to solve_step and the stepping
    /// solver, a registry entry (`chains`' baselines), instead of the frictional step (sim/friction_step).
    bool friction_by_solver = false;
    /// --fresh: discard an earlier simulation's output in out_dir first. Without it, out_dir must
    /// hold nothing of a simulation, or an interrupted (or shorter) run of the same inputs, which
    /// is resumed from its last complete frame (sim/resume_state.hpp); anything else is refused.
    bool fresh = false;
    /// Set (to the signal's number) by a SIGINT/SIGTERM handler: the run stops after the frame
    /// being stepped, its tables a complete prefix, resumable (interrupted() is then true).
    const volatile std::sig_atomic_t* stop = nullptr;
};

/// Bump when a change alters what a simulation of the same scene writes (physics, detection,
/// snapshot content): caches keyed on it (plots/reproduce.py) then simulate again.
/// 2: steps.csv judges steps like `solve`; *_rel columns; 3: stage columns;
/// 4: the measure counts each body's rigid motion (free fall is no longer met at x0)
constexpr int SIMULATOR_VERSION = 4;

/// What one QP solve of a step produced.
struct StepRecord {
    long frame = 0, step = 0;
    int newton = 0;
    std::string solver, status;
    long iterations = 0;
    std::string solver_status;   ///< the solver's own word (status is the harness's verdict)
    double accuracy = 0;         ///< the accuracy error e on the original QP (every detected row)
    double accuracy_solved = 0;  ///< e on the QP solved (the kept rows)
    double time_assembly_s = 0, time_detection_s = 0, time_solve_s = 0;
    double time_snapshot_s = 0;     ///< writing the .qpsnap (0: none written)
    double time_solve_stage_s = 0;  ///< the solve stage's wall time: time_solve_s plus decoupling and judging
    /// The process's peak resident memory during each stage (MiB): the high-water mark is reset
    /// when the stage starts and read when it ends (plus the largest forked child's). 0: the stage
    /// did not run in this Newton step; -1: /proc unreadable.
    double peak_detection_mb = 0, peak_assembly_mb = 0, peak_snapshot_mb = 0, peak_solve_mb = 0;
    long rows = 0, rows_solved = 0;
    std::string snapshot;  ///< path written, or empty
};

/// Physical outcome of one frame.
struct FrameRecord {
    long frame = 0;
    double time_s = 0;
    double max_penetration = 0;     ///< max violation of the step's rows after the solve (m)
    double max_detected_depth = 0;  ///< deepest penetration found by detection at the step's start (m)
    double max_penetration_rel = 0, max_detected_depth_rel = 0;  ///< the two above / body_size()
    double kinetic_energy = 0, elastic_energy = 0, max_speed = 0;
    long rows = 0;
    bool blow_up = false;
};

class PartialTable;  // simulator.cpp: a CSV written as .partial, renamed when whole

class Simulator {
public:
    Simulator(Scene scene, SimulatorOptions options);
    ~Simulator();
    /// Runs all frames (stops early after a blow-up, or at options.stop); writes the outputs.
    /// Returns false on blow-up.
    bool run();
    /// Sets options.stop (after construction: the caller installs its handlers once the inputs are valid).
    void set_stop(const volatile std::sig_atomic_t* stop) { m_opt.stop = stop; }
    /// The last run() stopped at options.stop before its last frame (the outputs are resumable).
    bool interrupted() const { return m_interrupted; }
    /// Frames whole in the output (after run(): done before it plus in it).
    long frames_done() const { return m_frame; }
    /// Advances one time step; returns its records (one per Newton step).
    std::vector<StepRecord> step();
    /// Frame statistics at the current state (after a step).
    FrameRecord frame_record() const;

    const Scene& scene() const { return m_scene; }
    const CorotatedFem& fem() const { return *m_fem; }
    const Vec& positions() const { return m_x; }
    const Vec& velocities() const { return m_v; }
    Vec& velocities() { return m_v; }
    long vertices() const { return m_fem->vertices(); }
    long dofs() const { return 3 * m_fem->vertices(); }
    long tets() const { return m_fem->tet_count(); }
    /// Surface of every body at the current positions (global vertex ids renumbered per body).
    std::vector<SurfaceMesh> body_surfaces() const;
    /// The same at other positions of this scene.
    std::vector<SurfaceMesh> surfaces_at(const Vec& x) const;
    /// What a step reads besides the scene and the positions and velocities: the steps taken (the
    /// random order's seed offset) and the power method's warm start. `chains` saves them with x
    /// and v after each frame and restores them to resume bit for bit (sim/chains_state.hpp).
    long steps_done() const { return m_step; }
    const Vec& eigenvector() const { return m_eigenvector; }
    void restore_state(const Vec& x, const Vec& v, const Vec& eigenvector, long steps_done);
    const std::string& solver_name() const { return m_solver_name; }
    /// The last frictional step's NSGS run and contact states (mu > 0; x not kept).
    const FrictionalStepOutcome& last_frictional_step() const { return m_friction_last; }
    /// Frictional steps of this run that did not reach friction_settings.tol.
    long frictional_steps_unsolved() const { return m_friction_unsolved; }
    /// The rows of the last detection.
    const std::vector<ContactRow>& last_rows() const { return m_rows; }
    /// The length penetrations are compared with: the smallest body's largest rest extent (m).
    double body_size() const { return m_body_size; }
    /// Deepest penetration at the current positions (a detection run now; m).
    double penetration_now() const;
    /// Every contact row at the current positions (a detection run now).
    std::vector<ContactRow> contacts_now() const { return m_detector->detect(m_x); }
    /// The time step used (s, after --h) and the steps per frame.
    double step_h() const { return m_scene.step.h; }
    int steps_per_frame() const { return m_scene.steps_per_frame; }

private:
    bool run_frames(long frames, bool write, PartialTable& steps_csv, PartialTable& frames_csv);
    /// Every input of what the simulation writes (scene and mesh file contents, solver and its
    /// settings, decoupling, step, data folder, simulator version): a resume needs the same.
    nlohmann::json resume_identity() const;
    /// Checks out_dir before a run (resume or refuse, see SimulatorOptions::fresh) and restores
    /// the state of a resumed run; returns run()'s result when there is nothing left to do.
    std::optional<bool> prepare_output(long frames, PartialTable& steps_csv, PartialTable& frames_csv);
    void save_resume_state(long frames_done, bool finished, bool blow_up) const;
    std::string snapshot_path(long frame, int newton) const;
    Scene m_scene;
    SimulatorOptions m_opt;
    std::unique_ptr<CorotatedFem> m_fem;
    std::unique_ptr<CollisionDetector> m_detector;
    std::vector<long> m_body_first;   ///< first global vertex of each body
    std::vector<Faces> m_body_faces;  ///< per body, local vertex ids
    Vec m_x, m_v;
    SpMat m_A;
    std::string m_solver_name;
    Vec m_eigenvector;
    std::vector<ContactRow> m_rows;
    long m_frame = 0, m_step = 0;
    double m_last_violation = 0, m_last_depth = 0;
    double m_body_size = 1;
    bool m_nonfinite = false;
    nlohmann::json m_material;
    bool m_peak_reset =
        true;  ///< false once the kernel refused a high-water mark reset (stage peaks are then cumulative)
    bool m_interrupted = false;
    FrictionalStepOutcome m_friction_last;  ///< the last frictional step (mu > 0): its run and contact states
    long m_friction_unsolved = 0;           ///< frictional steps of this run that missed their tolerance
    nlohmann::json m_identity;              ///< resume_identity(), once per run
    std::vector<long> m_strip_frames;  ///< frames pictured so far ...
    std::vector<Vec> m_strip_x;        ///< ... and their positions
};

}  // namespace cb::sim
