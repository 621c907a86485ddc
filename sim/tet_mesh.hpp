#pragma once
/// Tetrahedral and triangle surface meshes of the simulator, and small geometric helpers.
#include "solvers/core/types.hpp"

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>
#include <vector>

namespace cb::sim {

using Vec3 = Eigen::Vector3d;
using Positions = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;  ///< #V by 3
using Tets = Eigen::Matrix<int, Eigen::Dynamic, 4, Eigen::RowMajor>;          ///< #T by 4, 0-based
using Faces = Eigen::Matrix<int, Eigen::Dynamic, 3, Eigen::RowMajor>;         ///< #F by 3, 0-based

/// A closed triangle surface (obstacles, inputs of the tetrahedraliser, exported frames).
struct SurfaceMesh {
    Positions positions;
    Faces faces;  ///< counter-clockwise seen from outside (outward normals by the right-hand rule)
};

/// A tetrahedral mesh: rest positions and tets with positive orientation
/// (det[x1-x0, x2-x0, x3-x0] > 0).
struct TetMesh {
    Positions positions;
    Tets tets;
    long vertices() const { return static_cast<long>(positions.rows()); }
    long tet_count() const { return static_cast<long>(tets.rows()); }
};

/// Signed volume of tet (a, b, c, d): det[b-a, c-a, d-a] / 6.
double signed_volume(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d);

/// Total (signed) volume of the mesh's tets.
double mesh_volume(const TetMesh& mesh);

/// Swaps two vertices of every negatively oriented tet. Throws InputError(`where`) naming the
/// first tet whose volume is (numerically) zero or whose vertex ids are out of range/repeated.
void orient_tets(TetMesh& mesh, const std::string& where);

/// Boundary faces (faces of exactly one tet), oriented outward.
Faces boundary_faces(const TetMesh& mesh);

/// Sorted unique vertex ids of the boundary faces.
std::vector<int> boundary_vertices(const Faces& faces, long vertex_count);

/// Axis-aligned bounding box of positions.
void bounding_box(const Positions& p, Vec3& lo, Vec3& hi);

/// Rotation from Euler angles in degrees: R = Rz(z) * Ry(y) * Rx(x) (x applied first).
Eigen::Matrix3d rotation_from_euler_deg(const Vec3& degrees);

/// x <- R (scale * x) + translation, for every row.
void transform_positions(Positions& p, double scale, const Eigen::Matrix3d& R, const Vec3& translation);

/// Procedural box of nx*ny*nz cubes, 6 tets per cube (Kuhn subdivision), from `lo` with cube
/// edge lengths `cell`. The paper's long cube is 16 x 16 x 32 cubes: 9537 vertices, 49152 tets.
TetMesh make_box_mesh(int nx, int ny, int nz, const Vec3& cell, const Vec3& lo = Vec3::Zero());

/// Mesh quality: min/max dihedral angle (degrees) and the volume ratio
/// (min over tets of 6 sqrt(2) V / l_rms^3, 1 for a regular tet).
struct MeshQuality {
    double min_dihedral_deg = 0, max_dihedral_deg = 0;
    double min_volume_ratio = 0, mean_volume_ratio = 0;
    double min_volume = 0, max_volume = 0;
    std::string to_string() const;
};
MeshQuality mesh_quality(const TetMesh& mesh);

}  // namespace cb::sim
