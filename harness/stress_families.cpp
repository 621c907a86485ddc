#include "harness/stress_families.hpp"
#include "harness/temp_folder.hpp"

#include "problems/qpsnap.hpp"
#include "sim/scene.hpp"
#include "sim/simulator.hpp"
#include "problems/synthetic.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <optional>
#include <random>
#include <unistd.h>

namespace cb {

namespace {

using nlohmann::json;

StressCase make_case(std::string id, std::string family, int severity, std::string synthetic, json params,
                     std::string description, std::string modifier = "")
{
    StressCase c;
    c.id = std::move(id);
    c.family = std::move(family);
    c.severity = severity;
    c.synthetic = std::move(synthetic);
    c.params = std::move(params);
    c.description = std::move(description);
    c.modifier = std::move(modifier);
    return c;
}

/// Appends rows (triplets per row, c, contact metadata) to a QP.
struct RowAppender {
    std::vector<Triplet> t;
    std::vector<double> c;
    ContactRows contacts;
    int rows = 0;

    void add_existing(const Qp& qp, Eigen::Index r, double scale, double c_value)
    {
        for (SpMat::InnerIterator it(qp.J, r); it; ++it)
            t.emplace_back(rows, static_cast<int>(it.col()), scale * it.value());
        c.push_back(c_value);
        if (!qp.contacts.empty()) {
            contacts.kind.push_back(qp.contacts.kind[static_cast<size_t>(r)]);
            contacts.depth.push_back(qp.contacts.depth[static_cast<size_t>(r)]);
            for (int k = 0; k < 4; ++k) contacts.vertex.push_back(qp.contacts.vertex[static_cast<size_t>(4 * r + k)]);
        }
        ++rows;
    }
    void add_vertex_row(int vertex, const Eigen::Vector3d& normal, double c_value, double depth)
    {
        for (int d = 0; d < 3; ++d)
            if (normal[d] != 0.0) t.emplace_back(rows, 3 * vertex + d, normal[d]);
        c.push_back(c_value);
        contacts.kind.push_back(static_cast<std::int64_t>(ContactKind::OTHER));
        contacts.depth.push_back(depth);
        contacts.vertex.insert(contacts.vertex.end(), {vertex, -1, -1, -1});
        ++rows;
    }
    void finish(Qp& qp, bool keep_contacts)
    {
        qp.J = SpMat(rows, qp.n());
        qp.J.setFromTriplets(t.begin(), t.end());
        qp.c = Eigen::Map<Vec>(c.data(), static_cast<Eigen::Index>(c.size()));
        qp.contacts = keep_contacts ? contacts : ContactRows{};
    }
};

/// Degenerate J: every other row gets a parallel copy (scaled by 2.5), half of them the same
/// constraint, half a slightly weaker one (never active at the solution but parallel).
void add_parallel_rows(Qp& qp, std::uint64_t seed)
{
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    RowAppender out;
    const bool keep = !qp.contacts.empty();
    const double offset = 1e-3 * std::max(1.0, qp.c.size() ? qp.c.lpNorm<Eigen::Infinity>() : 0.0);
    for (Eigen::Index r = 0; r < qp.m(); ++r) {
        out.add_existing(qp, r, 1.0, qp.c[r]);
        if (r % 2 == 0) {
            const bool same = u(rng) < 0.5;
            out.add_existing(qp, r, 2.5, 2.5 * (qp.c[r] - (same ? 0.0 : offset)));
        }
    }
    out.finish(qp, keep);
}

/// Degenerate J: many rows (20) with different normals on the most penetrating vertex, all
/// satisfied at that vertex's projection onto the plane y = 0 (so the set stays non-empty).
void add_rows_on_one_vertex(Qp& qp, std::uint64_t seed)
{
    if (qp.m() == 0) return;
    const Vec slack = qp.J * qp.x0 - qp.c;
    Eigen::Index deepest = 0;
    slack.minCoeff(&deepest);
    int vertex = -1;
    for (SpMat::InnerIterator it(qp.J, deepest); it; ++it) {
        vertex = static_cast<int>(it.col() / 3);
        break;
    }
    if (vertex < 0) return;
    std::mt19937_64 rng(seed);
    std::normal_distribution<double> gauss(0.0, 1.0);
    RowAppender out;
    const bool keep = !qp.contacts.empty();
    for (Eigen::Index r = 0; r < qp.m(); ++r) out.add_existing(qp, r, 1.0, qp.c[r]);
    Eigen::Vector3d target = qp.x0.segment<3>(3 * static_cast<Eigen::Index>(vertex));
    target.y() = std::max(0.0, target.y());
    for (int k = 0; k < 20; ++k) {
        Eigen::Vector3d normal(gauss(rng), 0.0, gauss(rng));
        normal.y() = 1.0;  // upper hemisphere, at most ~70 degrees from the plane normal
        normal.normalize();
        const double c_value = normal.dot(target);
        out.add_vertex_row(
            vertex, normal, c_value,
            std::max(0.0, c_value - normal.dot(qp.x0.segment<3>(3 * static_cast<Eigen::Index>(vertex)))));
    }
    out.finish(qp, keep);
}

/// Rigid translation of the whole problem by t per vertex (x -> x + t): x0 + t, b + A t, c + J t.
/// The solution moves by t and nothing else changes; a solver that sees only differences of
/// positions behaves the same (problems whose DOF count is not a multiple of 3 are left alone).
void translate_problem(Qp& qp, const Eigen::Vector3d& shift)
{
    if (qp.n() % 3 != 0) return;
    Vec t(qp.n());
    for (Eigen::Index v = 0; v < qp.n() / 3; ++v) t.segment<3>(3 * v) = shift;
    qp.b += qp.A * t;
    qp.c += qp.J * t;
    qp.x0 += t;
    qp.meta["translated_m"] = {shift.x(), shift.y(), shift.z()};
}

/// The stiff slab of scenes/stiff_slab.json (issue 17's reproducer: 16x4x16 cubes, 1445
/// vertices, E = params["youngs"], nu = 0.45, h = 0.05 s) tilted by 2 degrees and dropped on
/// the ground, so that about 289 vertex-plane rows exist (margin 6 cm) and only some are active.
json fem_slab_scene(const json& params)
{
    const json material = {{"youngs", params.value("youngs", 1e10)}, {"poisson", 0.45}, {"density", 1000}};
    return {
        {"name", "stress-slab"},
        {"h", params.value("h", 0.05)},
        {"gravity", {0, -9.8, 0}},
        {"detection", {{"margin", 0.06}}},
        {"bodies",
         {{{"name", "slab"},
           {"box", {{"cells", {16, 4, 16}}, {"size", {1.6, 0.4, 1.6}}}},
           {"material", material},
           {"rotate_deg", {0, 0, 2}},
           {"translate", {0, 0.228, 0}},
           {"velocity", {0, -0.5, 0}}}}},
        {"obstacles", {{{"type", "plane"}, {"normal", {0, 1, 0}}, {"point", {0, 0, 0}}}}},
        {"output", {{"strip_frames", 0}}},
    };
}

/// The stiff dinosaur of scenes/stiff_dino.json (issue 17's reproducer at the unseen snapshot's
/// scale): the authors' 1303-vertex dino (CGAL's dino.off tetrahedralised when their data is
/// missing) with E = params["youngs"], nu = 0.45, h = 0.05 s, dropped feet first at 3 m/s; its
/// second step has 263 vertex-plane rows.
json fem_dino_scene(const json& params)
{
    const json material = {{"youngs", params.value("youngs", 1e10)}, {"poisson", 0.45}, {"density", 1000}};
    const json fallback = {{"path", "cache:meshes/dino.off"},
                           {"center", true},
                           {"rotate_deg", {0, 90, 0}},
                           {"fit_size", 1.015},
                           {"resolution", 25}};
    return {
        {"name", "stress-dino"},
        {"h", 0.05},
        {"gravity", {0, -9.8, 0}},
        {"bodies",
         {{{"name", "dino"},
           {"mesh", {"data:meshes/dino_1303_4014.abq", fallback}},
           {"material", material},
           {"translate", {0, 0.44, 0}},
           {"velocity", {0, -3.0, 0}}}}},
        {"obstacles", {{{"type", "plane"}, {"normal", {0, 1, 0}}, {"point", {0, 0, 0}}}}},
        {"output", {{"strip_frames", 0}}},
    };
}

/// The demo scene (scenes/demo.json: two 4x4x4-cube boxes, 750 DOF) built in memory, with the
/// case's overrides: "youngs" (Pa, both bodies), "speed" (m/s, added downwards to both bodies'
/// initial velocities), "h" (s).
json fem_demo_scene(const json& params)
{
    const double youngs = params.value("youngs", 2e5);
    const double speed = params.value("speed", 0.0);
    const json material = {{"youngs", youngs}, {"poisson", 0.4}, {"density", 1000}};
    return {
        {"name", "stress-fem"},
        {"h", params.value("h", 0.01)},
        {"gravity", {0, -9.8, 0}},
        {"a_M", 0.02},
        {"a_K", 0.01},
        {"solver_settings", {{"tol", 1e-8}, {"max_iterations", 5000}}},
        {"detection", {{"margin", 0.005}}},
        {"bodies",
         {{{"name", "lower"},
           {"box", {{"cells", {4, 4, 4}}, {"size", {0.4, 0.4, 0.4}}}},
           {"material", material},
           {"translate", {0, 0.22, 0}},
           {"velocity", {0, -1.0 - speed, 0}}},
          {{"name", "upper"},
           {"box", {{"cells", {4, 4, 4}}, {"size", {0.3, 0.3, 0.3}}}},
           {"material", material},
           {"translate", {0.05, 0.75, 0.03}},
           {"rotate_deg", {20, 0, 15}},
           {"velocity", {0, -2.5 - speed, 0}}}}},
        {"obstacles", {{{"type", "plane"}, {"normal", {0, 1, 0}}, {"point", {0, 0, 0}}}}},
        {"output", {{"strip_frames", 0}}},
    };
}

/// A FEM snapshot from our own simulator: the demo scene (with the case's overrides) stepped
/// for params["frames"] time steps (mprgp as the stepping solver, so the trajectory does
/// not depend on a solver under test); the QP of the last step that had contact rows is the
/// case. The simulator only hands QPs out as .qpsnap files, so they go through a temp folder.
Qp make_fem_sim_qp(const StressCase& c)
{
    const std::string where = "stress case " + c.id;
    const long frames = c.params.value("frames", 5L);
    if (frames < 1) throw_input_error(where, "frames", "expected >= 1");
    std::optional<TempFolder> folder;
    try {
        folder.emplace("cb-stress-fem");
    } catch (const std::exception& e) {
        throw_input_error(where, "temporary folder", e.what());
    }
    const std::string tmp_path = folder->path().string();
    std::filesystem::create_directories(tmp_path + "/snapshots");

    sim::SimulatorOptions options;
    options.out_dir = tmp_path;
    const std::string scene = c.params.value("scene", std::string("demo"));
    const bool slab = scene == "slab";
    const bool dino = scene == "dino";
    // mprgp steps every scene: CHOLMOD (active-set) in the parent leaves the forked children
    // of `stress` hanging. The slab and dino cases use the first step with rows, whose QP no
    // solver has touched.
    options.solver = "mprgp";
    sim::PathRoots roots;
    if (dino) {
        // The authors' mesh when `make paper-data` wrote it, else the CGAL stand-in (`make meshes`).
        roots = sim::default_path_roots("", "");
        std::error_code ec;
        if (std::filesystem::is_directory(roots.cache + "/paper-data", ec)) roots.data = roots.cache + "/paper-data";
    }
    const json scene_json = slab   ? fem_slab_scene(c.params)
                            : dino ? fem_dino_scene(c.params)
                                   : fem_demo_scene(c.params);
    sim::Simulator simulator(sim::load_scene_json(scene_json, where, roots), options);
    Qp last;
    long last_step = -1;
    for (long s = 0; s < frames; ++s) {
        for (const sim::StepRecord& rec : simulator.step()) {
            if (rec.rows > 0 && !rec.snapshot.empty()) {
                last = read_qpsnap(rec.snapshot);
                last_step = s;
            }
        }
    }
    if (last_step < 0 || last.m() == 0)
        throw_input_error(where, "frames", "no step with contact rows in " + std::to_string(frames) + " steps");
    last.meta["stress_source"] = {{"step", last_step},
                                  {"frames", frames},
                                  {"scene", slab   ? "stiff slab (in memory)"
                                            : dino ? "stiff dino (in memory)"
                                                   : "demo (in memory)"}};
    return last;
}

}  // namespace

std::vector<StressCase> stress_cases(bool quick)
{
    // Bodies stay small: the FEM grid defaults to 4x4x4 cubes (375 DOF); a few cases use more.
    const json base = json::object();
    std::vector<StressCase> all = {
        make_case("baseline-plane", "baseline", 0, "plane", base, "a soft body falling on the ground"),
        make_case("baseline-coupled", "baseline", 0, "coupled", base, "two bodies, vertex-triangle rows (coupled J)"),
        make_case("empty-J", "empty-J", 0, "unconstrained", base, "m = 0: the unconstrained problem"),
        make_case("stiffness-1e4", "stiffness", 1, "plane", {{"youngs", 1e4}}, "very soft body (E = 1e4 Pa)"),
        make_case("stiffness-1e8", "stiffness", 2, "plane", {{"youngs", 1e8}}, "stiff body (E = 1e8 Pa)"),
        make_case("stiffness-1e10", "stiffness", 2, "plane", {{"youngs", 1e10}}, "very stiff body (E = 1e10 Pa)"),
        make_case("stiffness-1e12", "stiffness", 3, "plane", {{"youngs", 1e12}}, "steel-like and beyond (E = 1e12 Pa)"),
        make_case("stiffness-coupled-1e9", "stiffness", 3, "coupled", {{"youngs", 1e9}},
                  "stiff bodies with coupled rows"),
        make_case("units-mm-g", "units", 2, "plane", {{"length_scale", 1e-3}, {"mass_scale", 1e-3}},
                  "lengths in mm, masses in g"),
        make_case("units-km-t", "units", 2, "plane", {{"length_scale", 1e3}, {"mass_scale", 1e3}},
                  "lengths in km, masses in t"),
        make_case("timestep-1e-5", "timestep", 2, "plane", {{"h", 1e-5}}, "tiny time step h = 1e-5 s"),
        make_case("timestep-1", "timestep", 2, "plane", {{"h", 1.0}}, "huge time step h = 1 s"),
        make_case("timestep-10", "timestep", 3, "plane", {{"h", 10.0}}, "absurd time step h = 10 s"),
        make_case("rows-scaled-1e3", "scaled-rows", 1, "scaled-rows", {{"row_scale", 1e3}},
                  "rows of J scaled by factors in [1e-3, 1e3]"),
        make_case("rows-scaled-1e6", "scaled-rows", 3, "scaled-rows", {{"row_scale", 1e6}},
                  "rows of J scaled by factors in [1e-6, 1e6]"),
        make_case("rows-duplicate-50", "degenerate-J", 1, "duplicate-rows", {{"fraction", 0.5}},
                  "half the rows duplicated"),
        make_case("rows-duplicate-all", "degenerate-J", 2, "duplicate-rows", {{"fraction", 1.0}},
                  "every row duplicated"),
        make_case("rows-parallel", "degenerate-J", 2, "plane", base, "parallel rows (scaled copies, some weaker)",
                  "parallel-rows"),
        make_case("rows-zero", "degenerate-J", 1, "zero-rows", {{"count", 5}}, "five zero rows with c = 0"),
        make_case("rows-one-vertex", "degenerate-J", 2, "plane", base, "20 rows with different normals on one vertex",
                  "one-vertex"),
        make_case("infeasible-1", "infeasible", 2, "infeasible", {{"pairs", 1}}, "one contradictory pair of rows"),
        make_case("infeasible-5", "infeasible", 3, "infeasible", {{"pairs", 5}}, "five contradictory pairs"),
        make_case("singular-mass-1e-6", "singular-A", 2, "plane", {{"density", 1e-6}},
                  "tiny mass: A ~ h^2 K with its rigid modes nearly singular"),
        make_case("singular-mass-1e-10", "singular-A", 3, "plane", {{"density", 1e-10}},
                  "vanishing mass: A nearly singular"),
        make_case("tiny-h2K", "singular-A", 1, "plane", {{"h", 1e-7}, {"youngs", 1e4}},
                  "h^2 K below rounding of M: A ~ M"),
        make_case("m-near-n-90", "m-near-n", 2, "box", {{"fraction", 0.9}}, "bounds on 90% of the DOFs"),
        make_case("m-equals-n", "m-near-n", 3, "box", {{"fraction", 1.0}}, "a bound on every DOF"),
        make_case("random-spd-1e8", "conditioning", 2, "random-spd", {{"n", 300}, {"m", 60}, {"condition", 1e8}},
                  "random SPD, condition 1e8"),
        make_case("random-spd-1e12", "conditioning", 3, "random-spd", {{"n", 300}, {"m", 60}, {"condition", 1e12}},
                  "random SPD, condition 1e12"),
        make_case("random-spd-m-near-n", "m-near-n", 2, "random-spd", {{"n", 200}, {"m", 190}},
                  "random SPD with m = 190 rows on n = 200"),
        make_case("plane-tilted-larger", "baseline", 1, "plane", {{"nx", 8}, {"ny", 4}, {"nz", 8}, {"tilt_deg", 30.0}},
                  "a larger body (1215 DOF) on a 30 degree slope"),
        make_case("fem-stiff-1e10", "fem-sim", 2, "fem-sim", {{"youngs", 1e10}, {"frames", 11}},
                  "simulator snapshot: demo scene (750 DOF) with E = 1e10 Pa, step 10 (the boxes collide; "
                  "earlier resting steps are solved at x0)"),
        make_case("fem-fast-50ms", "fem-sim", 3, "fem-sim", {{"speed", 50.0}, {"frames", 3}},
                  "simulator snapshot: demo scene (750 DOF) thrown down at ~50 m/s, last step with contacts"),
        make_case("slab-stiff-1e4", "stiff-slab", 1, "fem-sim", {{"scene", "slab"}, {"youngs", 1e4}, {"frames", 1}},
                  "stiff-slab scene (4335 DOF, h = 0.05 s, 289 plane rows) with E = 1e4 Pa, first step"),
        make_case("slab-stiff-1e6", "stiff-slab", 1, "fem-sim", {{"scene", "slab"}, {"youngs", 1e6}, {"frames", 1}},
                  "stiff-slab scene with E = 1e6 Pa, first step"),
        make_case("slab-stiff-1e8", "stiff-slab", 2, "fem-sim", {{"scene", "slab"}, {"youngs", 1e8}, {"frames", 1}},
                  "stiff-slab scene with E = 1e8 Pa, first step"),
        make_case("slab-stiff-1e10", "stiff-slab", 2, "fem-sim", {{"scene", "slab"}, {"youngs", 1e10}, {"frames", 1}},
                  "issue 17's reproducer: stiff-slab scene with E = 1e10 Pa (cond(A) ~ 1e9), first step"),
        make_case("slab-stiff-1e12", "stiff-slab", 3, "fem-sim", {{"scene", "slab"}, {"youngs", 1e12}, {"frames", 1}},
                  "stiff-slab scene with E = 1e12 Pa, first step"),
        make_case("dino-stiff-1e10", "stiff-dino", 3, "fem-sim", {{"scene", "dino"}, {"youngs", 1e10}, {"frames", 2}},
                  "issue 17's reproducer (scenes/stiff_dino.json): 1303-vertex dino (3909 DOF), E = 1e10 Pa, "
                  "h = 0.05 s, 263 plane rows at step 1; the CGAL dino without the authors' data"),
        make_case("coupled-translated-100m", "translation", 2, "coupled", base,
                  "baseline-coupled moved by 100 m along x (x0 + t, b + A t, c + J t)", "translate-100m"),
        make_case("coupled-stiff-translated-100m", "translation", 3, "coupled", {{"youngs", 1e9}},
                  "stiffness-coupled-1e9 moved by 100 m along x", "translate-100m"),
        make_case("fem-translated-100m", "translation", 3, "fem-sim", {{"youngs", 1e8}, {"frames", 6}},
                  "simulator snapshot (demo scene, E = 1e8 Pa, plane and inter-body rows) moved by 100 m along x",
                  "translate-100m"),
    };
    if (!quick) return all;
    std::vector<StressCase> subset;
    for (const auto& c : all)
        if (c.id == "baseline-plane" || c.id == "rows-duplicate-50" || c.id == "infeasible-1" || c.id == "empty-J")
            subset.push_back(c);
    return subset;
}

std::vector<StressCase> select_stress_cases(const std::vector<StressCase>& all, const std::vector<std::string>& names)
{
    if (names.empty()) return all;
    std::vector<StressCase> out;
    for (const auto& name : names) {
        bool found = false;
        for (const auto& c : all)
            if (c.id == name || c.family == name) {
                found = true;
                if (std::none_of(out.begin(), out.end(), [&](const StressCase& o) { return o.id == c.id; }))
                    out.push_back(c);
            }
        if (!found) {
            std::string known;
            for (const auto& c : all) known += (known.empty() ? "" : ", ") + c.id;
            throw_input_error("--cases", name, "no stress case or family of that name; known: " + known);
        }
    }
    return out;
}

Qp make_stress_qp(const StressCase& c)
{
    Qp qp = c.synthetic == "fem-sim" ? make_fem_sim_qp(c) : make_synthetic(c.synthetic, c.params, c.seed);
    if (c.modifier == "parallel-rows")
        add_parallel_rows(qp, c.seed);
    else if (c.modifier == "one-vertex")
        add_rows_on_one_vertex(qp, c.seed);
    else if (c.modifier == "translate-100m")
        translate_problem(qp, Eigen::Vector3d(100.0, 0.0, 0.0));
    else if (!c.modifier.empty())
        throw_input_error("stress case " + c.id, "modifier", "unknown '" + c.modifier + "'");
    qp.meta["stress"] = {{"case", c.id}, {"family", c.family}, {"severity", c.severity}, {"modifier", c.modifier}};
    return qp;
}

}  // namespace cb
