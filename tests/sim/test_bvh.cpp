// The BVH against brute force, and inter-body detection (eq. 8 rows) against a brute-force
// search over every tet and triangle.
#include "sim/collision/bvh.hpp"
#include "sim/collision/dcd.hpp"
#include "sim/collision/obstacles.hpp"

#include <gtest/gtest.h>
#include <algorithm>
#include <random>

using namespace cb;
using namespace cb::sim;

namespace {
std::vector<Box3> random_boxes(int n, unsigned seed)
{
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(0, 1), s(0.001, 0.08);
    std::vector<Box3> boxes;
    for (int i = 0; i < n; ++i) {
        const Vec3 c(u(rng), u(rng), u(rng));
        const Vec3 e(s(rng), s(rng), s(rng));
        boxes.emplace_back(c - e, c + e);
    }
    return boxes;
}
}  // namespace

TEST(Bvh, PointAndBoxQueriesEqualBruteForce)
{
    const auto boxes = random_boxes(3000, 5);
    const Bvh bvh(boxes);
    std::mt19937 rng(9);
    std::uniform_real_distribution<double> u(-0.05, 1.05);
    long total = 0;
    for (int q = 0; q < 300; ++q) {
        const Vec3 p(u(rng), u(rng), u(rng));
        std::vector<int> got, want;
        bvh.query_point(p, [&](int i) { got.push_back(i); });
        for (int i = 0; i < static_cast<int>(boxes.size()); ++i)
            if (boxes[static_cast<size_t>(i)].contains(p)) want.push_back(i);
        std::sort(got.begin(), got.end());
        EXPECT_EQ(got, want);
        const Box3 qb(p, p + Vec3(0.05, 0.02, 0.07));
        got.clear();
        want.clear();
        bvh.query_box(qb, [&](int i) { got.push_back(i); });
        for (int i = 0; i < static_cast<int>(boxes.size()); ++i)
            if (boxes[static_cast<size_t>(i)].intersects(qb)) want.push_back(i);
        std::sort(got.begin(), got.end());
        EXPECT_EQ(got, want);
        total += static_cast<long>(want.size());
    }
    EXPECT_GT(total, 300);  // the queries do hit boxes
}

TEST(Bvh, NearestEqualsBruteForce)
{
    const auto boxes = random_boxes(2000, 11);
    const Bvh bvh(boxes);
    std::mt19937 rng(2);
    std::uniform_real_distribution<double> u(-0.5, 1.5);
    for (int q = 0; q < 200; ++q) {
        const Vec3 p(u(rng), u(rng), u(rng));
        // Distance to the box centre, bounded below by the box distance as required.
        auto d2 = [&](int i) { return (boxes[static_cast<size_t>(i)].center() - p).squaredNorm(); };
        double best = 1e300;
        int want = -1;
        for (int i = 0; i < static_cast<int>(boxes.size()); ++i)
            if (d2(i) < best) {
                best = d2(i);
                want = i;
            }
        double got_d2 = 0;
        EXPECT_EQ(bvh.nearest(p, d2, &got_d2), want);
        EXPECT_DOUBLE_EQ(got_d2, best);
    }
}

TEST(ClosestPoint, TriangleRegionsAndWeights)
{
    const Vec3 a(0, 0, 0), b(1, 0, 0), c(0, 1, 0);
    Eigen::Vector3d w;
    EXPECT_LT((closest_point_triangle(Vec3(0.2, 0.3, 0.5), a, b, c, w) - Vec3(0.2, 0.3, 0)).norm(), 1e-15);
    EXPECT_NEAR(w[0], 0.5, 1e-15);
    EXPECT_NEAR(w[1], 0.2, 1e-15);
    EXPECT_NEAR(w[2], 0.3, 1e-15);
    EXPECT_LT((closest_point_triangle(Vec3(-1, -1, 1), a, b, c, w) - a).norm(), 1e-15);
    EXPECT_LT((closest_point_triangle(Vec3(1, 1, 0), a, b, c, w) - Vec3(0.5, 0.5, 0)).norm(), 1e-15);
    EXPECT_NEAR(w[1], 0.5, 1e-15);
}

TEST(Dcd, InterBodyRowsEqualBruteForceAndHaveTwelveNonzeros)
{
    // Two boxes overlapping by 0.03 in y: the lower one's top vertices are inside the upper.
    const TetMesh lower = make_box_mesh(3, 3, 3, Vec3(0.1, 0.1, 0.1), Vec3(0, 0, 0));
    const TetMesh upper = make_box_mesh(3, 3, 3, Vec3(0.1, 0.1, 0.1), Vec3(0.05, 0.27, 0.04));
    const int nv = static_cast<int>(lower.vertices());
    std::vector<CollisionBody> bodies(2);
    Vec x(3 * (lower.vertices() + upper.vertices()));
    for (int b = 0; b < 2; ++b) {
        const TetMesh& m = b == 0 ? lower : upper;
        const int off = b == 0 ? 0 : nv;
        bodies[b].tets = m.tets.array() + off;
        const Faces f = boundary_faces(m);
        bodies[b].faces = f.array() + off;
        for (int v : boundary_vertices(f, m.vertices())) bodies[b].surface_vertices.push_back(v + off);
        for (long i = 0; i < m.vertices(); ++i) x.segment<3>(3 * (off + i)) = m.positions.row(i).transpose();
    }
    const auto plane = make_plane(Vec3(0, 1, 0), Vec3(0, 0.005, 0));
    CollisionDetector det(bodies, {plane.get()}, DetectionSettings{});
    DetectionStats st;
    const auto rows = det.detect(x, &st);
    EXPECT_EQ(st.obstacle_rows, 16);  // the bottom face's 4x4 vertices below y = 0.005
    ASSERT_GT(st.inter_body_rows, 0);

    // Brute force: every surface vertex against every tet and every face of the other body.
    long brute = 0;
    for (int a = 0; a < 2; ++a)
        for (int v : bodies[a].surface_vertices) {
            const int b = 1 - a;
            const Vec3 p = x.segment<3>(3 * v);
            bool inside = false;
            for (Eigen::Index t = 0; t < bodies[b].tets.rows() && !inside; ++t) {
                const auto w =
                    tet_barycentric(p, x.segment<3>(3 * bodies[b].tets(t, 0)), x.segment<3>(3 * bodies[b].tets(t, 1)),
                                    x.segment<3>(3 * bodies[b].tets(t, 2)), x.segment<3>(3 * bodies[b].tets(t, 3)));
                inside = w.minCoeff() >= -1e-9;
            }
            if (!inside) continue;
            ++brute;
            double best = 1e300;
            for (Eigen::Index f = 0; f < bodies[b].faces.rows(); ++f) {
                Eigen::Vector3d w;
                const Vec3 q = closest_point_triangle(p, x.segment<3>(3 * bodies[b].faces(f, 0)),
                                                      x.segment<3>(3 * bodies[b].faces(f, 1)),
                                                      x.segment<3>(3 * bodies[b].faces(f, 2)), w);
                best = std::min(best, (p - q).norm());
            }
            const auto it = std::find_if(rows.begin(), rows.end(), [&](const ContactRow& r) {
                return r.kind == ContactKind::INTER_BODY && r.vertex[0] == v;
            });
            ASSERT_NE(it, rows.end()) << "vertex " << v;
            EXPECT_NEAR(it->depth, best, 1e-12);
        }
    EXPECT_EQ(st.inter_body_rows, brute);

    SpMat J;
    Vec c;
    ContactRows meta;
    assemble_constraints(rows, x.size(), J, c, meta);
    ASSERT_EQ(J.rows(), static_cast<Eigen::Index>(rows.size()));
    for (Eigen::Index i = 0; i < J.rows(); ++i) {
        const auto kind = static_cast<ContactKind>(meta.kind[static_cast<size_t>(i)]);
        EXPECT_EQ(J.outerIndexPtr()[i + 1] - J.outerIndexPtr()[i], kind == ContactKind::INTER_BODY ? 12 : 3);
        if (kind == ContactKind::INTER_BODY) {
            EXPECT_EQ(c[i], 0.0);
            // At detection the vertex is inside: the row is violated by its depth.
            EXPECT_NEAR(J.row(i).dot(x), -meta.depth[static_cast<size_t>(i)], 1e-12);
        }
    }
}

TEST(Obstacles, SignedDistancesOfSimpleShapes)
{
    ObstacleHit hit;
    const auto sphere = make_sphere(Vec3(0, 0, 0), 1.0);
    ASSERT_TRUE(sphere->query(Vec3(0, 0.9, 0), 0.0, hit));
    EXPECT_NEAR(hit.distance, -0.1, 1e-15);
    EXPECT_LT((hit.normal - Vec3(0, 1, 0)).norm(), 1e-15);
    EXPECT_FALSE(sphere->query(Vec3(0, 1.1, 0), 0.05, hit));
    const auto box = make_box(Vec3(0, 0, 0), Vec3(1, 2, 3));
    ASSERT_TRUE(box->query(Vec3(0.5, 1.95, 1.0), 0.0, hit));
    EXPECT_NEAR(hit.distance, -0.05, 1e-15);
    EXPECT_LT((hit.normal - Vec3(0, 1, 0)).norm(), 1e-15);
    const auto cyl = make_cylinder(Vec3(0, 0, 0), Vec3(0, 1, 0), 0.5, 2.0);
    ASSERT_TRUE(cyl->query(Vec3(0.45, 0.2, 0), 0.0, hit));
    EXPECT_NEAR(hit.distance, -0.05, 1e-15);
    EXPECT_LT((hit.normal - Vec3(1, 0, 0)).norm(), 1e-15);
    ASSERT_TRUE(cyl->query(Vec3(0.1, 0.98, 0), 0.0, hit));  // nearer the cap than the mantle
    EXPECT_LT((hit.normal - Vec3(0, 1, 0)).norm(), 1e-15);
    // A mesh obstacle (the box's surface) agrees with the analytic box near a face.
    const TetMesh cube = make_box_mesh(2, 2, 2, Vec3(0.5, 1.0, 1.5));
    SurfaceMesh s;
    s.positions = cube.positions;
    s.faces = boundary_faces(cube);
    const auto mesh = make_mesh_obstacle(s, 0.2);
    ASSERT_TRUE(mesh->query(Vec3(0.5, 1.95, 1.0), 0.0, hit));
    EXPECT_NEAR(hit.distance, -0.05, 1e-12);
    EXPECT_LT((hit.normal - Vec3(0, 1, 0)).norm(), 1e-12);
    EXPECT_FALSE(mesh->query(Vec3(0.5, 2.05, 1.0), 0.0, hit));
}

TEST(Dcd, SelfContactFindsOverlapWithinOneBodyAndNothingAtRest)
{
    // One body made of two overlapping box components: with self-contact on, its rows equal
    // the inter-body rows of the same geometry split into two bodies; a plain box has none.
    const TetMesh a = make_box_mesh(3, 3, 3, Vec3(0.1, 0.1, 0.1), Vec3(0, 0, 0));
    const TetMesh b = make_box_mesh(3, 3, 3, Vec3(0.1, 0.1, 0.1), Vec3(0.05, 0.27, 0.04));
    const int nv = static_cast<int>(a.vertices());
    Vec x(3 * (a.vertices() + b.vertices()));
    CollisionBody one, two[2];
    for (int k = 0; k < 2; ++k) {
        const TetMesh& m = k == 0 ? a : b;
        const int off = k == 0 ? 0 : nv;
        const Faces f = boundary_faces(m);
        for (long i = 0; i < m.vertices(); ++i) x.segment<3>(3 * (off + i)) = m.positions.row(i).transpose();
        two[k].tets = m.tets.array() + off;
        two[k].faces = f.array() + off;
        for (int v : boundary_vertices(f, m.vertices())) two[k].surface_vertices.push_back(v + off);
    }
    one.tets.resize(two[0].tets.rows() + two[1].tets.rows(), 4);
    one.tets << two[0].tets, two[1].tets;
    one.faces.resize(two[0].faces.rows() + two[1].faces.rows(), 3);
    one.faces << two[0].faces, two[1].faces;
    one.surface_vertices = two[0].surface_vertices;
    one.surface_vertices.insert(one.surface_vertices.end(), two[1].surface_vertices.begin(),
                                two[1].surface_vertices.end());
    DetectionSettings self;
    self.self_contact = true;
    DetectionStats st_self, st_inter, st_rest;
    CollisionDetector(std::vector<CollisionBody>{one}, {}, self).detect(x, &st_self);
    CollisionDetector(std::vector<CollisionBody>{two[0], two[1]}, {}, DetectionSettings{}).detect(x, &st_inter);
    EXPECT_EQ(st_inter.inter_body_rows, 18);
    EXPECT_EQ(st_self.self_rows, st_inter.inter_body_rows);
    CollisionDetector(std::vector<CollisionBody>{two[0]}, {}, self).detect(x, &st_rest);
    EXPECT_EQ(st_rest.self_rows, 0);
}
