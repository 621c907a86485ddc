#include "sim/collision/obstacles.hpp"

#include <algorithm>
#include <cmath>

namespace cb::sim {

Vec3 closest_point_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c, Eigen::Vector3d& w)
{
    // Voronoi-region walk (Ericson, Real-Time Collision Detection, Sec. 5.1.5).
    const Vec3 ab = b - a, ac = c - a, ap = p - a;
    const double d1 = ab.dot(ap), d2 = ac.dot(ap);
    if (d1 <= 0 && d2 <= 0) {
        w = {1, 0, 0};
        return a;
    }
    const Vec3 bp = p - b;
    const double d3 = ab.dot(bp), d4 = ac.dot(bp);
    if (d3 >= 0 && d4 <= d3) {
        w = {0, 1, 0};
        return b;
    }
    const double vc = d1 * d4 - d3 * d2;
    if (vc <= 0 && d1 >= 0 && d3 <= 0) {
        const double v = d1 / (d1 - d3);
        w = {1 - v, v, 0};
        return a + v * ab;
    }
    const Vec3 cp = p - c;
    const double d5 = ab.dot(cp), d6 = ac.dot(cp);
    if (d6 >= 0 && d5 <= d6) {
        w = {0, 0, 1};
        return c;
    }
    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0 && d2 >= 0 && d6 <= 0) {
        const double t = d2 / (d2 - d6);
        w = {1 - t, 0, t};
        return a + t * ac;
    }
    const double va = d3 * d6 - d5 * d4;
    if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
        const double t = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        w = {0, 1 - t, t};
        return b + t * (c - b);
    }
    const double denom = va + vb + vc;
    if (!(std::abs(denom) > 0)) {  // degenerate triangle: fall back to vertex a
        w = {1, 0, 0};
        return a;
    }
    const double v = vb / denom, t = vc / denom;
    w = {1 - v - t, v, t};
    return a + ab * v + ac * t;
}

namespace {

SurfaceMesh quad(const Vec3& c, const Vec3& u, const Vec3& v)
{
    SurfaceMesh s;
    s.positions.resize(4, 3);
    s.positions.row(0) = (c - u - v).transpose();
    s.positions.row(1) = (c + u - v).transpose();
    s.positions.row(2) = (c + u + v).transpose();
    s.positions.row(3) = (c - u + v).transpose();
    s.faces.resize(2, 3);
    s.faces << 0, 1, 2, 0, 2, 3;
    return s;
}

void any_perpendicular(const Vec3& n, Vec3& u, Vec3& v)
{
    u = (std::abs(n.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY()).cross(n).normalized();
    v = n.cross(u);
}

class Plane final : public Obstacle {
public:
    Plane(const Vec3& n, const Vec3& p) : m_n(n.normalized()), m_p(p) {}
    std::string type() const override { return "plane"; }
    ContactKind kind() const override { return ContactKind::PLANE; }
    bool query(const Vec3& x, double margin, ObstacleHit& hit) const override
    {
        const double d = m_n.dot(x - m_p);
        if (d >= margin) return false;
        hit = {d, m_n, x - d * m_n};
        return true;
    }
    SurfaceMesh surface(const Vec3& center, double extent) const override
    {
        Vec3 u, v;
        any_perpendicular(m_n, u, v);
        const Vec3 c = center - m_n * m_n.dot(center - m_p);
        // Winding chosen so the quad's normal is +n.
        SurfaceMesh s = quad(c, 0.5 * extent * u, 0.5 * extent * v);
        return s;
    }

private:
    Vec3 m_n, m_p;
};

class Sphere final : public Obstacle {
public:
    Sphere(const Vec3& c, double r) : m_c(c), m_r(r) {}
    std::string type() const override { return "sphere"; }
    bool query(const Vec3& x, double margin, ObstacleHit& hit) const override
    {
        const Vec3 d = x - m_c;
        const double len = d.norm();
        const double dist = len - m_r;
        if (dist >= margin) return false;
        const Vec3 n = len > 0 ? Vec3(d / len) : Vec3::UnitY();  // centre: any direction
        hit = {dist, n, m_c + m_r * n};
        return true;
    }
    SurfaceMesh surface(const Vec3&, double) const override
    {
        // UV sphere, 12 x 24.
        const int nu = 12, nv = 24;
        SurfaceMesh s;
        s.positions.resize((nu + 1) * nv, 3);
        for (int i = 0; i <= nu; ++i)
            for (int j = 0; j < nv; ++j) {
                const double th = M_PI * i / nu, ph = 2 * M_PI * j / nv;
                s.positions.row(i * nv + j) =
                    (m_c + m_r * Vec3(std::sin(th) * std::cos(ph), std::cos(th), std::sin(th) * std::sin(ph)))
                        .transpose();
            }
        std::vector<std::array<int, 3>> f;
        for (int i = 0; i < nu; ++i)
            for (int j = 0; j < nv; ++j) {
                const int a = i * nv + j, b = i * nv + (j + 1) % nv, c = a + nv, d = b + nv;
                f.push_back({a, b, d});
                f.push_back({a, d, c});
            }
        s.faces.resize(static_cast<Eigen::Index>(f.size()), 3);
        for (size_t k = 0; k < f.size(); ++k) s.faces.row(static_cast<Eigen::Index>(k)) << f[k][0], f[k][1], f[k][2];
        return s;
    }

private:
    Vec3 m_c;
    double m_r;
};

class Box final : public Obstacle {
public:
    Box(const Vec3& lo, const Vec3& hi) : m_lo(lo.cwiseMin(hi)), m_hi(lo.cwiseMax(hi)) {}
    std::string type() const override { return "box"; }
    bool query(const Vec3& x, double margin, ObstacleHit& hit) const override
    {
        const Vec3 q = x.cwiseMax(m_lo).cwiseMin(m_hi);
        const Vec3 d = x - q;
        const double out = d.norm();
        if (out > 0) {
            if (out >= margin) return false;
            hit = {out, d / out, q};
            return true;
        }
        // Inside: the nearest face.
        double best = 1e300;
        int axis = 0, side = 0;
        for (int k = 0; k < 3; ++k) {
            if (x[k] - m_lo[k] < best) {
                best = x[k] - m_lo[k];
                axis = k;
                side = -1;
            }
            if (m_hi[k] - x[k] < best) {
                best = m_hi[k] - x[k];
                axis = k;
                side = 1;
            }
        }
        Vec3 n = Vec3::Zero();
        n[axis] = side;
        Vec3 p = x;
        p[axis] = side > 0 ? m_hi[axis] : m_lo[axis];
        hit = {-best, n, p};
        return true;
    }
    SurfaceMesh surface(const Vec3&, double) const override
    {
        TetMesh box = make_box_mesh(1, 1, 1, m_hi - m_lo, m_lo);
        SurfaceMesh s;
        s.positions = box.positions;
        s.faces = boundary_faces(box);
        return s;
    }

private:
    Vec3 m_lo, m_hi;
};

class Cylinder final : public Obstacle {
public:
    Cylinder(const Vec3& c, const Vec3& axis, double r, double h) : m_c(c), m_a(axis.normalized()), m_r(r), m_h(h) {}
    std::string type() const override { return "cylinder"; }
    bool query(const Vec3& x, double margin, ObstacleHit& hit) const override
    {
        const Vec3 d = x - m_c;
        const double t = m_a.dot(d);
        Vec3 radial = d - t * m_a;
        const double rho = radial.norm();
        Vec3 er;
        if (rho > 1e-300)
            er = radial / rho;
        else {
            Vec3 v;
            any_perpendicular(m_a, er, v);
        }
        const double dr = rho - m_r, da = std::abs(t) - 0.5 * m_h;
        const double sgn = t >= 0 ? 1.0 : -1.0;
        if (dr <= 0 && da <= 0) {  // inside: nearest of the mantle and the caps
            if (dr >= da)
                hit = {dr, er, m_c + t * m_a + m_r * er};
            else
                hit = {da, sgn * m_a, m_c + sgn * 0.5 * m_h * m_a + radial};
            return true;
        }
        const Vec3 q = m_c + std::clamp(t, -0.5 * m_h, 0.5 * m_h) * m_a + std::min(rho, m_r) * er;
        const Vec3 e = x - q;
        const double dist = e.norm();
        if (dist >= margin) return false;
        hit = {dist, dist > 0 ? Vec3(e / dist) : er, q};
        return true;
    }
    SurfaceMesh surface(const Vec3&, double) const override
    {
        const int nv = 32;
        Vec3 u, v;
        any_perpendicular(m_a, u, v);
        SurfaceMesh s;
        s.positions.resize(2 * nv + 2, 3);
        for (int j = 0; j < nv; ++j) {
            const double ph = 2 * M_PI * j / nv;
            const Vec3 e = std::cos(ph) * u + std::sin(ph) * v;
            s.positions.row(j) = (m_c - 0.5 * m_h * m_a + m_r * e).transpose();
            s.positions.row(nv + j) = (m_c + 0.5 * m_h * m_a + m_r * e).transpose();
        }
        s.positions.row(2 * nv) = (m_c - 0.5 * m_h * m_a).transpose();
        s.positions.row(2 * nv + 1) = (m_c + 0.5 * m_h * m_a).transpose();
        s.faces.resize(4 * nv, 3);
        for (int j = 0; j < nv; ++j) {
            const int k = (j + 1) % nv;
            s.faces.row(4 * j) << j, k, nv + k;
            s.faces.row(4 * j + 1) << j, nv + k, nv + j;
            s.faces.row(4 * j + 2) << 2 * nv, k, j;
            s.faces.row(4 * j + 3) << 2 * nv + 1, nv + j, nv + k;
        }
        return s;
    }

private:
    Vec3 m_c, m_a;
    double m_r, m_h;
};

class MeshObstacle final : public Obstacle {
public:
    MeshObstacle(SurfaceMesh mesh, double thickness) : m_mesh(std::move(mesh)), m_thickness(thickness)
    {
        std::vector<Box3> boxes(static_cast<size_t>(m_mesh.faces.rows()));
        m_normals.resize(boxes.size());
        for (size_t f = 0; f < boxes.size(); ++f) {
            const Vec3 a = vertex(static_cast<int>(f), 0), b = vertex(static_cast<int>(f), 1),
                       c = vertex(static_cast<int>(f), 2);
            boxes[f].extend(a);
            boxes[f].extend(b);
            boxes[f].extend(c);
            const Vec3 n = (b - a).cross(c - a);
            m_normals[f] = n.norm() > 0 ? Vec3(n.normalized()) : Vec3::UnitY();
        }
        m_bvh.build(boxes);
    }
    std::string type() const override { return "mesh"; }
    bool query(const Vec3& x, double margin, ObstacleHit& hit) const override
    {
        const double reach = std::max(margin, m_thickness);
        if (m_bvh.empty() || m_bvh.bounds().squaredExteriorDistance(x) > reach * reach) return false;
        Vec3 best_q;
        Eigen::Vector3d w;
        double d2 = 0;
        const int f = m_bvh.nearest(
            x,
            [&](int face) {
                const Vec3 q = closest_point_triangle(x, vertex(face, 0), vertex(face, 1), vertex(face, 2), w);
                return (x - q).squaredNorm();
            },
            &d2);
        if (f < 0 || d2 > reach * reach) return false;
        best_q = closest_point_triangle(x, vertex(f, 0), vertex(f, 1), vertex(f, 2), w);
        const Vec3& n = m_normals[static_cast<size_t>(f)];
        const double dist = n.dot(x - best_q) >= 0 ? std::sqrt(d2) : -std::sqrt(d2);
        if (dist >= margin || dist < -m_thickness) return false;
        hit = {dist, n, best_q};
        return true;
    }
    SurfaceMesh surface(const Vec3&, double) const override { return m_mesh; }

private:
    Vec3 vertex(int f, int k) const { return m_mesh.positions.row(m_mesh.faces(f, k)).transpose(); }
    SurfaceMesh m_mesh;
    double m_thickness;
    std::vector<Vec3> m_normals;
    Bvh m_bvh;
};

}  // namespace

std::unique_ptr<Obstacle> make_plane(const Vec3& normal, const Vec3& point)
{
    return std::make_unique<Plane>(normal, point);
}
std::unique_ptr<Obstacle> make_sphere(const Vec3& center, double radius)
{
    return std::make_unique<Sphere>(center, radius);
}
std::unique_ptr<Obstacle> make_box(const Vec3& lo, const Vec3& hi) { return std::make_unique<Box>(lo, hi); }
std::unique_ptr<Obstacle> make_cylinder(const Vec3& center, const Vec3& axis, double radius, double height)
{
    return std::make_unique<Cylinder>(center, axis, radius, height);
}
std::unique_ptr<Obstacle> make_mesh_obstacle(SurfaceMesh mesh, double thickness)
{
    return std::make_unique<MeshObstacle>(std::move(mesh), thickness);
}

}  // namespace cb::sim
