#include "sim/chains.hpp"

#include "solvers/core/format_number.hpp"

#include "problems/io_util.hpp"
#include "problems/qpsnap.hpp"
#include "problems/safe_output.hpp"
#include "sim/chains_state.hpp"
#include "sim/partial_table.hpp"
#include "sim/render.hpp"
#include "solvers/core/format_number.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <limits>
#include <memory>
#include <optional>
#include <ostream>
#include <sstream>

namespace cb::sim {

ChainDistance chain_distance(const Vec& a, const Vec& b)
{
    ChainDistance d;
    if (a.size() != b.size() || a.size() % 3 != 0 || !a.allFinite() || !b.allFinite()) {
        d.rms = d.max = std::numeric_limits<double>::quiet_NaN();
        return d;
    }
    const Eigen::Index nv = a.size() / 3;
    double sum = 0;
    for (Eigen::Index i = 0; i < nv; ++i) {
        const double s = (a.segment<3>(3 * i) - b.segment<3>(3 * i)).squaredNorm();
        sum += s;
        d.max = std::max(d.max, std::sqrt(s));
    }
    d.rms = nv > 0 ? std::sqrt(sum / static_cast<double>(nv)) : 0.0;
    return d;
}

Vec3 vertex_mean(const Vec& x)
{
    const Eigen::Index nv = x.size() / 3;
    if (nv == 0 || !x.allFinite()) return Vec3::Constant(std::numeric_limits<double>::quiet_NaN());
    Vec3 sum = Vec3::Zero();
    for (Eigen::Index i = 0; i < nv; ++i) sum += x.segment<3>(3 * i);
    return sum / static_cast<double>(nv);
}

namespace {

std::string number(double v)
{
    if (!std::isfinite(v)) return "nan";
    std::ostringstream s;
    s << std::setprecision(9) << v;
    return s.str();
}

/// Side-by-side pictures of every chain at one frame, one tile each, in the chains' order.
void render_side_by_side(const std::string& path, const Scene& scene,
                         const std::vector<std::vector<SurfaceMesh>>& chain_surfaces)
{
    Box3 box;
    for (const auto& chain : chain_surfaces)
        for (const auto& s : chain)
            for (Eigen::Index i = 0; i < s.positions.rows(); ++i) box.extend(Vec3(s.positions.row(i).transpose()));
    if (box.isEmpty()) return;
    const Vec3 lo = box.min(), hi = box.max();
    const double extent = 2.0 * (hi - lo).norm();
    std::vector<SurfaceMesh> obstacles;
    for (const auto& o : scene.obstacles) obstacles.push_back(o->surface(0.5 * (lo + hi), extent));
    const View view = make_view(scene.output.view_deg, lo, hi);
    const int size = scene.output.image_size;
    Image image(size * static_cast<int>(chain_surfaces.size()), size);
    static const std::array<double, 3> palette[] = {{0.85, 0.35, 0.25}, {0.25, 0.55, 0.85}, {0.35, 0.7, 0.35},
                                                    {0.85, 0.7, 0.25},  {0.6, 0.4, 0.8},    {0.3, 0.75, 0.75}};
    for (size_t c = 0; c < chain_surfaces.size(); ++c) {
        std::vector<ColoredSurface> surfaces;
        surfaces.reserve(obstacles.size() + chain_surfaces[c].size());
        for (const auto& s : obstacles) surfaces.push_back({&s, {0.75, 0.75, 0.75}});
        for (size_t b = 0; b < chain_surfaces[c].size(); ++b)
            surfaces.push_back({&chain_surfaces[c][b], palette[b % 6]});
        render_tile(image, static_cast<int>(c) * size, size, view, surfaces);
    }
    AtomicFile png(path, SpecialTarget::REFUSE);  // no link followed, no special file replaced
    write_png(png.hand_over_temporary(), image);
    png.commit();
}

/// A frame's end as a detection run sees it.
struct EndContacts {
    double depth = std::numeric_limits<double>::quiet_NaN();  ///< deepest vertex inside a body or an obstacle (m)
    long inside = -1;  ///< surface vertices inside another body's tetrahedra: they passed through its surface
};

EndContacts end_contacts(const Simulator& sim)
{
    EndContacts end;
    if (!sim.positions().allFinite()) return end;  // a blown-up chain: nothing to count
    std::vector<int> inside;
    end.depth = 0;
    for (const ContactRow& r : sim.contacts_now()) {
        end.depth = std::max(end.depth, r.depth);
        if (r.kind == ContactKind::INTER_BODY) inside.push_back(r.vertex[0]);
    }
    std::sort(inside.begin(), inside.end());  // one row per vertex and other body: count vertices once
    end.inside = static_cast<long>(std::unique(inside.begin(), inside.end()) - inside.begin());
    return end;
}

/// Keeps every chain's positions at the frame where a figure of the shown chain is largest so far
/// (positions, not surfaces: they are what a resumed run restores).
void offer(PicturedFrame& p, double v, long f, const std::vector<std::unique_ptr<Simulator>>& sims)
{
    if (!std::isfinite(v) || v <= p.value) return;
    p.value = v;
    p.frame = f;
    p.x.clear();
    for (const auto& sim : sims) p.x.push_back(sim->positions());
}

std::vector<std::vector<SurfaceMesh>> surfaces_of(const PicturedFrame& p,
                                                  const std::vector<std::unique_ptr<Simulator>>& sims)
{
    std::vector<std::vector<SurfaceMesh>> surfaces;
    for (size_t c = 0; c < p.x.size(); ++c) surfaces.push_back(sims[c]->surfaces_at(p.x[c]));
    return surfaces;
}

}  // namespace

bool run_chains(const std::function<Scene()>& load_scene, const ChainOptions& opt, long* frames_done)
{
    namespace fs = std::filesystem;
    if (opt.chains.empty()) throw_input_error("chains", "", "no chain to run");
    size_t ref = opt.chains.size(), shown = opt.chains.size();
    for (size_t c = 0; c < opt.chains.size(); ++c) {
        if (opt.chains[c].label == opt.reference) ref = c;
        if (opt.chains[c].label == opt.render_chain) shown = c;
    }
    if (ref == opt.chains.size()) throw_input_error("chains", "reference", "no chain labelled '" + opt.reference + "'");
    if (shown == opt.chains.size()) shown = ref;

    std::vector<std::unique_ptr<Simulator>> sims;
    for (const ChainSpec& spec : opt.chains) {
        Scene s = load_scene();
        SimulatorOptions so;       // no out_dir: the chains write their own tables
        if (spec.friction_step) {  // the scene's frictional step, its tol the chain's
            if (!(s.friction.mu > 0.0))
                throw_input_error(s.file, "/mu",
                                  "chain '" + spec.label +
                                      "' steps with the frictional step, but the scene has no "
                                      "friction (mu = 0)");
            for (const auto& [key, value] : spec.settings.items()) {
                if (key != "tol" || !value.is_number() || !(value.get<double>() > 0.0))
                    throw_input_error("chain " + spec.label, key,
                                      "a frictional-step chain takes only \"tol\" (> 0), got " + value.dump());
                s.friction.tol = value.get<double>();
            }
        } else {
            s.solver = spec.solver;
            s.solver_settings = spec.settings;
            so.friction_by_solver = true;  // mu > 0: the chain's solver takes the frictional QP
        }
        so.solve_step = opt.solve_step;
        so.decouple = spec.decouple;
        so.decouple_seed = opt.decouple_seed;
        so.h = opt.h;
        sims.push_back(std::make_unique<Simulator>(std::move(s), so));
    }
    const Simulator& first = *sims[ref];
    const Scene& scene = first.scene();
    const long frames = opt.frames >= 0 ? opt.frames : scene.frames;
    const double size = first.body_size();

    nlohmann::json chains = nlohmann::json::array();
    for (const ChainSpec& spec : opt.chains) {
        chains.push_back(
            {{"label", spec.label}, {"solver", spec.solver}, {"settings", spec.settings}, {"decouple", spec.decouple}});
        if (scene.friction.mu > 0.0) chains.back()["friction_step"] = spec.friction_step;
    }
    // Every input of what the chains write: a resume needs the same (file contents, not names).
    nlohmann::json meshes = nlohmann::json::object();
    for (const auto& b : scene.bodies)
        if (!b.mesh_file.empty()) meshes[b.mesh_file] = qpsnap_content_hash(b.mesh_file);
    std::error_code ec;
    const bool scene_file = !scene.file.empty() && fs::is_regular_file(scene.file, ec);
    const nlohmann::json identity = {
        {"scene_file", scene_file ? qpsnap_content_hash(scene.file) : "not a file: " + scene.file},
        {"meshes", meshes},
        {"data", opt.data_dir},
        {"frames", frames},
        {"h", first.step_h()},
        {"steps_per_frame", first.steps_per_frame()},
        {"decouple_seed", opt.decouple_seed},
        {"chains", chains},
        {"reference", opt.reference},
        {"render", opt.render_chain},
        {"chains_version", CHAINS_VERSION},
        {"simulator_version", SIMULATOR_VERSION}};

    fs::create_directories(opt.out_dir, ec);
    if (!fs::is_directory(opt.out_dir))
        throw_input_error(opt.out_dir, "--out", "cannot create the output folder: " + ec.message());
    const std::string csv_path = opt.out_dir + "/chains.csv", json_path = opt.out_dir + "/chains.json";
    const std::string png_path = opt.out_dir + "/" + scene.name + "_largest_difference.png";
    const std::string pen_png_path = opt.out_dir + "/" + scene.name + "_largest_penetration.png";
    const std::string state_path = chains_state_path(opt.out_dir), partial_path = csv_path + ".partial";
    const std::string fresh = "; --fresh discards it, or use another --out";
    if (opt.fresh)
        for (const std::string& p : {json_path, csv_path, partial_path, png_path, pen_png_path, state_path})
            fs::remove(p, ec);
    // Never mix runs, and never delete one without --fresh: an interrupted run of the same inputs
    // (chains.state and chains.csv, or chains.csv.partial when killed; no chains.json) is resumed
    // from its last whole frame.
    std::optional<ChainsState> state = read_chains_state(opt.out_dir);
    if (state && state->identity != identity) {
        std::string changed;
        for (const auto& [key, value] : identity.items())
            if (!state->identity.contains(key) || state->identity[key] != value)
                changed += (changed.empty() ? "" : ", ") + key;
        throw_input_error(opt.out_dir, "--out",
                          "holds a chains run of other inputs (changed: " + changed + ")" + fresh);
    }
    std::string found;
    for (const std::string& p : {json_path, csv_path, partial_path, png_path, pen_png_path})
        if ((!state || (p != csv_path && p != partial_path)) && fs::exists(fs::symlink_status(p, ec)))
            found += (found.empty() ? "" : ", ") + fs::path(p).filename().string();
    if (!found.empty())
        throw_input_error(opt.out_dir, "--out", "holds an earlier chains run's output (" + found + ")" + fresh);
    if (state && (state->frames_done > frames || state->x.size() != sims.size() || state->v.size() != sims.size() ||
                  state->eigenvector.size() != sims.size() || state->steps_done.size() != sims.size() ||
                  state->stopped.size() != sims.size()))
        throw_input_error(state_path, "", "does not match these chains" + fresh);
    // chains.csv.partial, appended and flushed frame by frame, renamed to chains.csv at the end or
    // at a signal; a resumed run keeps the whole frames its state records and appends after them.
    const std::string header =
        "frame,time_s,chain,solver,decouple,status,steps_not_solved,accuracy,rows,rows_solved,rows_dropped,"
        "penetration,penetration_rel,vertices_inside,violation_rel,rms_distance_rel,max_distance_rel,"
        "kinetic_energy,elastic_energy,blow_up,travel_rel,drift_rel\n";
    PartialTable csv;
    long csv_bytes = 0;
    if (state) {
        csv.resume_prefix(csv_path, header, static_cast<size_t>(state->csv_bytes));
        csv_bytes = state->csv_bytes;
    } else {
        csv.open(csv_path, header);
        csv_bytes = static_cast<long>(header.size());
    }
    const auto write_csv = [&csv, &csv_bytes](const std::string& text) {
        csv.append(text);  // fails with an InputError naming the file (disk full, ...)
        csv_bytes += static_cast<long>(text.size());
    };

    std::vector<Vec3> start_mean;  // each chain's start (before a resume restores a later state)
    for (const auto& sim : sims) start_mean.push_back(vertex_mean(sim->positions()));
    std::vector<bool> stopped(sims.size(), false);
    PicturedFrame difference, penetration;  // of the shown chain against the reference
    std::vector<double> pen_of(sims.size(), 0.0);
    bool ok = true;
    long first_frame = 0;
    if (state) {
        for (size_t c = 0; c < sims.size(); ++c)
            sims[c]->restore_state(state->x[c], state->v[c], state->eigenvector[c], state->steps_done[c]);
        stopped = state->stopped;
        ok = std::find(stopped.begin(), stopped.end(), true) == stopped.end();
        difference = state->difference;
        penetration = state->penetration;
        first_frame = state->frames_done;
        if (opt.progress)
            *opt.progress << "chains: resuming " << opt.out_dir << " after frame " << first_frame - 1 << " ("
                          << first_frame << " of " << frames << " frames whole)\n";
    }
    const auto save_state = [&](long whole) {
        ChainsState s;
        s.identity = identity;
        s.frames_done = whole;
        s.csv_bytes = csv_bytes;
        s.stopped = stopped;
        for (const auto& sim : sims) {
            s.steps_done.push_back(sim->steps_done());
            s.x.push_back(sim->positions());
            s.v.push_back(sim->velocities());
            s.eigenvector.push_back(sim->eigenvector());
        }
        s.difference = difference;
        s.penetration = penetration;
        write_chains_state(opt.out_dir, s);
    };
    const auto start = std::chrono::steady_clock::now();
    for (long f = first_frame; f < frames; ++f) {
        std::ostringstream rows;
        for (size_t c = 0; c < sims.size(); ++c) {
            if (stopped[c]) continue;
            Simulator& sim = *sims[c];
            std::string status;
            double e = 0;
            long not_solved = 0, nrows = 0, nsolved = 0;
            for (int s = 0; s < sim.steps_per_frame(); ++s) {
                for (const StepRecord& r : sim.step()) {
                    status = r.status;
                    e = std::max(e, std::isfinite(r.accuracy) ? r.accuracy : std::numeric_limits<double>::infinity());
                    if (r.status != "converged" && r.status != "solved_relaxation") ++not_solved;
                    nrows = r.rows;
                    nsolved = r.rows_solved;
                }
            }
            const FrameRecord fr = sim.frame_record();
            if (fr.blow_up) {
                stopped[c] = true;
                ok = false;
            }
            const EndContacts end = end_contacts(sim);
            const double pen = end.depth;
            pen_of[c] = pen;
            const ChainDistance d = chain_distance(sim.positions(), sims[ref]->positions());
            const Vec3 mean = vertex_mean(sim.positions());
            const double travel = (mean - start_mean[c]).norm() / size;
            const double drift = (mean - vertex_mean(sims[ref]->positions())).norm() / size;
            const ChainSpec& spec = opt.chains[c];
            rows << f << ',' << number(static_cast<double>(f + 1) * sim.step_h() * sim.steps_per_frame()) << ','
                 << spec.label << ',' << spec.solver << ',' << spec.decouple << ',' << status << ',' << not_solved
                 << ',' << number(e) << ',' << nrows << ',' << nsolved << ',' << (nrows - nsolved) << ',' << number(pen)
                 << ',' << number(pen / size) << ',' << end.inside << ',' << number(fr.max_penetration_rel) << ','
                 << number(d.rms / size) << ',' << number(d.max / size) << ',' << number(fr.kinetic_energy) << ','
                 << number(fr.elastic_energy) << ',' << (fr.blow_up ? 1 : 0) << ',' << number(travel) << ','
                 << number(drift) << '\n';
            if (opt.progress) {
                char line[320];
                std::snprintf(line, sizeof line,
                              "%s frame %04ld  %-14s rows %4ld kept %4ld  %s  e %.1e  pen %.2g%% (%ld inside)  "
                              "dist max %.2g%% rms %.2g%% travel %.2g%% drift %.2g%% of body%s\n",
                              scene.name.c_str(), f, spec.label.c_str(), nrows, nsolved, status.c_str(), e,
                              100 * pen / size, end.inside, 100 * d.max / size, 100 * d.rms / size, 100 * travel,
                              100 * drift, fr.blow_up ? "  BLOW-UP (chain stopped)" : "");
                *opt.progress << line << std::flush;
            }
        }
        // Every chain has stepped this frame: keep the pictures when the shown chain is farthest yet.
        if (shown != ref && !stopped[shown]) {
            offer(difference, chain_distance(sims[shown]->positions(), sims[ref]->positions()).max, f, sims);
            offer(penetration, pen_of[shown], f, sims);
        }
        write_csv(rows.str());
        save_state(f + 1);  // after the frame's rows: a resume starts from here
        if (opt.progress) {
            const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
            char line[160];
            std::snprintf(line, sizeof line, "%s frame %04ld (%ld of %ld)  elapsed %.1fs ETA %.1fs\n",
                          scene.name.c_str(), f, f + 1, frames, elapsed,
                          elapsed / static_cast<double>(f + 1 - first_frame) * static_cast<double>(frames - f - 1));
            *opt.progress << line << std::flush;
        }
        if (opt.stop && *opt.stop != 0 && f + 1 < frames) {  // a signal: every chain's whole frames, no record
            csv.finish();
            if (frames_done) *frames_done = f + 1;
            return ok;
        }
    }
    csv.finish();
    if (frames_done) *frames_done = frames;
    if (!difference.x.empty()) render_side_by_side(png_path, scene, surfaces_of(difference, sims));
    if (!penetration.x.empty()) render_side_by_side(pen_png_path, scene, surfaces_of(penetration, sims));
    const nlohmann::json record = {
        {"scene", scene.name},
        {"scene_file", scene.file},
        {"data", opt.data_dir},
        {"frames", frames},
        {"h", first.step_h()},
        {"steps_per_frame", first.steps_per_frame()},
        {"body_size", size},
        {"decouple_seed", opt.decouple_seed},
        {"chains", chains},
        {"reference", opt.chains[ref].label},
        {"render",
         {{"chain", opt.chains[shown].label},
          {"frame", difference.frame},
          {"max_distance_rel", difference.value >= 0 ? nlohmann::json(difference.value / size) : nlohmann::json()},
          {"file", difference.x.empty() ? nlohmann::json() : nlohmann::json(fs::path(png_path).filename())},
          {"penetration_frame", penetration.frame},
          {"penetration_rel", penetration.value >= 0 ? nlohmann::json(penetration.value / size) : nlohmann::json()},
          {"penetration_file",
           penetration.x.empty() ? nlohmann::json() : nlohmann::json(fs::path(pen_png_path).filename())}}},
        {"blow_up", !ok},
        {"chains_version", CHAINS_VERSION},
        {"simulator_version", SIMULATOR_VERSION}};
    write_file_atomic(json_path, record.dump(1) + "\n");
    fs::remove(state_path, ec);  // the run is whole: chains.json now refuses a rerun without --fresh
    return ok;
}

}  // namespace cb::sim
