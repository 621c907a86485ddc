// Synthetic QP families. The FEM-like matrix is assembled straight into its CSR pattern (the
// Kuhn split of a cube into 6 tets has one fixed 15-point vertex stencil), so 100k-DOF bodies
// take milliseconds and no triplet list.
// Ref: Li et al., CGF 2015, eq. (9) (the QP) and eq. (8) (vertex-triangle rows).
#include "problems/synthetic.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <map>
#include <random>
#include <sstream>

namespace cb {
namespace {

// ---------------------------------------------------------------------------------------------
// Parameters: every family's keys and defaults live in this one table.

struct ParamSpec {
    const char* name;
    nlohmann::json value;  ///< default; its type is the expected type (integer, number, bool)
    const char* help;
};

std::vector<ParamSpec> fem_params()
{
    const FemGridParams d;
    return {
        {"nx", d.nx, "cubes along x"},
        {"ny", d.ny, "cubes along y (up)"},
        {"nz", d.nz, "cubes along z"},
        {"spacing", d.spacing, "cube edge length, m"},
        {"youngs", d.youngs, "Young's modulus, Pa (up to 1e12 for stiff bodies)"},
        {"poisson", d.poisson, "Poisson ratio, in (-1, 0.5)"},
        {"density", d.density, "kg/m^3"},
        {"h", d.h, "time step, s (A = M + h^2 K)"},
        {"length_scale", 1.0, "length unit in m (1e-3: lengths in mm, 1e3: km)"},
        {"mass_scale", 1.0, "mass unit in kg (1e-3: g, 1e3: t)"},
    };
}

std::vector<ParamSpec> scene_params()
{
    return {
        {"gravity", 9.81, "gravity along -y, m/s^2"},
        {"gap", 0.002, "distance from the body to the ground (or the other body) at the start, m"},
        {"speed", 1.0, "speed toward the ground (or the other body), m/s"},
        {"noise", 0.05, "random per-vertex velocity noise (uniform, +-), m/s"},
    };
}

struct FamilySpec {
    const char* summary;
    std::vector<ParamSpec> params;
};

const std::map<std::string, FamilySpec>& families()
{
    static const std::map<std::string, FamilySpec> table = [] {
        std::map<std::string, FamilySpec> t;
        auto with = [](std::vector<ParamSpec> a, const std::vector<ParamSpec>& b) {
            a.insert(a.end(), b.begin(), b.end());
            return a;
        };
        const auto fem = fem_params();
        const auto scene = with(fem, scene_params());
        const std::vector<ParamSpec> plane_own = {
            {"tilt_deg", 0.0, "ground tilt about z, degrees (normal (sin t, cos t, 0))"},
            {"margin", 1.5, "rows for vertices closer to the ground than margin * spacing at x0"},
        };
        const auto plane = with(scene, plane_own);
        t["unconstrained"] = {"the falling body of 'plane' without any row (m = 0)", scene};
        t["plane"] = {"a body falling onto a ground plane y >= 0: one unit-normal row (3 nnz) per vertex "
                      "near the ground, decoupled; x0 = predicted positions, some penetrate",
                      plane};
        t["box"] = {"bounds x_i >= l_i or -x_i >= -u_i (signed unit rows) on a random subset of DOFs",
                    with(fem, {{"fraction", 0.3, "share of DOFs with a bound"},
                               {"spread", 0.1,
                                "bound offsets uniform in +-spread * spacing around the "
                                "unconstrained minimiser"}})};
        t["coupled"] = {"a smaller body pressed onto a lower body: vertex-triangle rows of eq. (8), 12 nnz, "
                        "c = 0, rows share vertices (not decoupled); the scene is randomly rotated",
                        with(scene, {{"upper_scale", 0.77, "upper body spacing / lower body spacing, in (0, 1)"},
                                     {"upper_ny", 2, "cubes of the upper body along y"},
                                     {"rotate", true, "rotate the whole scene randomly (generic normals)"}})};
        t["random-spd"] = {"random dense SPD with a given condition number and random sparse rows",
                           {{"n", 100, "size"},
                            {"m", 30, "rows"},
                            {"condition", 1e4, "condition number of A (eigenvalues log-spaced in [1, condition])"},
                            {"row_nnz", 3, "nonzeros per row of J"},
                            {"length_scale", 1.0, "divide x by this"},
                            {"mass_scale", 1.0, "divide A and b by this"}}};
        t["infeasible"] = {"'plane' plus contradictory pairs x_i >= 1 and -x_i >= 0 on the same DOF: empty set",
                           with(plane, {{"pairs", 1, "contradictory pairs"}})};
        t["duplicate-rows"] = {"'plane' with a random share of rows repeated right after themselves",
                               with(plane, {{"fraction", 0.3, "share of rows duplicated"}})};
        t["scaled-rows"] = {"'plane' with each row (and its c) multiplied by a log-uniform factor in "
                            "[1/row_scale, row_scale]",
                            with(plane, {{"row_scale", 1e3, "largest factor (>= 1)"}})};
        t["zero-rows"] = {"'plane' with empty rows (0 >= c, c <= 0) inserted at random places",
                          with(plane, {{"count", 3, "zero rows"}, {"c", 0.0, "their c (must be <= 0)"}})};
        return t;
    }();
    return table;
}

/// Effective parameters: defaults overridden by `params`; unknown keys and wrong types rejected.
nlohmann::json effective_params(const std::string& family, const FamilySpec& spec, const nlohmann::json& params)
{
    const std::string where = "synthetic family '" + family + "'";
    if (!params.is_null() && !params.is_object())
        throw_input_error(where, "params", "expected a JSON object, got " + params.dump());
    nlohmann::json out = nlohmann::json::object();
    for (const auto& p : spec.params) out[p.name] = p.value;
    if (params.is_null()) return out;
    for (auto it = params.begin(); it != params.end(); ++it) {
        if (!out.contains(it.key())) {
            std::string known;
            for (const auto& p : spec.params) known += std::string(known.empty() ? "" : ", ") + p.name;
            throw_input_error(where, "params." + it.key(), "unknown parameter; known: " + known);
        }
        const nlohmann::json& def = out[it.key()];
        const nlohmann::json& v = it.value();
        if (def.is_boolean()) {
            if (!v.is_boolean())
                throw_input_error(where, "params." + it.key(), "expected true or false, got " + v.dump());
            out[it.key()] = v;
        } else if (def.is_number_integer()) {
            if (!v.is_number() || std::floor(v.get<double>()) != v.get<double>() || std::abs(v.get<double>()) > 1e9)
                throw_input_error(where, "params." + it.key(), "expected an integer, got " + v.dump());
            out[it.key()] = static_cast<long long>(v.get<double>());
        } else {
            if (!v.is_number() || !std::isfinite(v.get<double>()))
                throw_input_error(where, "params." + it.key(), "expected a finite number, got " + v.dump());
            out[it.key()] = v.get<double>();
        }
    }
    return out;
}

/// Bounds of the generator (problems/synthetic.hpp): what a laptop holds, stated in the messages.
constexpr double MAX_GRID_VERTICES = 1e6;
constexpr long MAX_ROWS = 10000000;

[[noreturn]] void bad_param(const std::string& family, const std::string& key, const std::string& what,
                            const nlohmann::json& got)
{
    throw_input_error("synthetic family '" + family + "'", "params." + key, "expected " + what + ", got " + got.dump());
}

FemGridParams fem_from(const std::string& family, const nlohmann::json& p)
{
    FemGridParams f;
    f.nx = p["nx"].get<int>();
    f.ny = p["ny"].get<int>();
    f.nz = p["nz"].get<int>();
    f.spacing = p["spacing"].get<double>();
    f.youngs = p["youngs"].get<double>();
    f.poisson = p["poisson"].get<double>();
    f.density = p["density"].get<double>();
    f.h = p["h"].get<double>();
    if (!(p["length_scale"].get<double>() > 0)) bad_param(family, "length_scale", "> 0", p["length_scale"]);
    if (!(p["mass_scale"].get<double>() > 0)) bad_param(family, "mass_scale", "> 0", p["mass_scale"]);
    return f;
}

void validate(const FemGridParams& p, const std::string& where)
{
    auto bad = [&](const char* key, const std::string& what, double got) {
        std::ostringstream s;
        s << "expected " << what << ", got " << got;
        throw_input_error(where, key, s.str());
    };
    if (p.nx < 1) bad("nx", "an integer >= 1", p.nx);
    if (p.ny < 1) bad("ny", "an integer >= 1", p.ny);
    if (p.nz < 1) bad("nz", "an integer >= 1", p.nz);
    // Memory grows with the grid (about 1 kB per vertex while assembling): bounded before it is built.
    const double vertices = double(p.nx + 1) * (double(p.ny) + 1) * (double(p.nz) + 1);
    if (vertices > MAX_GRID_VERTICES) bad("nx", "at most 1e6 vertices in all (nx+1)(ny+1)(nz+1)", vertices);
    if (!(p.spacing > 0) || !std::isfinite(p.spacing)) bad("spacing", "> 0", p.spacing);
    if (!(p.youngs > 0) || !std::isfinite(p.youngs)) bad("youngs", "> 0", p.youngs);
    if (!(p.poisson > -1 && p.poisson < 0.5)) bad("poisson", "a value in (-1, 0.5)", p.poisson);
    if (!(p.density > 0) || !std::isfinite(p.density)) bad("density", "> 0", p.density);
    if (!(p.h > 0) || !std::isfinite(p.h)) bad("h", "> 0", p.h);
}

// ---------------------------------------------------------------------------------------------
// FEM body on a grid.

using V3 = Eigen::Vector3d;

struct GridBody {
    int nx = 1, ny = 1, nz = 1;
    std::vector<V3> rest;  ///< (nx+1)(ny+1)(nz+1) positions, any (e.g. rotated) placement
    int vertex(int i, int j, int k) const { return i + (nx + 1) * (j + (ny + 1) * k); }
    int vertices() const { return (nx + 1) * (ny + 1) * (nz + 1); }
    int tets() const { return 6 * nx * ny * nz; }
};

GridBody make_grid(int nx, int ny, int nz, double spacing, const V3& origin)
{
    GridBody g;
    g.nx = nx;
    g.ny = ny;
    g.nz = nz;
    g.rest.resize(g.vertices());
    for (int k = 0; k <= nz; ++k)
        for (int j = 0; j <= ny; ++j)
            for (int i = 0; i <= nx; ++i) g.rest[g.vertex(i, j, k)] = origin + spacing * V3(i, j, k);
    return g;
}

struct Assembled {
    SpMat A;   ///< M + h^2 K
    Vec mass;  ///< lumped mass per DOF
};

/// The 15 stencil offsets of the Kuhn split, coded as (ox+1) + 3 (oy+1) + 9 (oz+1).
Assembled assemble(const GridBody& g, const FemGridParams& p)
{
    const int NX = g.nx + 1, NY = g.ny + 1, NZ = g.nz + 1;
    const int nv = g.vertices();
    const long n = 3L * nv;
    // Stencil: 0 and +-{the 7 nonzero {0,1}^3 vectors}, sorted by linear index delta.
    std::vector<std::array<int, 3>> offsets;
    for (int oz = -1; oz <= 1; ++oz)
        for (int oy = -1; oy <= 1; ++oy)
            for (int ox = -1; ox <= 1; ++ox) {
                const bool nonneg = ox >= 0 && oy >= 0 && oz >= 0;
                const bool nonpos = ox <= 0 && oy <= 0 && oz <= 0;
                if (nonneg || nonpos) offsets.push_back({ox, oy, oz});  // loop order = sorted by delta
            }
    // Per vertex: neighbour count, first value index, slot per offset code.
    std::vector<int> count(nv), slot(size_t(nv) * 27, -1);
    std::vector<long> base(nv + 1);
    base[0] = 0;
    for (int k = 0; k < NZ; ++k)
        for (int j = 0; j < NY; ++j)
            for (int i = 0; i < NX; ++i) {
                const int v = g.vertex(i, j, k);
                int c = 0;
                for (const auto& o : offsets) {
                    const int a = i + o[0], b = j + o[1], d = k + o[2];
                    if (a < 0 || a >= NX || b < 0 || b >= NY || d < 0 || d >= NZ) continue;
                    slot[size_t(v) * 27 + (o[0] + 1) + 3 * static_cast<size_t>(o[1] + 1) +
                         9 * static_cast<size_t>(o[2] + 1)] = c++;
                }
                count[v] = c;
                base[v + 1] = base[v] + 9L * c;
            }
    Assembled out;
    SpMat& A = out.A;
    A.resize(n, n);
    A.resizeNonZeros(base[nv]);
    int* outer = A.outerIndexPtr();
    int* inner = A.innerIndexPtr();
    double* val = A.valuePtr();
    for (int k = 0; k < NZ; ++k)
        for (int j = 0; j < NY; ++j)
            for (int i = 0; i < NX; ++i) {
                const int v = g.vertex(i, j, k);
                for (int d = 0; d < 3; ++d) {
                    long pos = base[v] + 3L * d * count[v];
                    outer[3 * v + d] = int(pos);
                    for (const auto& o : offsets) {
                        const int a = i + o[0], b = j + o[1], e = k + o[2];
                        if (a < 0 || a >= NX || b < 0 || b >= NY || e < 0 || e >= NZ) continue;
                        const int u = g.vertex(a, b, e);
                        for (int dd = 0; dd < 3; ++dd) inner[pos++] = 3 * u + dd;
                    }
                }
            }
    outer[n] = int(base[nv]);
    std::fill(val, val + base[nv], 0.0);
    out.mass = Vec::Zero(n);

    const double mu = p.youngs / (2 * (1 + p.poisson));
    const double lambda = p.youngs * p.poisson / ((1 + p.poisson) * (1 - 2 * p.poisson));
    static const int perms[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
    for (int k = 0; k < g.nz; ++k)
        for (int j = 0; j < g.ny; ++j)
            for (int i = 0; i < g.nx; ++i)
                for (const auto& perm : perms) {
                    // Kuhn tet: walk from corner (0,0,0) to (1,1,1) along axes perm[0], perm[1], perm[2].
                    std::array<std::array<int, 3>, 4> c{};
                    c[0] = {i, j, k};
                    for (int s = 1; s < 4; ++s) {
                        c[s] = c[s - 1];
                        c[s][perm[s - 1]] += 1;
                    }
                    std::array<int, 4> vid;
                    for (int s = 0; s < 4; ++s) vid[s] = g.vertex(c[s][0], c[s][1], c[s][2]);
                    Eigen::Matrix3d D;
                    for (int s = 0; s < 3; ++s) D.col(s) = g.rest[vid[s + 1]] - g.rest[vid[0]];
                    const double volume = std::abs(D.determinant()) / 6.0;
                    const Eigen::Matrix3d Dinv = D.inverse();
                    std::array<V3, 4> grad;
                    for (int s = 0; s < 3; ++s) grad[s + 1] = Dinv.row(s).transpose();
                    grad[0] = -(grad[1] + grad[2] + grad[3]);
                    for (int a = 0; a < 4; ++a) {
                        out.mass.segment<3>(3 * static_cast<Eigen::Index>(vid[a])).array() += p.density * volume / 4.0;
                        for (int b = 0; b < 4; ++b) {
                            const int code =
                                (c[b][0] - c[a][0] + 1) + 3 * (c[b][1] - c[a][1] + 1) + 9 * (c[b][2] - c[a][2] + 1);
                            const int sl = slot[size_t(vid[a]) * 27 + code];
                            const double gab = grad[a].dot(grad[b]);
                            for (int di = 0; di < 3; ++di)
                                for (int dj = 0; dj < 3; ++dj) {
                                    // K_ab = V (lambda g_a g_b' + mu (g_a.g_b) I + mu g_b g_a'); each
                                    // product is written so that K_ba(j, i) rounds exactly like K_ab(i, j).
                                    double kab =
                                        lambda * (grad[a][di] * grad[b][dj]) + mu * (grad[b][di] * grad[a][dj]);
                                    if (di == dj) kab += mu * gab;
                                    val[base[vid[a]] + 3L * di * count[vid[a]] + 3L * sl + dj] += volume * kab;
                                }
                        }
                    }
                }
    const double h2 = p.h * p.h;
    for (long e = 0; e < base[nv]; ++e) val[e] *= h2;
    for (int v = 0; v < nv; ++v) {
        const int sl = slot[size_t(v) * 27 + 13];
        for (int d = 0; d < 3; ++d) val[base[v] + 3L * d * count[v] + 3L * sl + d] += out.mass[3 * v + d];
    }
    return out;
}

/// Block diagonal [A1 0; 0 A2] of two CSR matrices.
SpMat block_diag(const SpMat& A1, const SpMat& A2)
{
    SpMat A(A1.rows() + A2.rows(), A1.cols() + A2.cols());
    A.resizeNonZeros(A1.nonZeros() + A2.nonZeros());
    const int n1 = int(A1.rows()), nnz1 = int(A1.nonZeros());
    std::copy(A1.outerIndexPtr(), A1.outerIndexPtr() + n1, A.outerIndexPtr());
    for (Eigen::Index r = 0; r <= A2.rows(); ++r) A.outerIndexPtr()[n1 + r] = nnz1 + A2.outerIndexPtr()[r];
    std::copy(A1.innerIndexPtr(), A1.innerIndexPtr() + nnz1, A.innerIndexPtr());
    for (Eigen::Index e = 0; e < A2.nonZeros(); ++e)
        A.innerIndexPtr()[nnz1 + e] = int(A1.cols()) + A2.innerIndexPtr()[e];
    std::copy(A1.valuePtr(), A1.valuePtr() + nnz1, A.valuePtr());
    std::copy(A2.valuePtr(), A2.valuePtr() + A2.nonZeros(), A.valuePtr() + nnz1);
    return A;
}

/// Rows of J built one at a time (sorted column indices per row; explicit zeros kept so that the
/// structure is what the family promises).
struct RowBuilder {
    std::vector<int> indptr{0}, indices;
    std::vector<double> data;
    std::vector<double> c;
    ContactRows contacts;
    void add(std::vector<std::pair<int, double>> entries, double rhs, ContactKind kind, double depth,
             std::array<std::int64_t, 4> vertex)
    {
        std::sort(entries.begin(), entries.end());
        for (const auto& e : entries) {
            indices.push_back(e.first);
            data.push_back(e.second);
        }
        indptr.push_back(int(indices.size()));
        c.push_back(rhs);
        contacts.kind.push_back(std::int64_t(kind));
        contacts.depth.push_back(depth);
        contacts.vertex.insert(contacts.vertex.end(), vertex.begin(), vertex.end());
    }
    void finish(Qp& qp, long n) const
    {
        const long m = long(c.size());
        qp.J.resize(m, n);
        qp.J.resizeNonZeros(long(indices.size()));
        std::copy(indptr.begin(), indptr.end(), qp.J.outerIndexPtr());
        std::copy(indices.begin(), indices.end(), qp.J.innerIndexPtr());
        std::copy(data.begin(), data.end(), qp.J.valuePtr());
        qp.c = Eigen::Map<const Vec>(c.data(), m);
        qp.contacts = contacts;
    }
};

struct Scene {
    Assembled fem;
    Vec rest, pred;  ///< rest positions X and predicted positions x_n + h v_n (3 per vertex)
    V3 gravity;
    FemGridParams fp;
    int vertices = 0, tets = 0;
};

/// b = M x_pred + h^2 K X + h^2 M g: the backward-Euler step of linear elasticity in positions.
Vec step_rhs(const Scene& s)
{
    const double h2 = s.fp.h * s.fp.h;
    Vec g = Vec::Zero(s.rest.size());
    for (Eigen::Index v = 0; v < g.size() / 3; ++v) g.segment<3>(3 * v) = s.gravity;
    const Vec KX_h2 = s.fem.A * s.rest - s.fem.mass.cwiseProduct(s.rest);
    return s.fem.mass.cwiseProduct(s.pred) + KX_h2 + h2 * s.fem.mass.cwiseProduct(g);
}

Vec flatten(const std::vector<V3>& pts)
{
    Vec x(3 * pts.size());
    for (size_t v = 0; v < pts.size(); ++v) x.segment<3>(3 * v) = pts[v];
    return x;
}

double uniform(std::mt19937_64& rng, double lo, double hi)
{
    return std::uniform_real_distribution<double>(lo, hi)(rng);
}

/// The plane scene: an axis-aligned body, its lowest point `gap` above the (tilted) ground and
/// moving toward it at `speed`, so that x_pred and the unconstrained minimiser penetrate.
Scene plane_scene(const FemGridParams& fp, const nlohmann::json& p, const V3& normal, std::mt19937_64& rng)
{
    Scene s;
    s.fp = fp;
    GridBody g =
        make_grid(fp.nx, fp.ny, fp.nz, fp.spacing, V3(-0.5 * fp.nx * fp.spacing, 0, -0.5 * fp.nz * fp.spacing));
    double lowest = 1e300;
    for (const auto& x : g.rest) lowest = std::min(lowest, normal.dot(x));
    const V3 lift = (p["gap"].get<double>() - lowest) / normal.y() * V3::UnitY();
    for (auto& x : g.rest) x += lift;
    s.fem = assemble(g, fp);
    s.rest = flatten(g.rest);
    s.gravity = V3(0, -p["gravity"].get<double>(), 0);
    const double noise = p["noise"].get<double>();
    s.pred.resize(s.rest.size());
    for (int v = 0; v < g.vertices(); ++v) {
        V3 vel = -p["speed"].get<double>() * normal;
        for (int d = 0; d < 3; ++d) vel[d] += uniform(rng, -noise, noise);
        s.pred.segment<3>(3 * static_cast<Eigen::Index>(v)) = g.rest[v] + fp.h * vel;
    }
    s.vertices = g.vertices();
    s.tets = g.tets();
    return s;
}

nlohmann::json base_meta(const std::string& family, const nlohmann::json& p, std::uint64_t seed)
{
    nlohmann::json meta;
    meta["generator"] = {{"name", "synthetic"}, {"family", family}, {"seed", seed}, {"params", p}};
    if (p.contains("length_scale"))
        meta["units"] =
            (p["length_scale"] == 1.0 && p["mass_scale"] == 1.0)
                ? nlohmann::json("SI")
                : nlohmann::json{{"length_m", p["length_scale"]}, {"mass_kg", p["mass_scale"]}, {"time_s", 1.0}};
    return meta;
}

void fill_fem_meta(nlohmann::json& meta, const FemGridParams& fp, int vertices, int tets)
{
    meta["h"] = fp.h;
    meta["vertices"] = vertices;
    meta["tets"] = tets;
    meta["material"] = {{"youngs", fp.youngs}, {"poisson", fp.poisson}, {"density", fp.density}};
}

/// Unit change: lengths in units of L m, masses in units of Ms kg. The energy is divided by
/// Ms L^2 (per s^2), so A -> A / Ms, b -> b / (Ms L), x -> x / L, c -> c / L (J is unitless).
void apply_units(Qp& qp, double L, double Ms)
{
    if (L == 1.0 && Ms == 1.0) return;
    qp.A /= Ms;
    qp.b /= (Ms * L);
    qp.x0 /= L;
    qp.c /= L;
    for (auto& d : qp.contacts.depth) d /= L;
}

Qp make_plane_like(const std::string& family, const nlohmann::json& p, std::uint64_t seed, bool rows)
{
    const FemGridParams fp = fem_from(family, p);
    validate(fp, "synthetic family '" + family + "': params");
    std::mt19937_64 rng(seed);
    const double tilt = p.contains("tilt_deg") ? p["tilt_deg"].get<double>() : 0.0;
    if (!(std::abs(tilt) < 80)) bad_param(family, "tilt_deg", "|tilt_deg| < 80", p["tilt_deg"]);
    const double t = tilt * M_PI / 180.0;
    const V3 normal(std::sin(t), std::cos(t), 0.0);
    const Scene s = plane_scene(fp, p, normal, rng);
    Qp qp;
    qp.A = s.fem.A;
    qp.b = step_rhs(s);
    qp.x0 = s.pred;
    const long n = qp.A.rows();
    RowBuilder rb;
    if (rows) {
        const double margin = p["margin"].get<double>() * fp.spacing;
        for (int v = 0; v < s.vertices; ++v) {
            const double dist = normal.dot(V3(s.pred.segment<3>(3 * static_cast<Eigen::Index>(v))));
            if (dist >= margin) continue;
            rb.add({{3 * v, normal.x()}, {3 * v + 1, normal.y()}, {3 * v + 2, normal.z()}}, 0.0, ContactKind::PLANE,
                   std::max(0.0, -dist), {v, -1, -1, -1});
        }
    }
    rb.finish(qp, n);
    if (!rows) qp.contacts = ContactRows{};
    qp.meta = base_meta(family, p, seed);
    fill_fem_meta(qp.meta, fp, s.vertices, s.tets);
    if (rows) qp.meta["plane"] = {{"normal", {normal.x(), normal.y(), normal.z()}}, {"offset", 0.0}};
    return qp;
}

Qp make_box(const std::string& family, const nlohmann::json& p, std::uint64_t seed)
{
    const FemGridParams fp = fem_from(family, p);
    validate(fp, "synthetic family '" + family + "': params");
    const double fraction = p["fraction"].get<double>();
    if (!(fraction >= 0 && fraction <= 1)) bad_param(family, "fraction", "a value in [0, 1]", p["fraction"]);
    std::mt19937_64 rng(seed);
    const GridBody g = make_grid(fp.nx, fp.ny, fp.nz, fp.spacing, V3::Zero());
    const Assembled fem = assemble(g, fp);
    const long n = fem.A.rows();
    Vec target = flatten(g.rest);
    for (long i = 0; i < n; ++i) target[i] += uniform(rng, -0.1, 0.1) * fp.spacing;
    Qp qp;
    qp.A = fem.A;
    qp.b = qp.A * target;  // the unconstrained minimiser is `target`
    qp.x0 = target;
    const double spread = p["spread"].get<double>() * fp.spacing;
    RowBuilder rb;
    for (long i = 0; i < n; ++i) {
        if (uniform(rng, 0, 1) >= fraction) continue;
        const double sign = uniform(rng, 0, 1) < 0.5 ? 1.0 : -1.0;
        const double bound = target[i] + uniform(rng, -spread, spread);
        const double rhs = sign * bound;
        rb.add({{int(i), sign}}, rhs, ContactKind::OTHER, std::max(0.0, rhs - sign * target[i]), {i / 3, -1, -1, -1});
    }
    rb.finish(qp, n);
    qp.meta = base_meta(family, p, seed);
    fill_fem_meta(qp.meta, fp, g.vertices(), g.tets());
    return qp;
}

Eigen::Matrix3d random_rotation(std::mt19937_64& rng)
{
    // A uniformly random unit quaternion (normalised Gaussian 4-vector).
    std::normal_distribution<double> normal(0.0, 1.0);
    Eigen::Quaterniond q(normal(rng), normal(rng), normal(rng), normal(rng));
    q.normalize();
    return q.toRotationMatrix();
}

Qp make_coupled(const std::string& family, const nlohmann::json& p, std::uint64_t seed)
{
    const FemGridParams fp = fem_from(family, p);
    validate(fp, "synthetic family '" + family + "': params");
    const double scale = p["upper_scale"].get<double>();
    if (!(scale > 0 && scale < 1)) bad_param(family, "upper_scale", "a value in (0, 1)", p["upper_scale"]);
    const int upper_ny = p["upper_ny"].get<int>();
    if (upper_ny < 1) bad_param(family, "upper_ny", "an integer >= 1", p["upper_ny"]);
    if (double(fp.nx + 1) * (double(upper_ny) + 1) * (double(fp.nz) + 1) > MAX_GRID_VERTICES)
        bad_param(family, "upper_ny", "at most 1e6 vertices in the upper body", p["upper_ny"]);
    std::mt19937_64 rng(seed);
    const double s = fp.spacing;
    const double gap = p["gap"].get<double>();
    // Lower body [0, nx s] x [0, ny s] x [0, nz s]; the upper one (spacing scale * s) above it,
    // its footprint strictly inside the lower top face so that every bottom vertex projects onto it.
    GridBody lower = make_grid(fp.nx, fp.ny, fp.nz, s, V3::Zero());
    const double slack_x = (1 - scale) * fp.nx * s, slack_z = (1 - scale) * fp.nz * s;
    const V3 origin(uniform(rng, 0.1, 0.9) * slack_x, fp.ny * s + gap, uniform(rng, 0.1, 0.9) * slack_z);
    GridBody upper = make_grid(fp.nx, upper_ny, fp.nz, scale * s, origin);
    const int nv1 = lower.vertices(), nv2 = upper.vertices();

    // Rows from the rest configuration (before rotation): bottom vertex i of the upper body over
    // triangle (j, k, l) of the lower top face, the face split along the Kuhn diagonal.
    struct Row {
        int i;
        std::array<int, 3> tri;
        std::array<double, 3> w;
    };
    std::vector<Row> rows;
    for (int k = 0; k <= fp.nz; ++k)
        for (int i = 0; i <= fp.nx; ++i) {
            const int vi = upper.vertex(i, 0, k);
            const V3& x = upper.rest[vi];
            const double fx = x.x() / s, fz = x.z() / s;
            const int ci = std::min(fp.nx - 1, int(std::floor(fx))), ck = std::min(fp.nz - 1, int(std::floor(fz)));
            const double u = fx - ci, w = fz - ck;
            const int p00 = lower.vertex(ci, fp.ny, ck), p10 = lower.vertex(ci + 1, fp.ny, ck);
            const int p01 = lower.vertex(ci, fp.ny, ck + 1), p11 = lower.vertex(ci + 1, fp.ny, ck + 1);
            if (u >= w)
                rows.push_back({vi, {p00, p10, p11}, {1 - u, u - w, w}});
            else
                rows.push_back({vi, {p00, p01, p11}, {1 - w, w - u, u}});
        }

    // Rotate the whole scene (positions, velocities, gravity, normal) so that normals are generic.
    const Eigen::Matrix3d R = p["rotate"].get<bool>() ? random_rotation(rng) : Eigen::Matrix3d::Identity();
    for (auto& x : lower.rest) x = R * x;
    for (auto& x : upper.rest) x = R * x;
    const V3 normal = R * V3::UnitY();
    const V3 gravity = R * V3(0, -p["gravity"].get<double>(), 0);
    const double noise = p["noise"].get<double>();
    const double speed = p["speed"].get<double>();

    Scene sc;
    sc.fp = fp;
    const Assembled f1 = assemble(lower, fp);
    FemGridParams fp2 = fp;
    fp2.spacing = scale * s;
    const Assembled f2 = assemble(upper, fp2);
    sc.fem.A = block_diag(f1.A, f2.A);
    sc.fem.mass.resize(f1.mass.size() + f2.mass.size());
    sc.fem.mass << f1.mass, f2.mass;
    sc.rest.resize(3 * static_cast<Eigen::Index>(nv1 + nv2));
    sc.rest << flatten(lower.rest), flatten(upper.rest);
    sc.pred = sc.rest;
    sc.gravity = gravity;
    for (int v = 0; v < nv1 + nv2; ++v) {
        V3 vel = v >= nv1 ? V3(-speed * normal) : V3::Zero();
        for (int d = 0; d < 3; ++d) vel[d] += uniform(rng, -noise, noise);
        sc.pred.segment<3>(3 * static_cast<Eigen::Index>(v)) += fp.h * vel;
    }
    Qp qp;
    qp.A = sc.fem.A;
    qp.b = step_rhs(sc);
    qp.x0 = sc.pred;
    RowBuilder rb;
    for (const Row& r : rows) {
        const int vi = nv1 + r.i;  // upper body DOFs follow the lower body's
        std::vector<std::pair<int, double>> e;
        e.reserve(12);  // the vertex's 3 DOFs and the triangle's 9
        for (int d = 0; d < 3; ++d) e.push_back({3 * vi + d, normal[d]});
        for (int t = 0; t < 3; ++t)
            for (int d = 0; d < 3; ++d) e.push_back({3 * r.tri[t] + d, -r.w[t] * normal[d]});
        double gapv = normal.dot(V3(qp.x0.segment<3>(3 * static_cast<Eigen::Index>(vi))));
        for (int t = 0; t < 3; ++t)
            gapv -= r.w[t] * normal.dot(V3(qp.x0.segment<3>(3 * static_cast<Eigen::Index>(r.tri[t]))));
        rb.add(e, 0.0, ContactKind::INTER_BODY, std::max(0.0, -gapv), {vi, r.tri[0], r.tri[1], r.tri[2]});
    }
    rb.finish(qp, qp.A.rows());
    qp.meta = base_meta(family, p, seed);
    FemGridParams both = fp;
    fill_fem_meta(qp.meta, both, nv1 + nv2, lower.tets() + upper.tets());
    qp.meta["bodies"] = 2;
    return qp;
}

Qp make_random_spd(const std::string& family, const nlohmann::json& p, std::uint64_t seed)
{
    const long n = p["n"].get<long>(), m = p["m"].get<long>(), row_nnz = p["row_nnz"].get<long>();
    const double cond = p["condition"].get<double>();
    if (n < 1 || n > 3000) bad_param(family, "n", "an integer in [1, 3000] (A is dense)", p["n"]);
    if (m < 0 || m > MAX_ROWS) bad_param(family, "m", "an integer in [0, 1e7]", p["m"]);
    if (row_nnz < 1 || row_nnz > n) bad_param(family, "row_nnz", "an integer in [1, n]", p["row_nnz"]);
    if (!(cond >= 1)) bad_param(family, "condition", "a number >= 1", p["condition"]);
    if (!(p["length_scale"].get<double>() > 0)) bad_param(family, "length_scale", "> 0", p["length_scale"]);
    if (!(p["mass_scale"].get<double>() > 0)) bad_param(family, "mass_scale", "> 0", p["mass_scale"]);
    std::mt19937_64 rng(seed);
    std::normal_distribution<double> normal(0.0, 1.0);
    Eigen::MatrixXd G(n, n);
    for (long j = 0; j < n; ++j)
        for (long i = 0; i < n; ++i) G(i, j) = normal(rng);
    const Eigen::MatrixXd Q = Eigen::HouseholderQR<Eigen::MatrixXd>(G).householderQ();
    Vec eig(n);
    for (long i = 0; i < n; ++i) eig[i] = n == 1 ? 1.0 : std::pow(cond, double(i) / double(n - 1));
    Eigen::MatrixXd D = Q * eig.asDiagonal() * Q.transpose();
    D = 0.5 * (D + D.transpose()).eval();  // exactly symmetric
    Qp qp;
    qp.A = D.sparseView(0.0, 0.0);
    qp.A.makeCompressed();
    qp.b.resize(n);
    for (long i = 0; i < n; ++i) qp.b[i] = normal(rng);
    const Vec xu = Eigen::LLT<Eigen::MatrixXd>(D).solve(qp.b);
    qp.x0 = Vec::Zero(n);
    RowBuilder rb;
    std::vector<int> cols(n);
    for (long i = 0; i < n; ++i) cols[i] = int(i);
    for (long r = 0; r < m; ++r) {
        std::shuffle(cols.begin(), cols.end(), rng);
        std::vector<std::pair<int, double>> e;
        double jx = 0;
        for (long k = 0; k < row_nnz; ++k) {
            e.push_back({cols[k], normal(rng)});
            jx += e.back().second * xu[cols[k]];
        }
        // About half the rows cut off the unconstrained minimiser.
        rb.add(e, jx + uniform(rng, -1, 1) * (1 + std::abs(jx)) * 0.5, ContactKind::OTHER, 0.0, {-1, -1, -1, -1});
    }
    rb.finish(qp, n);
    qp.meta = base_meta(family, p, seed);
    qp.meta["condition"] = cond;
    apply_units(qp, p["length_scale"].get<double>(), p["mass_scale"].get<double>());
    return qp;
}

/// Rebuilds J (and c, contacts) from a list of rows of an existing QP in a new order, possibly
/// with repeats, scales and inserted zero rows (row index -1).
void remap_rows(Qp& qp, const std::vector<long>& order, const std::vector<double>& scale, double zero_c)
{
    RowBuilder rb;
    for (size_t t = 0; t < order.size(); ++t) {
        const long r = order[t];
        if (r < 0) {
            rb.add({}, zero_c, ContactKind::OTHER, 0.0, {-1, -1, -1, -1});
            continue;
        }
        std::vector<std::pair<int, double>> e;
        for (SpMat::InnerIterator it(qp.J, r); it; ++it) e.push_back({int(it.col()), scale[t] * it.value()});
        std::array<std::int64_t, 4> vtx;
        for (int k = 0; k < 4; ++k) vtx[k] = qp.contacts.vertex[4 * r + k];
        rb.add(e, scale[t] * qp.c[r], ContactKind(qp.contacts.kind[r]), qp.contacts.depth[r], vtx);
    }
    rb.finish(qp, qp.A.rows());
}

Qp make_variant(const std::string& family, const nlohmann::json& p, std::uint64_t seed)
{
    Qp qp = make_plane_like(family, p, seed, true);
    std::mt19937_64 rng(seed ^ 0x9e3779b97f4a7c15ULL);  // independent of the scene's stream
    const long m = qp.m();
    std::vector<long> order;
    std::vector<double> scale;
    double zero_c = 0.0;
    if (family == "duplicate-rows") {
        const double fraction = p["fraction"].get<double>();
        if (!(fraction >= 0 && fraction <= 1)) bad_param(family, "fraction", "a value in [0, 1]", p["fraction"]);
        for (long r = 0; r < m; ++r) {
            order.push_back(r);
            if (uniform(rng, 0, 1) < fraction) order.push_back(r);
        }
        scale.assign(order.size(), 1.0);
    } else if (family == "scaled-rows") {
        const double rs = p["row_scale"].get<double>();
        if (!(rs >= 1)) bad_param(family, "row_scale", "a number >= 1", p["row_scale"]);
        for (long r = 0; r < m; ++r) {
            order.push_back(r);
            scale.push_back(std::pow(rs, uniform(rng, -1, 1)));
        }
    } else if (family == "zero-rows") {
        const long count = p["count"].get<long>();
        zero_c = p["c"].get<double>();
        if (count < 0 || count > MAX_ROWS) bad_param(family, "count", "an integer in [0, 1e7]", p["count"]);
        if (!(zero_c <= 0)) bad_param(family, "c", "a number <= 0 (a zero row must be satisfiable)", p["c"]);
        for (long r = 0; r < m; ++r) order.push_back(r);
        for (long k = 0; k < count; ++k) {
            const long at = std::uniform_int_distribution<long>(0, long(order.size()))(rng);
            order.insert(order.begin() + at, -1);
        }
        scale.assign(order.size(), 1.0);
    } else {  // infeasible
        const long pairs = p["pairs"].get<long>();
        if (pairs < 1 || pairs > MAX_ROWS / 2) bad_param(family, "pairs", "an integer in [1, 5e6]", p["pairs"]);
        RowBuilder rb;
        // Copy the plane rows, then append the contradictory pairs.
        for (long r = 0; r < m; ++r) {
            std::vector<std::pair<int, double>> e;
            for (SpMat::InnerIterator it(qp.J, r); it; ++it) e.push_back({int(it.col()), it.value()});
            rb.add(e, qp.c[r], ContactKind(qp.contacts.kind[r]), qp.contacts.depth[r],
                   {qp.contacts.vertex[4 * r], -1, -1, -1});
        }
        const double L = p["length_scale"].get<double>();
        for (long k = 0; k < pairs; ++k) {
            const int dof = std::uniform_int_distribution<int>(0, int(qp.n()) - 1)(rng);
            // In the final units: x_i >= 1 and -x_i >= 0 (scaled back by L below).
            rb.add({{dof, 1.0}}, 1.0 * L, ContactKind::OTHER, 0.0, {dof / 3, -1, -1, -1});
            rb.add({{dof, -1.0}}, 0.0, ContactKind::OTHER, 0.0, {dof / 3, -1, -1, -1});
        }
        rb.finish(qp, qp.n());
        return qp;
    }
    remap_rows(qp, order, scale, zero_c * p["length_scale"].get<double>());
    return qp;
}

}  // namespace

namespace {

/// Extreme parameters (youngs 1e308, length_scale 1e-300) overflow to inf or NaN: refused here,
/// so that `generate` never writes a snapshot its own reader rejects.
void require_finite(const std::string& family, const Qp& qp)
{
    auto check = [&](const char* field, const double* v, Eigen::Index count) {
        for (Eigen::Index i = 0; i < count; ++i)
            if (!std::isfinite(v[i]))
                throw_input_error("synthetic family '" + family + "'", "params",
                                  std::string("the parameters give a non-finite value in ") + field + " (" +
                                      std::to_string(v[i]) + " at index " + std::to_string(long(i)) +
                                      "); choose less extreme values");
    };
    check("A", qp.A.valuePtr(), qp.A.nonZeros());
    check("b", qp.b.data(), qp.b.size());
    check("x0", qp.x0.data(), qp.x0.size());
    check("J", qp.J.valuePtr(), qp.J.nonZeros());
    check("c", qp.c.data(), qp.c.size());
    for (size_t r = 0; r < qp.contacts.depth.size(); ++r)
        if (!std::isfinite(qp.contacts.depth[r])) check("contact.depth", &qp.contacts.depth[r], 1);
}

}  // namespace

SpMat fem_like_matrix(const FemGridParams& p)
{
    validate(p, "fem_like_matrix");
    return assemble(make_grid(p.nx, p.ny, p.nz, p.spacing, V3::Zero()), p).A;
}

Qp make_synthetic(const std::string& family, const nlohmann::json& params, std::uint64_t seed)
{
    const auto it = families().find(family);
    if (it == families().end()) {
        std::string known;
        for (const auto& f : synthetic_families()) known += (known.empty() ? "" : ", ") + f;
        throw_input_error("synthetic", "family", "unknown family '" + family + "'; known: " + known);
    }
    const nlohmann::json p = effective_params(family, it->second, params);
    if (family == "random-spd") {  // applies its own units
        Qp qp = make_random_spd(family, p, seed);
        require_finite(family, qp);
        return qp;
    }
    // Built in one initialisation: Eigen 3.4's SparseMatrix has no move assignment.
    Qp qp = family == "unconstrained" ? make_plane_like(family, p, seed, false)
            : family == "plane"       ? make_plane_like(family, p, seed, true)
            : family == "box"         ? make_box(family, p, seed)
            : family == "coupled"     ? make_coupled(family, p, seed)
                                      : make_variant(family, p, seed);
    apply_units(qp, p["length_scale"].get<double>(), p["mass_scale"].get<double>());
    require_finite(family, qp);
    return qp;
}

std::vector<std::string> synthetic_families()
{
    std::vector<std::string> names;
    for (const auto& kv : families()) names.push_back(kv.first);
    return names;  // std::map keeps them sorted
}

std::string synthetic_family_help(const std::string& family)
{
    const auto it = families().find(family);
    if (it == families().end()) throw_input_error("synthetic", "family", "unknown family '" + family + "'");
    std::ostringstream out;
    out << family << ": " << it->second.summary << "\n";
    for (const auto& p : it->second.params) {
        std::string name = p.name;
        name.resize(std::max<size_t>(name.size(), 13), ' ');
        out << "  " << name << " = " << p.value.dump() << "  " << p.help << "\n";
    }
    return out.str();
}

}  // namespace cb
