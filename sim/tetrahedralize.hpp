#pragma once
/// Our own tetrahedraliser for closed surfaces (no copyleft mesher is linked): a regular grid
/// of cubes, 6 Kuhn tets each, covering the surface's bounding box; a tet is kept when its
/// centroid is inside the surface (ray parity along +x, candidates from a BVH of the
/// triangles). The result is a staircase approximation at the requested resolution;
/// mesh_quality() reports its (grid-bounded: >= 45 degree) dihedral angles.
#include "sim/tet_mesh.hpp"

#include <memory>

namespace cb::sim {

struct TetrahedralizeOptions {
    int resolution = 16;      ///< grid cells along the longest bounding-box axis (>= 1)
    long max_tets = 6000000;  ///< more tets inside the surface: InputError (memory follows the kept tets)
};

/// Throws InputError(`where`) when the surface encloses no tet at this resolution.
TetMesh tetrahedralize(const SurfaceMesh& surface, const TetrahedralizeOptions& options, const std::string& where);

/// Ray-parity inside test of p against a closed surface (exposed for tests).
class InsideTest {
public:
    explicit InsideTest(const SurfaceMesh& surface);
    bool inside(const Vec3& p) const;

private:
    const SurfaceMesh& m_surface;
    struct Impl;
    std::shared_ptr<Impl> m_impl;
};

}  // namespace cb::sim
