#include "sim/simulator.hpp"

#include "problems/io_util.hpp"
#include "problems/qpsnap.hpp"
#include "sim/mesh_io.hpp"
#include "sim/partial_table.hpp"
#include "sim/render.hpp"
#include "sim/resume_state.hpp"
#include "solvers/core/format_number.hpp"
#include "solvers/core/peak_memory.hpp"
#include "solvers/core/registry.hpp"
#include "solvers/measure/accuracy.hpp"
#include "solvers/mprgp/decouple.hpp"

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fcntl.h>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <limits>
#include <ostream>
#include <set>
#include <sstream>
#include <sys/stat.h>
#include <unistd.h>

namespace cb::sim {
namespace {
double now_s() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }
void make_dirs(const std::string& path)
{
    std::string cur;
    std::stringstream ss(path);
    std::string part;
    if (!path.empty() && path[0] == '/') cur = "/";
    while (std::getline(ss, part, '/')) {
        if (part.empty()) continue;
        cur += part + "/";
        ::mkdir(cur.c_str(), 0755);
    }
    struct stat st {};
    if (::stat(path.c_str(), &st) != 0 || !S_ISDIR(st.st_mode))
        throw_input_error(path, "--out", "cannot create the output folder: " + std::string(std::strerror(errno)));
}

/// One stage of a step, measured: its wall time and the process's peak resident memory while it
/// ran. The high-water mark is reset when the stage starts, so that a stage's peak is its own and
/// not that of an earlier, larger stage (solvers/core/peak_memory.hpp); forked children (peers solving
/// in a child) add their largest peak, as in a run record.
class StageMeter {
public:
    StageMeter()
    {
        reset_peak_memory();
        m_start = now_s();
    }
    /// Ends the stage. `reset_worked` is cleared when the kernel refused the reset.
    void stop(double& seconds, double& peak_mb, bool& reset_worked) const
    {
        seconds = now_s() - m_start;
        const PeakMemory peak = read_peak_memory();
        peak_mb = peak.process_bytes < 0 ? -1.0 : double(peak.process_bytes + peak.children_bytes) / (1024.0 * 1024.0);
        reset_worked = reset_worked && peak.reset;
    }

private:
    double m_start = 0;
};

/// The largest peak of each stage over some steps, for the progress log.
struct StagePeaks {
    double detection = 0, assembly = 0, snapshot = 0, solve = 0;
    void add(const StepRecord& r)
    {
        detection = std::max(detection, r.peak_detection_mb);
        assembly = std::max(assembly, r.peak_assembly_mb);
        snapshot = std::max(snapshot, r.peak_snapshot_mb);
        solve = std::max(solve, r.peak_solve_mb);
    }
    void add(const StagePeaks& p)
    {
        detection = std::max(detection, p.detection);
        assembly = std::max(assembly, p.assembly);
        snapshot = std::max(snapshot, p.snapshot);
        solve = std::max(solve, p.solve);
    }
    std::string text() const
    {
        char out[128];
        std::snprintf(out, sizeof out, "det %.0f asm %.0f snap %.0f solve %.0f", detection, assembly, snapshot, solve);
        return out;
    }
};

}  // namespace

namespace {

/// What an earlier simulation left in `dir` ("simulation.json, steps.csv.partial, 188 snapshots"),
/// empty when nothing: the files remove_old_output removes.
std::string old_output(const std::string& dir, const std::string& scene_name)
{
    namespace fs = std::filesystem;
    std::error_code ec;
    std::string found;
    const auto add = [&found](const std::string& what) { found += (found.empty() ? "" : ", ") + what; };
    for (const char* name :
         {"simulation.json", "steps.csv", "frames.csv", "steps.csv.partial", "frames.csv.partial", "resume.state"})
        if (fs::exists(fs::symlink_status(fs::path(dir) / name, ec))) add(name);
    if (fs::exists(fs::symlink_status(fs::path(dir) / (scene_name + "_strip.png"), ec))) add(scene_name + "_strip.png");
    using Kind = std::pair<const char*, const char*>;  // (folder, extension)
    for (const Kind& kind : {Kind{"snapshots", ".qpsnap"}, Kind{"frames", ".obj"}}) {
        const auto& [sub, ext] = kind;
        long count = 0;
        if (fs::is_directory(fs::path(dir) / sub, ec))
            for (const auto& entry : fs::directory_iterator(fs::path(dir) / sub, ec))
                count += entry.path().extension() == ext;
        if (count > 0)
            add(std::to_string(count) + " " + (std::string(sub) == "snapshots" ? "snapshots" : "OBJ frames"));
    }
    return found;
}

/// Removes the temporaries (NAME.tmp.<pid>) a killed run left in `dir`, snapshots/ and frames/:
/// the caller holds the folder's lock (harness/run_lock.hpp), so no live writer owns them.
long remove_killed_runs_temporaries(const std::string& dir)
{
    namespace fs = std::filesystem;
    std::error_code ec;
    long removed = 0;
    for (const fs::path& folder : {fs::path(dir), fs::path(dir) / "snapshots", fs::path(dir) / "frames"}) {
        if (!fs::is_directory(folder, ec)) continue;
        for (const auto& entry : fs::directory_iterator(folder, ec)) {
            const std::string name = entry.path().filename().string();
            const size_t at = name.rfind(".tmp.");
            if (at == std::string::npos || at + 5 >= name.size() ||
                name.find_first_not_of("0123456789", at + 5) != std::string::npos)
                continue;
            removed += fs::remove(entry.path(), ec) ? 1 : 0;
        }
    }
    return removed;
}

/// Removes the files of an earlier simulation in `dir` (and only those): `simulate --fresh` into
/// an old --out replaces it instead of mixing its snapshots with the old ones.
void remove_old_output(const std::string& dir, const std::string& scene_name)
{
    namespace fs = std::filesystem;
    std::error_code ec;
    for (const char* name :
         {"simulation.json", "steps.csv", "frames.csv", "steps.csv.partial", "frames.csv.partial", "resume.state"})
        fs::remove(fs::path(dir) / name, ec);
    fs::remove(fs::path(dir) / (scene_name + "_strip.png"), ec);
    using Kind = std::pair<const char*, const char*>;  // (folder, extension)
    for (const Kind& kind : {Kind{"snapshots", ".qpsnap"}, Kind{"frames", ".obj"}}) {
        const auto& [sub, ext] = kind;
        const fs::path folder = fs::path(dir) / sub;
        if (!fs::is_directory(folder, ec)) continue;
        for (const auto& entry : fs::directory_iterator(folder, ec))
            if (entry.path().extension() == ext) fs::remove(entry.path(), ec);
    }
}
/// The step solver of callers outside the harness (the stress families, solver tests), which
/// need the chain and its snapshots, not a verdict: the solver's own status; e measured with the
/// solver's multipliers (0 on dropped rows). `simulate` and `chains` use harness_step_solver().
StepSolveOutcome solve_without_verdict(const StepSolveRequest& request)
{
    const Qp& qp = *request.qp;
    const std::unique_ptr<Solver> solver = builtin_registry().create(request.solver, request.settings);
    std::vector<int> kept;
    const bool decouple = request.decouple == "auto" ? solver->requires_decoupled() : request.decouple != "none";
    if (decouple && qp.m() > 0 && !is_decoupled(qp.J)) {
        const DecoupleOrder order =
            request.decouple == "auto" ? DecoupleOrder::AUTHORS : decouple_order_from_string(request.decouple);
        kept = decouple_rows(qp.view(), qp.contacts, order, request.decouple_seed).kept_rows;
    }
    Qp decoupled;
    if (!kept.empty() && static_cast<long>(kept.size()) < qp.m()) decoupled = select_rows(qp, kept);
    const Qp& solved = decoupled.A.size() > 0 ? decoupled : qp;
    SolveContext ctx;
    ctx.eigenvector = request.eigenvector;
    SolverResult res = solver->solve(solved.view(), ctx);
    StepSolveOutcome out;
    out.status = out.solver_status = to_string(res.status);
    out.iterations = res.iterations;
    out.rows_solved = solved.m();
    out.solve_s = res.setup_s + res.solve_s;
    if (res.x.size() == qp.n() && res.x.allFinite()) {
        const Vec lambda = res.lambda.size() == solved.m() ? res.lambda : Vec::Zero(solved.m());
        out.accuracy_solved = accuracy(solved.view(), res.x, lambda).max();
        Vec full = lambda;
        if (&solved != &qp) {
            full = Vec::Zero(qp.m());
            for (size_t k = 0; k < kept.size(); ++k) full[kept[k]] = lambda[static_cast<Eigen::Index>(k)];
        }
        out.accuracy = accuracy(qp.view(), res.x, full).max();
    }
    out.x = std::move(res.x);
    return out;
}

}  // namespace

Simulator::Simulator(Scene scene, SimulatorOptions options) : m_scene(std::move(scene)), m_opt(std::move(options))
{
    // One global numbering: bodies one after another.
    long nv = 0, nt = 0;
    for (const Body& b : m_scene.bodies) {
        nv += b.mesh.vertices();
        nt += b.mesh.tet_count();
    }
    Positions rest(nv, 3);
    Tets tets(nt, 4);
    std::vector<Material> materials(static_cast<size_t>(nt));
    std::vector<CollisionBody> cbodies;
    long v0 = 0, t0 = 0;
    m_material = nlohmann::json::array();
    for (const Body& b : m_scene.bodies) {
        m_body_first.push_back(v0);
        rest.middleRows(v0, b.mesh.vertices()) = b.mesh.positions;
        tets.middleRows(t0, b.mesh.tet_count()) = b.mesh.tets.array() + static_cast<int>(v0);
        for (long t = 0; t < b.mesh.tet_count(); ++t) materials[static_cast<size_t>(t0 + t)] = b.material;
        CollisionBody cb;
        cb.tets = b.mesh.tets.array() + static_cast<int>(v0);
        const Faces local = boundary_faces(b.mesh);
        m_body_faces.push_back(local);
        cb.faces = local.array() + static_cast<int>(v0);
        for (int v : boundary_vertices(local, b.mesh.vertices()))
            cb.surface_vertices.push_back(v + static_cast<int>(v0));
        cbodies.push_back(std::move(cb));
        m_material.push_back({{"body", b.name},
                              {"youngs", b.material.youngs},
                              {"poisson", b.material.poisson},
                              {"density", b.material.density},
                              {"mesh", b.source}});
        v0 += b.mesh.vertices();
        t0 += b.mesh.tet_count();
    }
    m_fem = std::make_unique<CorotatedFem>(rest, tets, materials);
    std::vector<const Obstacle*> obs;
    for (const auto& o : m_scene.obstacles) obs.push_back(o.get());
    m_detector = std::make_unique<CollisionDetector>(std::move(cbodies), std::move(obs), m_scene.detection);
    m_x = Eigen::Map<const Vec>(rest.data(), 3 * nv);
    m_v.resize(3 * nv);
    for (size_t b = 0; b < m_scene.bodies.size(); ++b)
        for (long i = 0; i < m_scene.bodies[b].mesh.vertices(); ++i)
            m_v.segment<3>(3 * (m_body_first[b] + i)) = m_scene.bodies[b].velocity;

    // The stepping solver: the scene's (or --solver), default mprgp; fall back to active-set
    // when mprgp is not registered in this build.
    const SolverRegistry& reg = builtin_registry();
    m_solver_name = m_opt.solver.empty() ? m_scene.solver : m_opt.solver;
    if (m_opt.solver.empty() && m_solver_name == "mprgp" && !reg.contains("mprgp") && reg.contains("active-set")) {
        if (m_opt.progress)
            *m_opt.progress << "simulate: solver 'mprgp' is not registered; stepping with 'active-set'\n";
        m_solver_name = "active-set";
    }
    reg.create(m_solver_name, m_scene.solver_settings);  // validates the name and settings now
    if (m_opt.decouple != "auto" && m_opt.decouple != "none") decouple_order_from_string(m_opt.decouple);
    if (!m_opt.solve_step) m_opt.solve_step = solve_without_verdict;

    // --h: a smaller step keeps the frame's duration, so frames of both runs are the same instants.
    if (m_opt.h > 0) {
        const double frame_s = m_scene.step.h * m_scene.steps_per_frame;
        const double k = std::round(frame_s / m_opt.h);
        if (!(k >= 1) || std::abs(k * m_opt.h - frame_s) > 1e-9 * frame_s)
            throw_input_error("--h", "",
                              "the frame's duration " + std::to_string(frame_s) +
                                  " s (scene step x steps per frame) "
                                  "is not a whole number of steps of " +
                                  std::to_string(m_opt.h) + " s");
        m_scene.step.h = m_opt.h;
        m_scene.steps_per_frame = static_cast<int>(k);
    }
    m_body_size = std::numeric_limits<double>::infinity();
    for (const Body& b : m_scene.bodies) {
        const Positions& p = b.mesh.positions;
        if (p.rows() > 0)
            m_body_size = std::min(m_body_size, (p.colwise().maxCoeff() - p.colwise().minCoeff()).maxCoeff());
    }
    if (!(m_body_size > 0) || !std::isfinite(m_body_size)) m_body_size = 1.0;  // no body (or a flat one): metres
}

Simulator::~Simulator() = default;

std::string Simulator::snapshot_path(long frame, int newton) const
{
    char buf[64];
    std::snprintf(buf, sizeof buf, "_f%04ld_n%d.qpsnap", frame, newton);
    return m_opt.out_dir + "/snapshots/" + m_scene.name + buf;
}

std::vector<StepRecord> Simulator::step()
{
    std::vector<StepRecord> records;
    const double h = m_scene.step.h;
    const Vec x_n = m_x, v_n = m_v;
    const long frame = m_frame;

    const StageMeter detection;
    const Vec x_detect = m_scene.detect_at == "predicted" ? Vec(x_n + h * v_n) : x_n;
    DetectionStats dstats;
    m_rows = m_detector->detect(x_detect, &dstats);
    Qp qp;
    assemble_constraints(m_rows, dofs(), qp.J, qp.c, qp.contacts);
    if (m_scene.friction.mu > 0.0 && qp.m() > 0) {  // the snapshot's frictional fields (a step without rows has none)
        qp.friction.mu = Vec::Constant(qp.m(), m_scene.friction.mu);
        qp.friction.T = tangent_rows(m_rows, dofs());
        qp.friction.cT = qp.friction.T * x_n;  // slip measured from the step's start
        qp.friction.h = h;
        qp.friction.v0 = v_n;
    }
    double time_detection = 0, peak_detection = 0;
    detection.stop(time_detection, peak_detection, m_peak_reset);
    m_last_depth = 0;
    for (const ContactRow& r : m_rows) m_last_depth = std::max(m_last_depth, r.depth);

    Vec x_k = x_n;
    for (int k = 0; k < m_scene.newton_iterations; ++k) {
        StepRecord rec;
        rec.frame = frame;
        rec.step = m_step;
        rec.newton = k;
        rec.solver = m_solver_name;
        rec.time_detection_s = k == 0 ? time_detection : 0.0;
        rec.peak_detection_mb = k == 0 ? peak_detection : 0.0;
        const StageMeter assembly;
        assemble_newton_qp(*m_fem, m_scene.step, x_n, v_n, x_k, m_A, qp.b);
        assembly.stop(rec.time_assembly_s, rec.peak_assembly_mb, m_peak_reset);
        qp.A.swap(m_A);  // Eigen 3.4's SparseMatrix has no move assignment: std::move would copy A
        // Start point: the inertial prediction for the first Newton step, the iterate after.
        qp.x0 = k == 0 ? Vec(x_n + h * v_n) : x_k;
        rec.rows = qp.m();
        const bool in_range = frame >= m_scene.output.snapshot_first &&
                              (m_scene.output.snapshot_last < 0 || frame <= m_scene.output.snapshot_last);
        if (!m_opt.out_dir.empty() && m_opt.snapshots && m_scene.output.snapshots && in_range &&
            m_scene.steps_per_frame == 1) {
            const StageMeter snapshot;
            qp.meta = {
                {"scene", m_scene.name},
                {"frame", frame},
                {"step", m_step},
                {"newton_iteration", k},
                {"h", h},
                {"vertices", vertices()},
                {"tets", tets()},
                {"bodies", m_scene.bodies.size()},
                {"material", m_material},
                {"units", "SI"},
                {"damping", {{"a_M", m_scene.step.a_M}, {"a_K", m_scene.step.a_K}}},
                {"gravity", {m_scene.step.gravity.x(), m_scene.step.gravity.y(), m_scene.step.gravity.z()}},
                {"contacts",
                 {{"rows", qp.m()},
                  {"obstacle_rows", dstats.obstacle_rows},
                  {"inter_body_rows", dstats.inter_body_rows},
                  {"self_rows", dstats.self_rows},
                  {"detect_at", m_scene.detect_at},
                  {"margin", m_scene.detection.margin},
                  {"decoupled", is_decoupled(qp.J)}}},
                {"generator", {{"command", "simulate"}, {"scene_file", m_scene.file}, {"solver", m_solver_name}}}};
            if (m_scene.friction.mu > 0.0)
                qp.meta["friction"] = {{"mu", m_scene.friction.mu}, {"solver", m_scene.friction.solver}};
            rec.snapshot = snapshot_path(frame, k);
            write_qpsnap(rec.snapshot, qp);
            snapshot.stop(rec.time_snapshot_s, rec.peak_snapshot_mb, m_peak_reset);
        }
        if (m_scene.friction.mu > 0.0 && !m_opt.friction_by_solver) {
            // Coulomb friction: the contacts' local problem solved by NSGS, judged by FCLIB's error.
            const StageMeter solve;
            const FrictionalStepOutcome out =
                solve_frictional_step(qp.A, qp.b, m_rows, x_n, m_scene.friction, m_scene.name);
            solve.stop(rec.time_solve_stage_s, rec.peak_solve_mb, m_peak_reset);
            rec.solver = out.run.solver;
            rec.time_solve_s = out.seconds;
            rec.status = out.run.status;
            rec.solver_status = out.run.status;
            rec.iterations = out.run.iterations;
            rec.rows_solved = qp.m();
            rec.accuracy = rec.accuracy_solved = out.run.error;
            m_friction_last = out;
            m_friction_last.x.resize(0);
            if (out.run.status != "converged") ++m_friction_unsolved;
            if (out.x.size() == dofs() && out.x.allFinite()) {
                x_k = out.x;
            } else {
                m_nonfinite = true;
                rec.accuracy = rec.accuracy_solved = std::numeric_limits<double>::quiet_NaN();
            }
            m_last_violation = qp.m() > 0 && x_k.allFinite() ? max_violation(qp.view(), x_k) : 0.0;
            m_A.swap(qp.A);
            records.push_back(rec);
            if (m_nonfinite) break;
            continue;
        }
        // Solved and judged by solve_step (in `simulate`, the harness's rule): decoupling, when asked
        // or needed, happens there, and e is measured on this QP with every detected row.
        if (m_eigenvector.size() != dofs()) m_eigenvector.resize(0);
        StepSolveRequest request;
        request.qp = &qp;
        request.solver = m_solver_name;
        request.settings = m_scene.solver_settings;
        request.decouple = m_opt.decouple;
        request.decouple_seed = m_opt.decouple_seed + static_cast<std::uint64_t>(m_step);
        request.eigenvector = &m_eigenvector;
        const StageMeter solve;
        const StepSolveOutcome out = m_opt.solve_step(request);
        solve.stop(rec.time_solve_stage_s, rec.peak_solve_mb, m_peak_reset);
        rec.time_solve_s = out.solve_s;
        rec.status = out.status;
        rec.solver_status = out.solver_status;
        rec.iterations = out.iterations;
        rec.rows_solved = out.rows_solved;
        rec.accuracy = out.accuracy;
        rec.accuracy_solved = out.accuracy_solved;
        if (out.x.size() == dofs() && out.x.allFinite()) {
            x_k = out.x;
        } else {
            m_nonfinite = true;
            rec.accuracy = rec.accuracy_solved = std::numeric_limits<double>::quiet_NaN();
            if (out.x.size() == dofs()) x_k = out.x;
        }
        m_last_violation = qp.m() > 0 && x_k.allFinite() ? max_violation(qp.view(), x_k) : 0.0;
        m_A.swap(qp.A);
        records.push_back(rec);
        if (m_nonfinite) break;
    }
    m_v = (x_k - x_n) / h;
    m_x = x_k;
    ++m_step;
    return records;
}

FrameRecord Simulator::frame_record() const
{
    FrameRecord r;
    r.frame = m_frame;
    r.time_s = m_step * m_scene.step.h;
    r.max_penetration = m_last_violation;
    r.max_detected_depth = m_last_depth;
    r.max_penetration_rel = m_last_violation / m_body_size;
    r.max_detected_depth_rel = m_last_depth / m_body_size;
    r.rows = static_cast<long>(m_rows.size());
    r.kinetic_energy = kinetic_energy(*m_fem, m_v);
    r.elastic_energy = m_x.allFinite() ? m_fem->energy(m_x) : std::numeric_limits<double>::quiet_NaN();
    for (long i = 0; i < vertices(); ++i) r.max_speed = std::max(r.max_speed, m_v.segment<3>(3 * i).norm());
    r.blow_up = m_nonfinite || !m_v.allFinite() || !(r.max_speed <= m_scene.blowup_speed);
    return r;
}

double Simulator::penetration_now() const
{
    if (!m_x.allFinite()) return std::numeric_limits<double>::quiet_NaN();
    double depth = 0;
    for (const ContactRow& r : m_detector->detect(m_x)) depth = std::max(depth, r.depth);
    return depth;
}

std::vector<SurfaceMesh> Simulator::body_surfaces() const { return surfaces_at(m_x); }

void Simulator::restore_state(const Vec& x, const Vec& v, const Vec& eigenvector, long steps_done)
{
    if (x.size() != dofs() || v.size() != dofs())
        throw_input_error("restore_state", "", "positions of another size than the scene's");
    m_x = x;
    m_v = v;
    m_eigenvector = eigenvector;
    m_step = steps_done;
}

namespace {
const char* const STEPS_HEADER =
    "frame,step,newton_iteration,solver,status,solver_status,iterations,accuracy,accuracy_solved,"
    "time_assembly_s,time_detection_s,time_solve_s,rows,rows_solved,snapshot,time_snapshot_s,"
    "time_solve_stage_s,peak_detection_mb,peak_assembly_mb,peak_snapshot_mb,peak_solve_mb\n";
const char* const FRAMES_HEADER =
    "frame,time_s,max_penetration,max_penetration_rel,max_detected_depth,max_detected_depth_rel,"
    "kinetic_energy,elastic_energy,max_speed,rows,rows_solved,blow_up\n";
}  // namespace

nlohmann::json Simulator::resume_identity() const
{
    nlohmann::json meshes = nlohmann::json::object();
    for (const auto& b : m_scene.bodies)
        if (!b.mesh_file.empty()) meshes[b.mesh_file] = qpsnap_content_hash(b.mesh_file);
    std::error_code ec;  // a scene built in memory (tests, stress) names no file to hash
    const bool scene_file = !m_scene.file.empty() && std::filesystem::is_regular_file(m_scene.file, ec);
    return {{"scene_file", scene_file ? qpsnap_content_hash(m_scene.file) : "not a file: " + m_scene.file},
            {"meshes", meshes},
            {"data", m_opt.data_dir},
            {"solver", m_solver_name},
            {"settings", m_scene.solver_settings},
            {"decouple", m_opt.decouple},
            {"decouple_seed", m_opt.decouple_seed},
            {"h", m_scene.step.h},
            {"steps_per_frame", m_scene.steps_per_frame},
            {"snapshots", m_opt.snapshots},
            {"simulator_version", SIMULATOR_VERSION}};
}

void Simulator::save_resume_state(long frames_done, bool finished, bool blow_up) const
{
    ResumeState s;
    s.identity = m_identity;
    s.frames_done = frames_done;
    s.steps_done = m_step;
    s.finished = finished;
    s.blow_up = blow_up;
    s.peak_reset = m_peak_reset;
    s.x = m_x;
    s.v = m_v;
    s.eigenvector = m_eigenvector;
    s.strip_frames = m_strip_frames;
    s.strip_x = m_strip_x;
    write_resume_state(m_opt.out_dir, s);
}

std::optional<bool> Simulator::prepare_output(long frames, PartialTable& steps_csv, PartialTable& frames_csv)
{
    const std::string& out = m_opt.out_dir;
    m_identity = resume_identity();
    if (m_opt.fresh) remove_old_output(out, m_scene.name);
    if (const long removed = remove_killed_runs_temporaries(out); removed > 0 && m_opt.progress)
        *m_opt.progress << "simulate: removed " << removed << " temporary file(s) of an interrupted run in " << out
                        << "\n";
    const std::optional<ResumeState> state = read_resume_state(out);
    const std::string fresh = "; --fresh discards it, or use another --out";
    if (!state) {
        const std::string found = old_output(out, m_scene.name);
        if (!found.empty())
            throw_input_error(out, "--out", "holds an earlier simulation's output (" + found + ")" + fresh);
        steps_csv.open(out + "/steps.csv", STEPS_HEADER);
        frames_csv.open(out + "/frames.csv", FRAMES_HEADER);
        return std::nullopt;
    }
    if (state->identity != m_identity) {
        std::string changed;
        for (const auto& [key, value] : m_identity.items())
            if (!state->identity.contains(key) || state->identity[key] != value)
                changed += (changed.empty() ? "" : ", ") + key;
        throw_input_error(out, "--out", "holds a simulation of other inputs (changed: " + changed + ")" + fresh);
    }
    m_frame = state->frames_done;
    if (state->finished && (state->frames_done == frames || (state->blow_up && state->frames_done < frames))) {
        if (m_opt.progress)
            *m_opt.progress << "simulate: " << out << " already holds this simulation, " << m_frame << " frames"
                            << (state->blow_up ? " ending in a blow-up" : "") << " (--fresh simulates again)\n";
        return !state->blow_up;
    }
    if (state->frames_done > frames)
        throw_input_error(out, "--out",
                          "holds " + std::to_string(state->frames_done) + " frames of this simulation, more than the " +
                              std::to_string(frames) + " asked" + fresh);
    // An interrupted run (or a finished one to extend): its state and tables from the last whole frame.
    m_step = state->steps_done;
    m_x = state->x;
    m_v = state->v;
    m_eigenvector = state->eigenvector;
    m_peak_reset = state->peak_reset;
    m_strip_frames = state->strip_frames;
    m_strip_x = state->strip_x;
    if (m_x.size() != dofs() || m_v.size() != dofs())
        throw_input_error(resume_state_path(out), "", "positions of another size than the scene's" + fresh);
    steps_csv.resume(out + "/steps.csv", STEPS_HEADER, m_frame);
    frames_csv.resume(out + "/frames.csv", FRAMES_HEADER, m_frame);
    std::error_code ec;
    std::filesystem::remove(out + "/simulation.json", ec);  // written again when the run is whole
    if (m_opt.progress)
        *m_opt.progress << "simulate: resuming " << out << " after frame " << m_frame - 1 << " (" << m_frame << " of "
                        << frames << " frames whole)\n";
    return std::nullopt;
}

bool Simulator::run()
{
    const long frames = m_opt.frames >= 0 ? m_opt.frames : m_scene.frames;
    const bool write = !m_opt.out_dir.empty();
    PartialTable steps_csv, frames_csv;
    m_interrupted = false;
    m_frame = 0;
    m_strip_frames.clear();
    m_strip_x.clear();
    if (write) {
        make_dirs(m_opt.out_dir);
        if (const std::optional<bool> done = prepare_output(frames, steps_csv, frames_csv)) return *done;
        if (m_opt.snapshots && m_scene.output.snapshots) make_dirs(m_opt.out_dir + "/snapshots");
    }
    try {
        const bool ok = run_frames(frames, write, steps_csv, frames_csv);
        if (write && !m_interrupted) {
            steps_csv.finish();
            frames_csv.finish();
            // Written last: its presence says the folder holds a whole simulation, and of what.
            nlohmann::json meshes = nlohmann::json::array();
            for (const auto& b : m_scene.bodies)
                if (!b.mesh_file.empty() && std::find(meshes.begin(), meshes.end(), b.mesh_file) == meshes.end())
                    meshes.push_back(b.mesh_file);
            nlohmann::json record = {{"scene", m_scene.name},
                                     {"scene_file", m_scene.file},
                                     {"meshes", meshes},
                                     {"data", m_opt.data_dir},
                                     {"frames", frames},
                                     {"frames_done", m_frame},
                                     {"blow_up", !ok},
                                     {"solver", m_solver_name},
                                     {"simulator_version", SIMULATOR_VERSION},
                                     {"decouple", m_opt.decouple},
                                     {"decouple_seed", m_opt.decouple_seed},
                                     {"h", m_scene.step.h},
                                     {"steps_per_frame", m_scene.steps_per_frame},
                                     {"body_size", m_body_size},
                                     {"stage_peak_reset", m_peak_reset}};
            if (m_scene.friction.mu > 0.0)  // this run's steps only: a resumed run counts from its resume
                record["friction"] = {{"mu", m_scene.friction.mu},
                                      {"solver", m_scene.friction.solver},
                                      {"tol", m_scene.friction.tol},
                                      {"steps_not_converged", m_friction_unsolved}};
            write_file_atomic(m_opt.out_dir + "/simulation.json", record.dump(1) + "\n");
            save_resume_state(m_frame, true, !ok);  // a longer run of the same inputs goes on from here
        }
        return ok;
    } catch (...) {
        // No partial output on an error (a full disk, a file-size limit): the tables go, and with
        // them the resume state that refers to them; the snapshots written stay, as earlier output.
        steps_csv.abandon();
        frames_csv.abandon();
        std::error_code ec;
        if (write) std::filesystem::remove(resume_state_path(m_opt.out_dir), ec);
        throw;
    }
}

std::vector<SurfaceMesh> Simulator::surfaces_at(const Vec& x) const
{
    std::vector<SurfaceMesh> out;
    for (size_t b = 0; b < m_scene.bodies.size(); ++b) {
        SurfaceMesh s;
        const long nv = m_scene.bodies[b].mesh.vertices();
        s.positions.resize(nv, 3);
        for (long i = 0; i < nv; ++i) s.positions.row(i) = x.segment<3>(3 * (m_body_first[b] + i)).transpose();
        s.faces = m_body_faces[b];
        out.push_back(std::move(s));
    }
    return out;
}

bool Simulator::run_frames(long frames, bool write, PartialTable& steps_csv, PartialTable& frames_csv)
{
    // Frames pictured in the strip: evenly spread over the run, last frame included.
    std::vector<long> strip;
    const int ns = write ? m_scene.output.strip_frames : 0;
    for (int i = 0; i < ns && frames > 0; ++i) {
        const long f =
            ns == 1 ? frames - 1 : static_cast<long>(std::llround(static_cast<double>(i) * (frames - 1) / (ns - 1)));
        if (strip.empty() || strip.back() != f) strip.push_back(f);
    }
    const long first_frame = m_frame;  // > 0 when resumed
    const double start_s = now_s();
    double sum_asm = 0, sum_det = 0, sum_snap = 0, sum_solve = 0;
    StagePeaks run_peaks;  // the largest peak of each stage over the run
    long nsteps = 0;
    bool ok = true;
    for (; m_frame < frames; ++m_frame) {
        std::vector<StepRecord> recs;
        for (int s = 0; s < m_scene.steps_per_frame; ++s) {
            auto r = step();
            recs.insert(recs.end(), r.begin(), r.end());
            if (m_nonfinite) break;
        }
        const FrameRecord fr = frame_record();
        long iters = 0;
        double ta = 0, td = 0, tsn = 0, tsv = 0, e = 0, e_solved = 0;
        StagePeaks peaks;  // the largest peak of each stage over the frame's steps
        long rows_solved = 0;
        std::string status;
        std::ostringstream step_rows, frame_row;  // appended together once the frame is whole
        step_rows << std::setprecision(9);
        frame_row << std::setprecision(9);
        for (const StepRecord& r : recs) {
            iters += r.iterations;
            ta += r.time_assembly_s;
            td += r.time_detection_s;
            tsn += r.time_snapshot_s;
            tsv += r.time_solve_s;
            peaks.add(r);
            e = r.accuracy;
            e_solved = r.accuracy_solved;
            rows_solved = r.rows_solved;
            status = r.status;
            if (write)
                step_rows << r.frame << ',' << r.step << ',' << r.newton << ',' << r.solver << ',' << r.status << ','
                          << r.solver_status << ',' << r.iterations << ',' << r.accuracy << ',' << r.accuracy_solved
                          << ',' << r.time_assembly_s << ',' << r.time_detection_s << ',' << r.time_solve_s << ','
                          << r.rows << ',' << r.rows_solved << ',' << r.snapshot << ',' << r.time_snapshot_s << ','
                          << r.time_solve_stage_s << ',' << r.peak_detection_mb << ',' << r.peak_assembly_mb << ','
                          << r.peak_snapshot_mb << ',' << r.peak_solve_mb << '\n';
        }
        sum_asm += ta;
        sum_det += td;
        sum_snap += tsn;
        sum_solve += tsv;
        run_peaks.add(peaks);
        nsteps += static_cast<long>(recs.size());
        if (write)
            frame_row << fr.frame << ',' << fr.time_s << ',' << fr.max_penetration << ',' << fr.max_penetration_rel
                      << ',' << fr.max_detected_depth << ',' << fr.max_detected_depth_rel << ',' << fr.kinetic_energy
                      << ',' << fr.elastic_energy << ',' << fr.max_speed << ',' << fr.rows << ',' << rows_solved << ','
                      << (fr.blow_up ? 1 : 0) << '\n';
        if (write) {
            // steps first: a frame is recorded when its frames.csv row is there.
            steps_csv.append(step_rows.str());
            frames_csv.append(frame_row.str());
        }
        // This session's mean time per frame times the frames left (a resumed run counts its own).
        const double elapsed = now_s() - start_s;
        const double eta =
            elapsed / static_cast<double>(m_frame + 1 - first_frame) * static_cast<double>(frames - m_frame - 1);
        if (m_opt.progress) {
            // The last step's verdict, as `solve` would print it: e on the original QP, and on the
            // kept rows when rows were dropped.
            char solved[160] = "";
            if (rows_solved < fr.rows) std::snprintf(solved, sizeof solved, " (kept rows %.1e)", e_solved);
            std::string stepper = m_solver_name;
            if (m_scene.friction.mu > 0.0) {  // e is then FCLIB's relative error of the step's local problem
                const FrictionalStepOutcome& f = m_friction_last;
                stepper = m_scene.friction.solver + " mu " + format_g(m_scene.friction.mu);
                std::snprintf(solved, sizeof solved, " (FCLIB error; contacts %ld: stick %ld slide %ld open %ld)",
                              f.contacts, f.sticking, f.sliding, f.separated);
            }
            char line[400];
            std::snprintf(line, sizeof line,
                          "%s frame %04ld (%ld of %ld)  rows %ld solved %ld  %s %s  it %ld  e %.1e%s  pen %.2e "
                          "(%.2g%% of body)  asm %.3fs det %.3fs snap %.3fs solve %.3fs  peak MiB %s  "
                          "elapsed %.1fs ETA %.1fs%s\n",
                          m_scene.name.c_str(), m_frame, m_frame + 1, frames, fr.rows, rows_solved, stepper.c_str(),
                          status.c_str(), iters, e, solved, fr.max_penetration, 100.0 * fr.max_penetration_rel, ta, td,
                          tsn, tsv, peaks.text().c_str(), elapsed, eta, fr.blow_up ? "  BLOW-UP" : "");
            *m_opt.progress << line << std::flush;
        }
        if (write) {
            if (std::find(strip.begin(), strip.end(), m_frame) != strip.end()) {
                m_strip_frames.push_back(m_frame);
                m_strip_x.push_back(m_x);
            }
            const auto& ex = m_scene.output.export_frames;
            if (std::find(ex.begin(), ex.end(), m_frame) != ex.end()) {
                const auto surfaces = body_surfaces();
                for (size_t b = 0; b < surfaces.size(); ++b) {
                    char name[64];
                    std::snprintf(name, sizeof name, "_f%04ld_b%zu.obj", m_frame, b);
                    make_dirs(m_opt.out_dir + "/frames");
                    write_obj(m_opt.out_dir + "/frames/" + m_scene.name + name, surfaces[b]);
                }
            }
        }
        if (write) save_resume_state(m_frame + 1, false, false);  // after the frame's rows and files
        if (fr.blow_up) {
            ok = false;
            ++m_frame;
            break;
        }
        if (m_opt.stop && *m_opt.stop != 0 && m_frame + 1 < frames) {  // a signal: stop on a whole frame
            m_interrupted = true;
            ++m_frame;
            break;
        }
    }
    if (m_opt.progress && nsteps > 0) {
        char line[400];
        std::snprintf(line, sizeof line,
                      "%s: %ld steps, mean per step: assembly %.4fs detection %.4fs snapshot %.4fs solve %.4fs; "
                      "largest peak MiB %s%s%s\n",
                      m_scene.name.c_str(), nsteps, sum_asm / nsteps, sum_det / nsteps, sum_snap / nsteps,
                      sum_solve / nsteps, run_peaks.text().c_str(),
                      m_peak_reset ? "" : " (the kernel refused the reset: peaks are cumulative)",
                      ok ? "" : " (stopped: blow-up)");
        *m_opt.progress << line;
        if (m_scene.friction.mu > 0.0)
            std::snprintf(line, sizeof line, "%s: %ld frictional step(s) did not reach FCLIB error %.1e (%s)\n",
                          m_scene.name.c_str(), m_friction_unsolved, m_scene.friction.tol,
                          m_scene.friction.solver.c_str());
        else
            line[0] = '\0';
        *m_opt.progress << line;
    }
    std::vector<std::vector<SurfaceMesh>> strip_meshes;
    for (const Vec& x : m_strip_x) strip_meshes.push_back(surfaces_at(x));
    if (write && !m_interrupted && !strip_meshes.empty()) {
        // Common framing over every pictured frame.
        Box3 box;
        for (const auto& frame : strip_meshes)
            for (const auto& s : frame)
                for (Eigen::Index i = 0; i < s.positions.rows(); ++i) box.extend(Vec3(s.positions.row(i).transpose()));
        const Vec3 lo = box.min(), hi = box.max();
        const double extent = 2.0 * (hi - lo).norm();
        std::vector<SurfaceMesh> obstacle_surfaces;
        for (const auto& o : m_scene.obstacles) obstacle_surfaces.push_back(o->surface(0.5 * (lo + hi), extent));
        // Bodies and the finite obstacles near them set the frame; planes are cut by the tile.
        Box3 frame_box = box;
        for (size_t o = 0; o < m_scene.obstacles.size(); ++o)
            if (m_scene.obstacles[o]->type() != "plane" && m_scene.obstacles[o]->type() != "mesh")
                for (Eigen::Index i = 0; i < obstacle_surfaces[o].positions.rows(); ++i)
                    frame_box.extend(Vec3(obstacle_surfaces[o].positions.row(i).transpose()));
        const View view = make_view(m_scene.output.view_deg, frame_box.min(), frame_box.max());
        const int size = m_scene.output.image_size;
        Image image(size * static_cast<int>(strip_meshes.size()), size);
        static const std::array<double, 3> palette[] = {{0.85, 0.35, 0.25}, {0.25, 0.55, 0.85}, {0.35, 0.7, 0.35},
                                                        {0.85, 0.7, 0.25},  {0.6, 0.4, 0.8},    {0.3, 0.75, 0.75}};
        for (size_t f = 0; f < strip_meshes.size(); ++f) {
            std::vector<ColoredSurface> surfaces;
            surfaces.reserve(obstacle_surfaces.size() + strip_meshes[f].size());
            for (const auto& s : obstacle_surfaces) surfaces.push_back({&s, {0.75, 0.75, 0.75}});
            for (size_t b = 0; b < strip_meshes[f].size(); ++b)
                surfaces.push_back({&strip_meshes[f][b], palette[b % 6]});
            render_tile(image, static_cast<int>(f) * size, size, view, surfaces);
        }
        write_png(m_opt.out_dir + "/" + m_scene.name + "_strip.png", image);
    }
    return ok;
}

}  // namespace cb::sim
