#include "sim/tet_mesh.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <sstream>

namespace cb::sim {

double signed_volume(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d)
{
    return (b - a).dot((c - a).cross(d - a)) / 6.0;
}

static Vec3 row(const Positions& p, int i) { return p.row(i).transpose(); }

double mesh_volume(const TetMesh& mesh)
{
    double v = 0.0;
    for (Eigen::Index t = 0; t < mesh.tets.rows(); ++t)
        v += signed_volume(row(mesh.positions, mesh.tets(t, 0)), row(mesh.positions, mesh.tets(t, 1)),
                           row(mesh.positions, mesh.tets(t, 2)), row(mesh.positions, mesh.tets(t, 3)));
    return v;
}

void orient_tets(TetMesh& mesh, const std::string& where)
{
    const long nv = mesh.vertices();
    Vec3 lo, hi;
    bounding_box(mesh.positions, lo, hi);
    const double scale = std::max((hi - lo).maxCoeff(), 1e-300);
    // Relative threshold: a tet this flat has no usable stiffness (its inverse shape matrix blows up).
    const double eps = 1e-14 * scale * scale * scale;
    for (Eigen::Index t = 0; t < mesh.tets.rows(); ++t) {
        for (int k = 0; k < 4; ++k) {
            const int id = mesh.tets(t, k);
            if (id < 0 || id >= nv)
                throw_input_error(where, "tet " + std::to_string(t + 1),
                                  "vertex id " + std::to_string(id + 1) + " out of range 1.." + std::to_string(nv));
            for (int l = 0; l < k; ++l)
                if (mesh.tets(t, l) == id)
                    throw_input_error(where, "tet " + std::to_string(t + 1),
                                      "repeats vertex " + std::to_string(id + 1));
        }
        const double v = signed_volume(row(mesh.positions, mesh.tets(t, 0)), row(mesh.positions, mesh.tets(t, 1)),
                                       row(mesh.positions, mesh.tets(t, 2)), row(mesh.positions, mesh.tets(t, 3)));
        if (std::abs(v) <= eps)
            throw_input_error(where, "tet " + std::to_string(t + 1), "degenerate (volume " + std::to_string(v) + ")");
        if (v < 0) std::swap(mesh.tets(t, 2), mesh.tets(t, 3));
    }
}

Faces boundary_faces(const TetMesh& mesh)
{
    // Outward faces of a positively oriented tet (a, b, c, d).
    static const int local[4][3] = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
    struct Entry {
        std::array<int, 3> key;
        std::array<int, 3> face;
    };
    std::vector<Entry> entries;
    entries.reserve(static_cast<size_t>(mesh.tets.rows()) * 4);
    for (Eigen::Index t = 0; t < mesh.tets.rows(); ++t)
        for (const auto& f : local) {
            Entry e;
            e.face = {mesh.tets(t, f[0]), mesh.tets(t, f[1]), mesh.tets(t, f[2])};
            e.key = e.face;
            std::sort(e.key.begin(), e.key.end());
            entries.push_back(e);
        }
    std::sort(entries.begin(), entries.end(), [](const Entry& a, const Entry& b) { return a.key < b.key; });
    std::vector<std::array<int, 3>> out;
    for (size_t i = 0; i < entries.size();) {
        size_t j = i + 1;
        while (j < entries.size() && entries[j].key == entries[i].key) ++j;
        if (j - i == 1) out.push_back(entries[i].face);
        i = j;
    }
    Faces faces(static_cast<Eigen::Index>(out.size()), 3);
    for (size_t i = 0; i < out.size(); ++i)
        for (int k = 0; k < 3; ++k) faces(static_cast<Eigen::Index>(i), k) = out[i][k];
    return faces;
}

std::vector<int> boundary_vertices(const Faces& faces, long vertex_count)
{
    std::vector<char> mark(static_cast<size_t>(vertex_count), 0);
    for (Eigen::Index f = 0; f < faces.rows(); ++f)
        for (int k = 0; k < 3; ++k) mark[static_cast<size_t>(faces(f, k))] = 1;
    std::vector<int> out;
    for (long i = 0; i < vertex_count; ++i)
        if (mark[static_cast<size_t>(i)]) out.push_back(static_cast<int>(i));
    return out;
}

void bounding_box(const Positions& p, Vec3& lo, Vec3& hi)
{
    if (p.rows() == 0) {
        lo.setZero();
        hi.setZero();
        return;
    }
    lo = p.colwise().minCoeff().transpose();
    hi = p.colwise().maxCoeff().transpose();
}

Eigen::Matrix3d rotation_from_euler_deg(const Vec3& degrees)
{
    const Vec3 r = degrees * (M_PI / 180.0);
    return (Eigen::AngleAxisd(r.z(), Vec3::UnitZ()) * Eigen::AngleAxisd(r.y(), Vec3::UnitY()) *
            Eigen::AngleAxisd(r.x(), Vec3::UnitX()))
        .toRotationMatrix();
}

void transform_positions(Positions& p, double scale, const Eigen::Matrix3d& R, const Vec3& translation)
{
    for (Eigen::Index i = 0; i < p.rows(); ++i)
        p.row(i) = (R * (scale * p.row(i).transpose()) + translation).transpose();
}

TetMesh make_box_mesh(int nx, int ny, int nz, const Vec3& cell, const Vec3& lo)
{
    TetMesh mesh;
    const int vx = nx + 1, vy = ny + 1, vz = nz + 1;
    mesh.positions.resize(static_cast<Eigen::Index>(vx) * vy * vz, 3);
    auto id = [&](int i, int j, int k) { return (k * vy + j) * vx + i; };
    for (int k = 0; k < vz; ++k)
        for (int j = 0; j < vy; ++j)
            for (int i = 0; i < vx; ++i)
                mesh.positions.row(id(i, j, k)) = (lo + Vec3(i * cell.x(), j * cell.y(), k * cell.z())).transpose();
    // Kuhn subdivision: one tet per permutation of the axes along the cube's main diagonal.
    // Every cube uses the same diagonal, so neighbouring cubes share face triangulations.
    static const int perms[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
    mesh.tets.resize(static_cast<Eigen::Index>(nx) * ny * nz * 6, 4);
    Eigen::Index t = 0;
    for (int k = 0; k < nz; ++k)
        for (int j = 0; j < ny; ++j)
            for (int i = 0; i < nx; ++i)
                for (const auto& p : perms) {
                    int c[3] = {i, j, k};
                    mesh.tets(t, 0) = id(c[0], c[1], c[2]);
                    for (int s = 0; s < 3; ++s) {
                        ++c[p[s]];
                        mesh.tets(t, s + 1) = id(c[0], c[1], c[2]);
                    }
                    ++t;
                }
    orient_tets(mesh, "box mesh");
    return mesh;
}

std::string MeshQuality::to_string() const
{
    char buf[256];
    std::snprintf(buf, sizeof buf,
                  "dihedral angles %.2f..%.2f deg, volume ratio min %.3f mean %.3f, tet volume %.3g..%.3g",
                  min_dihedral_deg, max_dihedral_deg, min_volume_ratio, mean_volume_ratio, min_volume, max_volume);
    return buf;
}

MeshQuality mesh_quality(const TetMesh& mesh)
{
    MeshQuality q;
    q.min_dihedral_deg = 180;
    q.max_dihedral_deg = 0;
    q.min_volume_ratio = 1e300;
    q.min_volume = 1e300;
    q.max_volume = -1e300;
    double sum_ratio = 0;
    static const int edges[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};
    for (Eigen::Index t = 0; t < mesh.tets.rows(); ++t) {
        Vec3 x[4];
        for (int k = 0; k < 4; ++k) x[k] = row(mesh.positions, mesh.tets(t, k));
        const double v = signed_volume(x[0], x[1], x[2], x[3]);
        double l2 = 0;
        for (const auto& e : edges) l2 += (x[e[0]] - x[e[1]]).squaredNorm();
        const double lrms = std::sqrt(l2 / 6.0);
        const double ratio = 6.0 * std::sqrt(2.0) * v / (lrms * lrms * lrms);
        q.min_volume_ratio = std::min(q.min_volume_ratio, ratio);
        sum_ratio += ratio;
        q.min_volume = std::min(q.min_volume, v);
        q.max_volume = std::max(q.max_volume, v);
        // Dihedral angle at edge (a, b): angle between the two faces containing it.
        for (const auto& e : edges) {
            int o[2], n = 0;
            for (int k = 0; k < 4; ++k)
                if (k != e[0] && k != e[1]) o[n++] = k;
            const Vec3 axis = (x[e[1]] - x[e[0]]).normalized();
            Vec3 u = x[o[0]] - x[e[0]], w = x[o[1]] - x[e[0]];
            u -= axis * axis.dot(u);
            w -= axis * axis.dot(w);
            const double c = std::clamp(u.normalized().dot(w.normalized()), -1.0, 1.0);
            const double a = std::acos(c) * 180.0 / M_PI;
            q.min_dihedral_deg = std::min(q.min_dihedral_deg, a);
            q.max_dihedral_deg = std::max(q.max_dihedral_deg, a);
        }
    }
    if (mesh.tets.rows() > 0) q.mean_volume_ratio = sum_ratio / static_cast<double>(mesh.tets.rows());
    return q;
}

}  // namespace cb::sim
