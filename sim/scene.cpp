#include "sim/scene.hpp"

#include "problems/io_util.hpp"
#include "sim/mesh_io.hpp"
#include "sim/tetrahedralize.hpp"
#include "solvers/core/format_number.hpp"
#include "solvers/peers/siconos_fc3d.hpp"

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <set>
#include <sys/stat.h>

namespace cb::sim {
namespace {

/// A count for messages: "3e+09" style beyond 64-bit integers, exact below.
std::string fmt_count(double v)
{
    if (v < 9e18) return std::to_string(static_cast<long long>(v));
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.3g", v);
    return buf;
}

std::string json_type(const nlohmann::json& j) { return std::string(j.type_name()) + " " + j.dump().substr(0, 60); }

/// Strict reader of one JSON object: typed getters with defaults, JSON pointers in errors,
/// and finish() rejecting keys nobody asked for.
class Reader {
public:
    Reader(const nlohmann::json& j, std::string file, std::string pointer)
        : m_j(j), m_file(std::move(file)), m_ptr(std::move(pointer))
    {
        if (!m_j.is_object()) fail_here("expected an object, got " + json_type(m_j));
    }
    [[noreturn]] void fail(const std::string& key, const std::string& problem) const
    {
        throw_input_error(m_file, m_ptr + "/" + key, problem);
    }
    [[noreturn]] void fail_here(const std::string& problem) const
    {
        throw_input_error(m_file, m_ptr.empty() ? "/" : m_ptr, problem);
    }
    const nlohmann::json* find(const std::string& key)
    {
        m_read.insert(key);
        const auto it = m_j.find(key);
        return it == m_j.end() ? nullptr : &*it;
    }
    bool has(const std::string& key) const { return m_j.contains(key); }
    double number(const std::string& key, double fallback, double min_exclusive = -1e300, double max_inclusive = 1e300)
    {
        const auto* v = find(key);
        if (!v) return fallback;
        if (!v->is_number()) fail(key, "expected a number, got " + json_type(*v));
        const double x = v->get<double>();
        if (!(x > min_exclusive) || !(x <= max_inclusive))
            fail(key,
                 "must be in (" + format_g(min_exclusive) + ", " + format_g(max_inclusive) + "], got " + format_g(x));
        return x;
    }
    long integer(const std::string& key, long fallback, long min_inclusive, long max_inclusive = 1L << 40)
    {
        const auto* v = find(key);
        if (!v) return fallback;
        if (!v->is_number_integer()) fail(key, "expected an integer, got " + json_type(*v));
        const long x = v->get<long>();
        if (x < min_inclusive || x > max_inclusive)
            fail(key, "must be in [" + std::to_string(min_inclusive) + ", " + std::to_string(max_inclusive) +
                          "], got " + std::to_string(x));
        return x;
    }
    bool boolean(const std::string& key, bool fallback)
    {
        const auto* v = find(key);
        if (!v) return fallback;
        if (!v->is_boolean()) fail(key, "expected true or false, got " + json_type(*v));
        return v->get<bool>();
    }
    std::string string(const std::string& key, const std::string& fallback,
                       const std::vector<std::string>& allowed = {})
    {
        const auto* v = find(key);
        if (!v) return fallback;
        if (!v->is_string()) fail(key, "expected a string, got " + json_type(*v));
        std::string s = v->get<std::string>();
        if (!allowed.empty() && std::find(allowed.begin(), allowed.end(), s) == allowed.end()) {
            std::string list;
            for (const auto& a : allowed) list += (list.empty() ? "" : ", ") + a;
            fail(key, "must be one of " + list + ", got '" + s + "'");
        }
        return s;
    }
    Vec3 vec3(const std::string& key, const Vec3& fallback)
    {
        const auto* v = find(key);
        if (!v) return fallback;
        if (!v->is_array() || v->size() != 3) fail(key, "expected an array of 3 numbers, got " + json_type(*v));
        Vec3 out;
        for (int k = 0; k < 3; ++k) {
            if (!(*v)[static_cast<size_t>(k)].is_number()) fail(key + "/" + std::to_string(k), "expected a number");
            out[k] = (*v)[static_cast<size_t>(k)].get<double>();
        }
        return out;
    }
    std::vector<long> integers(const std::string& key)
    {
        std::vector<long> out;
        const auto* v = find(key);
        if (!v) return out;
        if (!v->is_array()) fail(key, "expected an array of integers, got " + json_type(*v));
        for (size_t k = 0; k < v->size(); ++k) {
            if (!(*v)[k].is_number_integer()) fail(key + "/" + std::to_string(k), "expected an integer");
            out.push_back((*v)[k].get<long>());
        }
        return out;
    }
    Reader object(const std::string& key)
    {
        const auto* v = find(key);
        static const nlohmann::json empty = nlohmann::json::object();
        return Reader(v ? *v : empty, m_file, m_ptr + "/" + key);
    }
    const nlohmann::json& json() const { return m_j; }
    const std::string& file() const { return m_file; }
    const std::string& pointer() const { return m_ptr; }
    void finish() const
    {
        for (auto it = m_j.begin(); it != m_j.end(); ++it)
            if (!m_read.count(it.key()))
                fail(it.key(), "unknown key (see scenes/README.md for the keys of this object)");
    }

private:
    const nlohmann::json& m_j;
    std::string m_file, m_ptr;
    std::set<std::string> m_read;
};

std::string resolve(const std::string& path, const PathRoots& roots, bool& available, std::string& why)
{
    available = true;
    std::string full;
    if (path.rfind("data:", 0) == 0) {
        if (roots.data.empty()) {
            available = false;
            why = path + " (no --data given)";
            return "";
        }
        full = roots.data + "/" + path.substr(5);
    } else if (path.rfind("cache:", 0) == 0)
        full = roots.cache + "/" + path.substr(6);
    else if (!path.empty() && path[0] == '/')
        full = path;
    else
        full = (roots.scene_dir.empty() ? std::string(".") : roots.scene_dir) + "/" + path;
    const std::string problem = regular_file_problem(full);  // a FIFO is named as one, not "not found"
    if (!problem.empty()) {
        available = false;
        why = full + " (" + problem + ")";
    }
    return full;
}

struct MeshChoice {
    TetMesh mesh;
    std::string source, quality, file;
};

MeshChoice load_body_mesh(Reader& body, const PathRoots& roots)
{
    const nlohmann::json* spec = body.find("mesh");
    const nlohmann::json* box = body.find("box");
    if (spec && box) body.fail("box", "give either 'mesh' or 'box', not both");
    MeshChoice out;
    if (box) {
        Reader b(*box, body.file(), body.pointer() + "/box");
        const std::vector<long> cells = b.integers("cells");
        if (cells.size() != 3 || *std::min_element(cells.begin(), cells.end()) < 1)
            b.fail("cells", "expected 3 positive integers [nx, ny, nz]");
        // Bounded before anything is allocated (a product of three longs can overflow: doubles).
        const double n_cells = double(cells[0]) * double(cells[1]) * double(cells[2]);
        if (n_cells * 6 > double(roots.max_tets))
            b.fail("cells", "[" + std::to_string(cells[0]) + ", " + std::to_string(cells[1]) + ", " +
                                std::to_string(cells[2]) + "] is " + fmt_count(n_cells) +
                                " cells, more than the limit of " + std::to_string(roots.max_tets / 6) + " (" +
                                std::to_string(roots.max_tets) + " tets)");
        const Vec3 size = b.vec3("size", Vec3(1, 1, 1));
        if (size.minCoeff() <= 0) b.fail("size", "must be > 0 in every direction");
        const bool center = b.boolean("center", true);
        b.finish();
        const Vec3 cell(size.x() / cells[0], size.y() / cells[1], size.z() / cells[2]);
        try {
            out.mesh = make_box_mesh(static_cast<int>(cells[0]), static_cast<int>(cells[1]), static_cast<int>(cells[2]),
                                     cell, center ? Vec3(-0.5 * size) : Vec3::Zero());
        } catch (const InputError& e) {  // "box mesh: tet 1: degenerate": say which scene and field
            char edges[96];
            std::snprintf(edges, sizeof edges, "%g x %g x %g", cell.x(), cell.y(), cell.z());
            b.fail("size", std::string("cells of ") + edges + " give degenerate tets (" + e.what() +
                               "): make the box larger or its cells less flat");
        }
        out.source =
            "box " + std::to_string(cells[0]) + "x" + std::to_string(cells[1]) + "x" + std::to_string(cells[2]);
        return out;
    }
    if (!spec) body.fail("mesh", "missing: every body needs 'mesh' or 'box'");
    std::vector<nlohmann::json> alts;
    if (spec->is_array())
        alts.assign(spec->begin(), spec->end());
    else
        alts.push_back(*spec);
    if (alts.empty()) body.fail("mesh", "empty list of mesh alternatives");
    std::string tried;
    for (size_t a = 0; a < alts.size(); ++a) {
        const std::string ptr = body.pointer() + "/mesh" + (spec->is_array() ? "/" + std::to_string(a) : "");
        nlohmann::json obj = alts[a].is_string() ? nlohmann::json{{"path", alts[a]}} : alts[a];
        Reader m(obj, body.file(), ptr);
        const std::string path = m.string("path", "");
        if (path.empty()) m.fail("path", "missing mesh path");
        const long resolution = m.integer("resolution", 16, 1, 512);
        const double fit = m.number("fit_size", 0.0, -1e-300);
        const bool center = m.boolean("center", false);
        const Vec3 pre_rot = m.vec3("rotate_deg", Vec3::Zero());
        m.finish();
        bool ok = false;
        std::string why;
        const std::string full = resolve(path, roots, ok, why);
        if (!ok) {
            tried += (tried.empty() ? "" : "; ") + why;
            continue;
        }
        if (is_surface_mesh_path(full)) {
            const SurfaceMesh s = read_surface_mesh(full);
            TetrahedralizeOptions opt;
            opt.resolution = static_cast<int>(resolution);
            opt.max_tets = roots.max_tets;
            out.mesh = tetrahedralize(s, opt, full);
            out.quality = mesh_quality(out.mesh).to_string();
            out.source = full + " (tetrahedralised, resolution " + std::to_string(resolution) + ")";
            out.file = full;
        } else {
            out.mesh = read_tet_mesh(full);
            out.source = full;
            out.file = full;
        }
        Vec3 lo, hi;
        bounding_box(out.mesh.positions, lo, hi);
        if (center) transform_positions(out.mesh.positions, 1.0, Eigen::Matrix3d::Identity(), -0.5 * (lo + hi));
        if (pre_rot.squaredNorm() > 0)
            transform_positions(out.mesh.positions, 1.0, rotation_from_euler_deg(pre_rot), Vec3::Zero());
        if (fit > 0) {
            bounding_box(out.mesh.positions, lo, hi);
            transform_positions(out.mesh.positions, fit / (hi - lo).maxCoeff(), Eigen::Matrix3d::Identity(),
                                Vec3::Zero());
        }
        return out;
    }
    throw_input_error(body.file(), body.pointer() + "/mesh", "no mesh alternative is available: tried " + tried);
}

std::unique_ptr<Obstacle> load_obstacle(Reader& o, const PathRoots& roots,
                                        std::vector<std::unique_ptr<Obstacle>>& extra)
{
    const std::string type = o.string("type", "", {"plane", "sphere", "box", "cylinder", "mesh", "stairs"});
    if (type.empty()) o.fail("type", "missing: one of plane, sphere, box, cylinder, mesh, stairs");
    if (type == "plane") {
        const Vec3 n = o.vec3("normal", Vec3(0, 1, 0));
        if (n.norm() == 0) o.fail("normal", "must be non-zero");
        return make_plane(n, o.vec3("point", Vec3::Zero()));
    }
    if (type == "sphere") return make_sphere(o.vec3("center", Vec3::Zero()), o.number("radius", 1.0, 0.0));
    if (type == "box") {
        const Vec3 lo = o.vec3("min", Vec3(-1, -1, -1)), hi = o.vec3("max", Vec3(1, 1, 1));
        if ((hi - lo).minCoeff() <= 0) o.fail("max", "must exceed /min in every direction");
        return make_box(lo, hi);
    }
    if (type == "cylinder") {
        const Vec3 axis = o.vec3("axis", Vec3(0, 1, 0));
        if (axis.norm() == 0) o.fail("axis", "must be non-zero");
        return make_cylinder(o.vec3("center", Vec3::Zero()), axis, o.number("radius", 0.1, 0.0),
                             o.number("height", 1.0, 0.0));
    }
    if (type == "stairs") {
        // n steps climbing along -z from `origin` (front bottom of the first step), each
        // `run` deep (z) and `rise` high (y), `width` wide (x), as solid boxes down to origin.y.
        const long n = o.integer("steps", 4, 1, 1000);
        const Vec3 origin = o.vec3("origin", Vec3::Zero());
        const double width = o.number("width", 2.0, 0.0), rise = o.number("rise", 0.2, 0.0),
                     run = o.number("run", 0.4, 0.0);
        for (long k = 0; k < n; ++k) {
            const Vec3 lo(origin.x() - 0.5 * width, origin.y(), origin.z() - (k + 1) * run);
            const Vec3 hi(origin.x() + 0.5 * width, origin.y() + (k + 1) * rise, origin.z() - k * run);
            if (k + 1 < n)
                extra.push_back(make_box(lo, hi));
            else
                return make_box(lo, hi);
        }
    }
    // mesh
    const std::string path = o.string("path", "");
    if (path.empty()) o.fail("path", "missing obstacle mesh path");
    bool ok = false;
    std::string why;
    const std::string full = resolve(path, roots, ok, why);
    if (!ok) o.fail("path", "mesh unavailable: " + why);
    SurfaceMesh s = read_surface_mesh(full);
    transform_positions(s.positions, o.number("scale", 1.0, 0.0),
                        rotation_from_euler_deg(o.vec3("rotate_deg", Vec3::Zero())), o.vec3("translate", Vec3::Zero()));
    return make_mesh_obstacle(std::move(s), o.number("thickness", 0.05, 0.0));
}

}  // namespace

PathRoots default_path_roots(const std::string& scene_path, const std::string& data_dir)
{
    PathRoots r;
    r.data = data_dir;
    const char* cache = std::getenv("CB_CACHE");
    const char* home = std::getenv("HOME");
    r.cache = cache && *cache ? std::string(cache) : std::string(home ? home : ".") + "/.cache/contactbench";
    const auto slash = scene_path.find_last_of('/');
    r.scene_dir = slash == std::string::npos ? "." : scene_path.substr(0, slash);
    return r;
}

Scene load_scene(const std::string& path, const PathRoots& roots)
{
    // A regular file only (a FIFO would block), nesting bounded (deep JSON overflows the stack).
    nlohmann::json j = read_json_checked(path, /*allow_comments=*/true);
    const auto dot = path.find_last_of('.');
    if (dot != std::string::npos && path.substr(dot) == ".ini") j = import_authors_ini(j, path);
    return load_scene_json(j, path, roots);
}

Scene load_scene_json(const nlohmann::json& j, const std::string& file, const PathRoots& roots)
{
    Scene s;
    s.file = file;
    Reader r(j, file, "");
    std::string stem = file.substr(file.find_last_of('/') == std::string::npos ? 0 : file.find_last_of('/') + 1);
    stem = stem.substr(0, stem.find('.'));
    s.name = r.string("name", stem);
    for (char ch : s.name)
        if (!(std::isalnum(static_cast<unsigned char>(ch)) || ch == '_' || ch == '-'))
            r.fail("name", "only letters, digits, '_' and '-' (it names files), got '" + s.name + "'");
    s.description = r.string("description", "");
    s.step.h = r.number("h", 0.01, 0.0, 10.0);
    s.frames = r.integer("frames", 20, 0);
    s.steps_per_frame = static_cast<int>(r.integer("steps_per_frame", 1, 1, 10000));
    s.newton_iterations = static_cast<int>(r.integer("newton_iterations", 1, 1, 100));
    s.step.gravity = r.vec3("gravity", Vec3(0, -9.8, 0));
    s.step.a_M = r.number("a_M", 0.0, -1e-300);
    s.step.a_K = r.number("a_K", 0.0, -1e-300);
    s.solver = r.string("solver", "mprgp");
    // A scene is data that travels (downloaded, shared): naming a program to run is opt-in, here
    // and on the command line (--allow-commands of simulate and chains), as for suites.
    s.allow_commands = r.boolean("allow_commands", false);
    if (s.solver == "command" && !s.allow_commands)
        r.fail("solver", "'command' runs an external program; the scene must opt in with \"allow_commands\": "
                         "true (and the command line with --allow-commands)");
    if (const auto* st = r.find("solver_settings")) {
        if (!st->is_object()) r.fail("solver_settings", "expected an object, got " + json_type(*st));
        s.solver_settings = *st;
    }
    s.blowup_speed = r.number("blowup_speed", 100.0, 0.0);
    s.friction.mu = r.number("mu", 0.0, -1e-300, 1e6);
    if (r.has("friction_settings")) {
        Reader f = r.object("friction_settings");
        if (!(s.friction.mu > 0.0)) f.fail_here("applies only to a frictional scene (\"mu\" > 0)");
        s.friction.solver = f.string("solver", "nsgs", {"nsgs", "siconos-nsn", "siconos-nsgs"});
        if (s.friction.solver != "nsgs" && !siconos_fc3d_built())
            f.fail("solver",
                   "'" + s.friction.solver + "' needs Siconos numerics, which this contactbench is built without");
        s.friction.tol = f.number("tol", s.friction.tol, 0.0, 1.0);
        s.friction.max_iterations = f.integer("max_iterations", s.friction.max_iterations, 1);
        s.friction.time_limit_s = f.number("time_limit_s", 0.0, -1e-300);
        f.finish();
    }
    {
        Reader d = r.object("detection");
        s.detection.margin = d.number("margin", 0.0, -1e-300);
        s.detection.inter_body = d.boolean("inter_body", true);
        s.detection.self_contact = d.boolean("self_contact", false);
        s.detection.inside_tolerance = d.number("inside_tolerance", 1e-9, -1e-300);
        s.detect_at = d.string("at", "start", {"start", "predicted"});
        d.finish();
    }
    {
        Reader o = r.object("output");
        s.output.snapshots = o.boolean("snapshots", true);
        const std::vector<long> range = o.integers("snapshot_frames");
        if (!range.empty()) {
            if (range.size() != 2) o.fail("snapshot_frames", "expected [first, last] (last -1: to the end)");
            s.output.snapshot_first = range[0];
            s.output.snapshot_last = range[1];
        }
        s.output.strip_frames = static_cast<int>(o.integer("strip_frames", 6, 0, 64));
        s.output.image_size = static_cast<int>(o.integer("image_size", 256, 16, 4096));
        // The strip is one image of strip_frames tiles: bounded (64 Mpixel) before it is allocated.
        if (double(s.output.strip_frames) * s.output.image_size * s.output.image_size > 67108864.0)
            o.fail("image_size",
                   "strip_frames x image_size^2 = " +
                       fmt_count(double(s.output.strip_frames) * s.output.image_size * s.output.image_size) +
                       " pixels, more than the limit of 67108864");
        s.output.view_deg = o.vec3("view_deg", s.output.view_deg);
        s.output.export_frames = o.integers("export_frames");
        o.finish();
    }
    const auto* bodies = r.find("bodies");
    if (!bodies || !bodies->is_array() || bodies->empty()) r.fail("bodies", "expected a non-empty array of bodies");
    double total_tets = 0;
    for (size_t bi = 0; bi < bodies->size(); ++bi) {
        Reader b((*bodies)[bi], file, "/bodies/" + std::to_string(bi));
        Body proto;
        proto.name = b.string("name", "body" + std::to_string(bi));
        {
            Reader m = b.object("material");
            proto.material.youngs = m.number("youngs", 1e6, 0.0);
            proto.material.poisson = m.number("poisson", 0.4, -1.0, 0.499);
            proto.material.density = m.number("density", 1000.0, 0.0);
            m.finish();
        }
        const double scale = b.number("scale", 1.0, 0.0);
        const Vec3 rot = b.vec3("rotate_deg", Vec3::Zero());
        const Vec3 trans = b.vec3("translate", Vec3::Zero());
        proto.velocity = b.vec3("velocity", Vec3::Zero());
        long count[3] = {1, 1, 1};
        Vec3 spacing = Vec3::Zero();
        if (b.has("array")) {
            Reader a = b.object("array");
            const std::vector<long> c = a.integers("count");
            if (c.size() != 3 || *std::min_element(c.begin(), c.end()) < 1)
                a.fail("count", "expected 3 positive integers");
            for (int k = 0; k < 3; ++k) count[k] = c[static_cast<size_t>(k)];
            const double copies = double(count[0]) * double(count[1]) * double(count[2]);
            if (copies > double(roots.max_tets))
                a.fail("count", fmt_count(copies) + " copies, more than the limit of " +
                                    std::to_string(roots.max_tets) + " tets allows");
            spacing = a.vec3("spacing", Vec3::Zero());
            a.finish();
        } else
            b.find("array");
        MeshChoice mc = load_body_mesh(b, roots);
        b.finish();
        const double body_tets = double(mc.mesh.tet_count()) * double(count[0]) * double(count[1]) * double(count[2]);
        total_tets += body_tets;
        if (total_tets > double(roots.max_tets))
            b.fail(b.has("array") ? "array/count" : "mesh", "the scene reaches " + fmt_count(total_tets) +
                                                                " tets, more than the limit of " +
                                                                std::to_string(roots.max_tets));
        transform_positions(mc.mesh.positions, scale, rotation_from_euler_deg(rot), trans);
        proto.source = mc.source;
        proto.quality = mc.quality;
        proto.mesh_file = mc.file;
        for (long k = 0; k < count[2]; ++k)
            for (long jj = 0; jj < count[1]; ++jj)
                for (long i = 0; i < count[0]; ++i) {
                    Body body = proto;
                    body.mesh = mc.mesh;
                    const Vec3 off(i * spacing.x(), jj * spacing.y(), k * spacing.z());
                    transform_positions(body.mesh.positions, 1.0, Eigen::Matrix3d::Identity(), off);
                    if (count[0] * count[1] * count[2] > 1) body.name += "_" + std::to_string(s.bodies.size());
                    s.bodies.push_back(std::move(body));
                }
    }
    if (const auto* obs = r.find("obstacles")) {
        if (!obs->is_array()) r.fail("obstacles", "expected an array");
        for (size_t oi = 0; oi < obs->size(); ++oi) {
            Reader o((*obs)[oi], file, "/obstacles/" + std::to_string(oi));
            std::vector<std::unique_ptr<Obstacle>> extra;
            auto ob = load_obstacle(o, roots, extra);
            o.finish();
            for (auto& e : extra) s.obstacles.push_back(std::move(e));
            s.obstacles.push_back(std::move(ob));
        }
    }
    r.finish();
    return s;
}

nlohmann::json import_authors_ini(const nlohmann::json& ini, const std::string& file)
{
    if (!ini.is_object()) throw_input_error(file, "/", "expected a JSON object");
    using nlohmann::json;
    json s;
    auto num = [&](const char* key, double fallback) {
        return ini.contains(key) && ini[key].is_number() ? ini[key].get<double>() : fallback;
    };
    std::string stem = file.substr(file.find_last_of('/') == std::string::npos ? 0 : file.find_last_of('/') + 1);
    s["name"] = stem.substr(0, stem.find('.'));
    s["description"] = "imported from the authors' " + stem;
    s["h"] = num("h", 0.01);
    // The authors' names are swapped: "alpha_k" multiplies M and "alpha_m" multiplies K.
    s["a_M"] = num("alpha_k", 0.0);
    s["a_K"] = num("alpha_m", 0.0);
    if (ini.contains("gravity")) s["gravity"] = ini["gravity"];
    s["frames"] = static_cast<long>(num("num_frames", 20));
    s["newton_iterations"] = static_cast<long>(num("newton_max_iteration", 1));
    const std::string solver = ini.value("fem_solver", "mprgp");
    s["solver"] = solver == "ica" ? "ica" : solver == "general_mprgp" ? "mprgp-coupled" : "mprgp";
    s["solver_settings"] = {{"stop", "native"},
                            {"tol", num("mprgp_tolerance", 1e-5)},
                            {"max_iterations", static_cast<long>(num("mprgp_max_iteration", 1000))}};
    s["detection"] = {{"self_contact", ini.value("enable_self_con", false)}};
    auto mesh_path = [](const std::string& p) {
        // "model/mesh_1303_4014.abq" -> "data:meshes/dino_1303_4014.abq" (the dinosaur files);
        // plain "model/mesh.abq" has no counterpart with a known resolution: keep the name.
        const std::string base = p.substr(p.find_last_of('/') + 1);
        if (base.rfind("mesh_", 0) == 0) return "data:meshes/dino_" + base.substr(5);
        return "data:meshes/" + base;
    };
    json bodies = json::array();
    auto add_body = [&](const std::string& vol, const json& trs, const json& vel, const json& array) {
        json b;
        b["mesh"] = mesh_path(vol);
        if (trs.is_array() && trs.size() == 7) {
            b["translate"] = {trs[0], trs[1], trs[2]};
            b["rotate_deg"] = {trs[3], trs[4], trs[5]};
            b["scale"] = trs[6];
        }
        if (vel.is_array() && vel.size() == 3) b["velocity"] = vel;
        if (!array.is_null()) b["array"] = array;
        bodies.push_back(b);
    };
    if (ini.contains("vol_file") && ini["vol_file"].is_array())
        for (size_t i = 0; i < ini["vol_file"].size(); ++i)
            add_body(ini["vol_file"][i].get<std::string>(),
                     ini.contains("trans_rot_scale") && i < ini["trans_rot_scale"].size() ? ini["trans_rot_scale"][i]
                                                                                          : json(),
                     ini.contains("init_vel") && i < ini["init_vel"].size() ? ini["init_vel"][i] : json(), json());
    if (ini.contains("group_vol_mtl_file") && ini.contains("group_trans_rot_scale_vel")) {
        const json& g = ini["group_trans_rot_scale_vel"];
        const json& d = ini.value("group_dx_dy_dz_nx_ny_nz", json::array({0, 0, 0, 1, 1, 1}));
        add_body(ini["group_vol_mtl_file"][0].get<std::string>(),
                 json::array({g[0], g[1], g[2], g[3], g[4], g[5], g[6]}), json::array({g[7], g[8], g[9]}),
                 json{{"count", {d[3], d[4], d[5]}}, {"spacing", {d[0], d[1], d[2]}}});
    }
    s["bodies"] = bodies;
    json obstacles = json::array();
    if (ini.contains("plane_ori_trans_scale"))
        for (const auto& p : ini["plane_ori_trans_scale"])
            obstacles.push_back({{"type", "plane"}, {"normal", {p[0], p[1], p[2]}}, {"point", {p[3], p[4], p[5]}}});
    if (ini.contains("cylinder_rad_y_ori_trans"))
        for (const auto& c : ini["cylinder_rad_y_ori_trans"])
            obstacles.push_back({{"type", "cylinder"},
                                 {"radius", c[0]},
                                 {"height", 2.0 * c[1].get<double>()},
                                 {"axis", {c[2], c[3], c[4]}},
                                 {"center", {c[5], c[6], c[7]}}});
    if (!obstacles.empty()) s["obstacles"] = obstacles;
    return s;
}

}  // namespace cb::sim
