#include "sim/tetrahedralize.hpp"

#include "sim/collision/bvh.hpp"

#include <cmath>
#include <memory>

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
    TetMesh grid = make_box_mesh(dims[0], dims[1], dims[2], Vec3::Constant(cell), origin);
    const InsideTest test(surface);
    std::vector<int> keep;
    for (Eigen::Index t = 0; t < grid.tets.rows(); ++t) {
        Vec3 c = Vec3::Zero();
        for (int k = 0; k < 4; ++k) c += grid.positions.row(grid.tets(t, k)).transpose();
        if (test.inside(c / 4.0)) keep.push_back(static_cast<int>(t));
    }
    if (keep.empty())
        throw_input_error(where, "resolution",
                          "no tet of the " + std::to_string(options.resolution) +
                              "-cell grid lies inside the surface (is it closed?)");
    std::vector<int> remap(static_cast<size_t>(grid.positions.rows()), -1);
    TetMesh out;
    out.tets.resize(static_cast<Eigen::Index>(keep.size()), 4);
    int nv = 0;
    for (size_t i = 0; i < keep.size(); ++i)
        for (int k = 0; k < 4; ++k) {
            int& r = remap[static_cast<size_t>(grid.tets(keep[i], k))];
            if (r < 0) r = nv++;
            out.tets(static_cast<Eigen::Index>(i), k) = r;
        }
    out.positions.resize(nv, 3);
    for (size_t v = 0; v < remap.size(); ++v)
        if (remap[v] >= 0) out.positions.row(remap[v]) = grid.positions.row(static_cast<Eigen::Index>(v));
    return out;
}

}  // namespace cb::sim
