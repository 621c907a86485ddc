#include "sim/collision/dcd.hpp"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>

namespace cb::sim {

Eigen::Vector4d tet_barycentric(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d)
{
    Eigen::Matrix3d T;
    T.col(0) = b - a;
    T.col(1) = c - a;
    T.col(2) = d - a;
    const double det = T.determinant();
    Eigen::Vector4d w;
    if (!(std::abs(det) > 1e-300)) {  // collapsed tet: report "outside"
        w << -1, -1, -1, -1;
        return w;
    }
    const Vec3 l = T.inverse() * (p - a);
    w << 1 - l.sum(), l.x(), l.y(), l.z();
    return w;
}

CollisionDetector::CollisionDetector(std::vector<CollisionBody> bodies, std::vector<const Obstacle*> obstacles,
                                     DetectionSettings settings)
    : m_bodies(std::move(bodies)), m_obstacles(std::move(obstacles)), m_settings(settings)
{
}

namespace {
Vec3 pos(const Vec& x, int i) { return x.segment<3>(3 * i); }

/// Per-body acceleration structures built lazily at one configuration.
struct BodyTrees {
    bool built = false;
    Bvh tets, faces;
    std::vector<std::vector<int>> vertex_faces;  ///< only for self-contact exclusion
};
}  // namespace

std::vector<ContactRow> CollisionDetector::detect(const Vec& x, DetectionStats* stats) const
{
    std::vector<ContactRow> rows;
    DetectionStats st;
    // Obstacles.
    for (size_t o = 0; o < m_obstacles.size(); ++o) {
        const Obstacle& ob = *m_obstacles[o];
        for (const CollisionBody& body : m_bodies)
            for (int v : body.surface_vertices) {
                ObstacleHit hit;
                if (!ob.query(pos(x, v), m_settings.margin, hit)) continue;
                ContactRow r;
                r.kind = ob.kind();
                r.depth = std::max(0.0, -hit.distance);
                r.vertex[0] = v;
                r.weight[0] = 1.0;
                r.normal = hit.normal;
                r.c = hit.normal.dot(hit.point);
                r.other = static_cast<int>(o);
                rows.push_back(r);
                ++st.obstacle_rows;
            }
    }
    const bool inter = m_settings.inter_body && m_bodies.size() >= 2;
    if (inter || m_settings.self_contact) {
        const size_t nb = m_bodies.size();
        std::vector<Box3> bounds(nb);
        for (size_t b = 0; b < nb; ++b)
            for (int v : m_bodies[b].surface_vertices) bounds[b].extend(pos(x, v));
        std::vector<BodyTrees> trees(nb);
        auto build = [&](size_t b) {
            BodyTrees& t = trees[b];
            if (t.built) return;
            const CollisionBody& body = m_bodies[b];
            std::vector<Box3> boxes(static_cast<size_t>(body.tets.rows()));
            for (Eigen::Index k = 0; k < body.tets.rows(); ++k)
                for (int a = 0; a < 4; ++a) boxes[static_cast<size_t>(k)].extend(pos(x, body.tets(k, a)));
            t.tets.build(boxes);
            boxes.assign(static_cast<size_t>(body.faces.rows()), Box3());
            for (Eigen::Index k = 0; k < body.faces.rows(); ++k)
                for (int a = 0; a < 3; ++a) boxes[static_cast<size_t>(k)].extend(pos(x, body.faces(k, a)));
            t.faces.build(boxes);
            t.built = true;
        };
        for (size_t a = 0; a < nb; ++a) {
            const CollisionBody& A = m_bodies[a];
            for (int v : A.surface_vertices) {
                const Vec3 p = pos(x, v);
                for (size_t b = 0; b < nb; ++b) {
                    const bool self = a == b;
                    if (self ? !m_settings.self_contact : !inter) continue;
                    if (!bounds[b].contains(p)) continue;
                    build(b);
                    const CollisionBody& B = m_bodies[b];
                    bool inside = false;
                    trees[b].tets.query_point(p, [&](int t) {
                        if (inside) return;
                        ++st.tet_candidates;
                        if (self)
                            for (int k = 0; k < 4; ++k)
                                if (B.tets(t, k) == v) return;
                        const Eigen::Vector4d w = tet_barycentric(p, pos(x, B.tets(t, 0)), pos(x, B.tets(t, 1)),
                                                                  pos(x, B.tets(t, 2)), pos(x, B.tets(t, 3)));
                        // Self-contact needs a strictly interior point (the own surface touches it).
                        const double tol = self ? -1e-6 : m_settings.inside_tolerance;
                        if (w.minCoeff() >= -tol) inside = true;
                    });
                    if (!inside) continue;
                    Eigen::Vector3d wbest;
                    double d2 = 0;
                    const int f = trees[b].faces.nearest(
                        p,
                        [&](int face) {
                            if (self && (B.faces(face, 0) == v || B.faces(face, 1) == v || B.faces(face, 2) == v))
                                return 1e300;
                            Eigen::Vector3d w;
                            const Vec3 q = closest_point_triangle(p, pos(x, B.faces(face, 0)), pos(x, B.faces(face, 1)),
                                                                  pos(x, B.faces(face, 2)), w);
                            return (p - q).squaredNorm();
                        },
                        &d2);
                    if (f < 0 || d2 >= 1e300) continue;
                    const Vec3 xa = pos(x, B.faces(f, 0)), xb = pos(x, B.faces(f, 1)), xc = pos(x, B.faces(f, 2));
                    closest_point_triangle(p, xa, xb, xc, wbest);
                    const Vec3 nrm = (xb - xa).cross(xc - xa);
                    if (!(nrm.norm() > 0)) continue;  // collapsed triangle: no usable normal
                    ContactRow r;
                    r.kind = self ? ContactKind::SELF : ContactKind::INTER_BODY;
                    r.depth = std::sqrt(d2);
                    r.normal = nrm.normalized();
                    r.vertex[0] = v;
                    r.weight[0] = 1.0;
                    for (int k = 0; k < 3; ++k) {
                        r.vertex[k + 1] = B.faces(f, k);
                        r.weight[k + 1] = -wbest[k];
                    }
                    r.c = 0.0;
                    r.other = static_cast<int>(b);
                    rows.push_back(r);
                    ++(self ? st.self_rows : st.inter_body_rows);
                }
            }
        }
    }
    if (stats) *stats = st;
    return rows;
}

void assemble_constraints(const std::vector<ContactRow>& rows, Eigen::Index n, SpMat& J, Vec& c, ContactRows& meta)
{
    const Eigen::Index m = static_cast<Eigen::Index>(rows.size());
    std::vector<Triplet> trip;
    trip.reserve(rows.size() * 12);
    c.resize(m);
    meta = ContactRows();
    meta.kind.reserve(rows.size());
    meta.depth.reserve(rows.size());
    meta.vertex.reserve(rows.size() * 4);
    for (Eigen::Index i = 0; i < m; ++i) {
        const ContactRow& r = rows[static_cast<size_t>(i)];
        for (int k = 0; k < 4; ++k) {
            if (r.vertex[k] < 0) continue;
            // Weights of exactly 0 (closest point on an edge/vertex) still get entries: a row
            // of eq. 8 always has 12 structural nonzeros, so the row's sparsity is the kind's.
            for (int d = 0; d < 3; ++d)
                trip.emplace_back(static_cast<int>(i), 3 * r.vertex[k] + d, r.weight[k] * r.normal[d]);
        }
        c[i] = r.c;
        meta.kind.push_back(static_cast<std::int64_t>(r.kind));
        meta.depth.push_back(r.depth);
        for (int k = 0; k < 4; ++k) meta.vertex.push_back(r.vertex[k]);
    }
    J.resize(m, n);
    J.setFromTriplets(trip.begin(), trip.end());
}

}  // namespace cb::sim
