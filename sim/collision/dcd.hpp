#pragma once
/// Discrete collision detection at one configuration: obstacle rows (3 nonzeros) and
/// inter-body vertex-triangle rows of eq. 8 (12 nonzeros): for every surface vertex i of one
/// body inside a tet of another body, the closest surface triangle (j, k, l) of that body, its
/// outward unit normal n and the barycentric weights w of the closest point give the row
///     n'(x_i - w_j x_j - w_k x_k - w_l x_l) >= 0      (c = 0).
/// Optional self-contact: the same test against non-incident tets/triangles of the own body.
/// Ref: Li et al. 2015, Sec. 3.2, eq. (8); candidates from Bvh (AABB trees), rebuilt per call.
#include "sim/collision/obstacles.hpp"
#include "solvers/core/qp.hpp"

#include <memory>
#include <vector>

namespace cb::sim {

/// One constraint row: sum_k weight_k n'x_{vertex_k} >= c.
struct ContactRow {
    ContactKind kind = ContactKind::OTHER;
    double depth = 0;  ///< penetration at detection (>= 0; 0 for rows within the margin)
    int vertex[4] = {-1, -1, -1, -1};
    double weight[4] = {0, 0, 0, 0};
    Vec3 normal = Vec3::Zero();
    double c = 0;
    int other = -1;  ///< obstacle index or other body index
};

/// A body as collision detection sees it (global vertex ids).
struct CollisionBody {
    Tets tets;
    Faces faces;  ///< outward boundary triangles
    std::vector<int> surface_vertices;
};

struct DetectionSettings {
    double margin = 0.0;             ///< m: obstacle rows also for vertices this close outside
    bool inter_body = true;          ///< vertex-in-other-body rows (only built when there are >= 2 bodies)
    bool self_contact = false;       ///< vertex-in-own-body rows (non-incident tets)
    double inside_tolerance = 1e-9;  ///< barycentric slack of the point-in-tet test
};

struct DetectionStats {
    long obstacle_rows = 0, inter_body_rows = 0, self_rows = 0;
    long tet_candidates = 0;  ///< point-in-box hits before the exact point-in-tet test
};

class CollisionDetector {
public:
    CollisionDetector(std::vector<CollisionBody> bodies, std::vector<const Obstacle*> obstacles,
                      DetectionSettings settings);
    /// Rows at positions x (3#V): obstacles first (in obstacle order, then vertex order), then
    /// inter-body and self rows (body, surface vertex, other body order): deterministic.
    std::vector<ContactRow> detect(const Vec& x, DetectionStats* stats = nullptr) const;
    const DetectionSettings& settings() const { return m_settings; }

private:
    std::vector<CollisionBody> m_bodies;
    std::vector<const Obstacle*> m_obstacles;
    DetectionSettings m_settings;
};

/// J (m x n), c and the per-row metadata the snapshot keeps.
void assemble_constraints(const std::vector<ContactRow>& rows, Eigen::Index n, SpMat& J, Vec& c, ContactRows& meta);

/// Barycentric coordinates of p in tet (a, b, c, d) (sum to 1).
Eigen::Vector4d tet_barycentric(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d);

}  // namespace cb::sim
