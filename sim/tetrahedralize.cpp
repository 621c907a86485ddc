#include "sim/tetrahedralize.hpp"

#include "sim/collision/bvh.hpp"

#include <array>
#include <cmath>
#include <cstdint>
#include <memory>
#include <unordered_map>
#include <vector>

namespace cb::sim {

struct InsideTest::Impl {
    Bvh bvh;
    double xmax = 0;
};

InsideTest::InsideTest(const SurfaceMesh& surface) : m_surface(surface), m_impl(std::make_shared<Impl>())
{
    std::vector<Box3> boxes(static_cast<size_t>(surface.faces.rows()));
    for (Eigen::Index f = 0; f < surface.faces.rows(); ++f)
        for (int k = 0; k < 3; ++k)
            boxes[static_cast<size_t>(f)].extend(Vec3(surface.positions.row(surface.faces(f, k)).transpose()));
    m_impl->bvh.build(boxes);
    m_impl->xmax = surface.positions.col(0).maxCoeff() + 1.0;
}

bool InsideTest::inside(const Vec3& p) const
{
    // Count crossings of the ray p + t e_x (t > 0): strict 2D point-in-triangle in the yz plane.
    // Callers pass points off the lattice of vertex coordinates, so ties have measure zero.
    Box3 ray(p, Vec3(m_impl->xmax, p.y(), p.z()));
    int crossings = 0;
    m_impl->bvh.query_box(ray, [&](int f) {
        const Vec3 a = m_surface.positions.row(m_surface.faces(f, 0)).transpose();
        const Vec3 b = m_surface.positions.row(m_surface.faces(f, 1)).transpose();
        const Vec3 c = m_surface.positions.row(m_surface.faces(f, 2)).transpose();
        const double det = (b.y() - a.y()) * (c.z() - a.z()) - (c.y() - a.y()) * (b.z() - a.z());
        if (det == 0) return;
        const double u = ((p.y() - a.y()) * (c.z() - a.z()) - (c.y() - a.y()) * (p.z() - a.z())) / det;
        const double v = ((b.y() - a.y()) * (p.z() - a.z()) - (p.y() - a.y()) * (b.z() - a.z())) / det;
        if (u <= 0 || v <= 0 || u + v >= 1) return;
        const double x = a.x() + u * (b.x() - a.x()) + v * (c.x() - a.x());
        if (x > p.x()) ++crossings;
    });
    return crossings % 2 == 1;
}

TetMesh tetrahedralize(const SurfaceMesh& surface, const TetrahedralizeOptions& options, const std::string& where)
{
    if (options.resolution < 1)
        throw_input_error(where, "resolution", "must be >= 1, got " + std::to_string(options.resolution));
    Vec3 lo, hi;
    bounding_box(surface.positions, lo, hi);
    const double cell = (hi - lo).maxCoeff() / options.resolution;
    if (!(cell > 0)) throw_input_error(where, "", "surface has an empty bounding box");
    int dims[3];
    for (int k = 0; k < 3; ++k) dims[k] = std::max(1, static_cast<int>(std::ceil((hi[k] - lo[k]) / cell - 1e-9)));
    // Centre the grid on the box, and shift it by an irrational fraction of a cell so that tet
    // centroids never sit exactly on the surface's (often axis-aligned) facets.
    Vec3 origin;
    for (int k = 0; k < 3; ++k)
        origin[k] = 0.5 * (lo[k] + hi[k]) - 0.5 * dims[k] * cell + cell * 1e-3 * std::sqrt(2.0 + k);
    // The grid is visited cell by cell, never built whole: memory follows the tets kept inside
    // the surface (resolution 512 once built 805M grid tets before any limit was checked).
    const InsideTest test(surface);
    const std::int64_t vx = dims[0] + 1, vy = dims[1] + 1;
    auto grid_id = [&](const int c[3]) { return (std::int64_t(c[2]) * vy + c[1]) * vx + c[0]; };
    // Kuhn subdivision, as make_box_mesh: one tet per permutation of the axes.
    static const int perms[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
    // Calls on_inside(c) for each grid tet whose centroid is inside, its corners c in grid
    // coordinates and in make_box_mesh's orientation (so that the kept mesh, vertex order and
    // numbering, is the one the whole grid gave); stops when on_inside returns false.
    auto visit_inside = [&](auto&& on_inside) {
        for (int k = 0; k < dims[2]; ++k)
            for (int j = 0; j < dims[1]; ++j)
                for (int i = 0; i < dims[0]; ++i)
                    for (const auto& p : perms) {
                        int c[4][3];
                        c[0][0] = i, c[0][1] = j, c[0][2] = k;
                        for (int s = 0; s < 3; ++s) {
                            for (int a = 0; a < 3; ++a) c[s + 1][a] = c[s][a];
                            ++c[s + 1][p[s]];
                        }
                        Vec3 x[4];
                        for (int v = 0; v < 4; ++v) x[v] = origin + cell * Vec3(c[v][0], c[v][1], c[v][2]);
                        if (signed_volume(x[0], x[1], x[2], x[3]) < 0) {
                            std::swap(x[2], x[3]);
                            for (int a = 0; a < 3; ++a) std::swap(c[2][a], c[3][a]);
                        }
                        Vec3 centroid = Vec3::Zero();
                        for (const auto& v : x) centroid += v;
                        if (test.inside(centroid / 4.0) && !on_inside(c)) return;
                    }
    };
    // A grid of more tets than the limit may keep more than the limit: counted first, storing
    // nothing, so that a refusal costs no memory (resolution 512 on a tetrahedron).
    const double grid_tets = 6.0 * dims[0] * double(dims[1]) * double(dims[2]);
    if (grid_tets > double(options.max_tets)) {
        long inside = 0;
        visit_inside([&](const int(&)[4][3]) { return ++inside <= options.max_tets; });
        if (inside > options.max_tets)
            throw_input_error(where, "resolution",
                              std::to_string(options.resolution) + " puts more than " +
                                  std::to_string(options.max_tets) +
                                  " tets inside the surface (the limit); use a lower resolution");
    }
    std::unordered_map<std::int64_t, int> remap;
    std::vector<std::array<int, 3>> corners;  // grid coordinates of the kept vertices
    std::vector<std::array<int, 4>> tets;
    visit_inside([&](const int(&c)[4][3]) {
        std::array<int, 4> tet{};
        for (int v = 0; v < 4; ++v) {
            const auto [at, fresh] = remap.emplace(grid_id(c[v]), int(corners.size()));
            if (fresh) corners.push_back({c[v][0], c[v][1], c[v][2]});
            tet[size_t(v)] = at->second;
        }
        tets.push_back(tet);
        return true;
    });
    if (tets.empty())
        throw_input_error(where, "resolution",
                          "no tet of the " + std::to_string(options.resolution) +
                              "-cell grid lies inside the surface (is it closed?)");
    TetMesh out;
    out.tets.resize(static_cast<Eigen::Index>(tets.size()), 4);
    for (size_t t = 0; t < tets.size(); ++t)
        for (int v = 0; v < 4; ++v) out.tets(static_cast<Eigen::Index>(t), v) = tets[t][size_t(v)];
    out.positions.resize(static_cast<Eigen::Index>(corners.size()), 3);
    for (size_t v = 0; v < corners.size(); ++v)
        out.positions.row(static_cast<Eigen::Index>(v)) =
            (origin + cell * Vec3(corners[v][0], corners[v][1], corners[v][2])).transpose();
    orient_tets(out, where);
    return out;
}

}  // namespace cb::sim
