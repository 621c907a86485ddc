#pragma once
/// Static obstacles: plane, sphere, axis-aligned box, capped cylinder, triangle mesh.
/// A vertex closer than the detection margin (or inside) gets a tangent-plane row
/// n'x_i >= n'q (q the closest surface point, n the outward normal there): 3 nonzeros.
/// Ref: Li et al. 2015, Sec. 3.2 (the obstacle case of eq. 8: the triangle is fixed).
#include "sim/collision/bvh.hpp"
#include "sim/tet_mesh.hpp"
#include "solvers/core/qp.hpp"

#include <memory>
#include <string>

namespace cb::sim {

/// Closest point on triangle (a, b, c) to p, with barycentric weights w (q = w0 a + w1 b + w2 c).
Vec3 closest_point_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c, Eigen::Vector3d& w);

/// Where a point is relative to an obstacle surface.
struct ObstacleHit {
    double distance = 0;  ///< signed: < 0 inside the obstacle
    Vec3 normal;          ///< unit outward normal at the closest point
    Vec3 point;           ///< closest point on the surface
};

class Obstacle {
public:
    virtual ~Obstacle() = default;
    virtual std::string type() const = 0;
    /// Row kind: PLANE for planes, OBSTACLE otherwise (the authors' decoupling order).
    virtual ContactKind kind() const { return ContactKind::OBSTACLE; }
    /// True (and `hit` filled) when p is inside or within `margin` of the surface.
    virtual bool query(const Vec3& p, double margin, ObstacleHit& hit) const = 0;
    /// A triangle surface for pictures (planes: a square of side `extent` around `center`).
    virtual SurfaceMesh surface(const Vec3& center, double extent) const = 0;
};

std::unique_ptr<Obstacle> make_plane(const Vec3& normal, const Vec3& point);
std::unique_ptr<Obstacle> make_sphere(const Vec3& center, double radius);
std::unique_ptr<Obstacle> make_box(const Vec3& lo, const Vec3& hi);
/// Capped cylinder: `center` is the middle of the axis, `height` the full length.
std::unique_ptr<Obstacle> make_cylinder(const Vec3& center, const Vec3& axis, double radius, double height);
/// A triangle mesh; inside/outside from the normal of the closest triangle (works for closed
/// meshes and for consistently oriented open shells such as a cup). `thickness` bounds how deep
/// below the surface a point still counts as penetrating (beyond it the point is ignored).
std::unique_ptr<Obstacle> make_mesh_obstacle(SurfaceMesh mesh, double thickness);

}  // namespace cb::sim
