#pragma once
/// Small self-contained contact QPs for the ica/pgs tests (no dependency on problems/):
/// a grid of vertices with an SPD A = mass I + stiffness (L (x) C) (L: the grid graph Laplacian,
/// C: a fixed SPD 3x3 coupling, so the 3x3 vertex blocks are full), pushed below the plane y >= 0.
#include "solvers/core/qp.hpp"
#include "solvers/measure/accuracy.hpp"

#include <Eigen/Dense>
#include <cmath>
#include <vector>

namespace cb::test {

struct GridQpParams {
    int nx = 4, ny = 3, nz = 4;
    double mass = 1.0, stiffness = 20.0;
    double drop = 0.25;    ///< how far below its rest position the predicted body sits
    double tilt = 0.2;     ///< plane normal (sin tilt, cos tilt, 0)
    bool coupled = false;  ///< add rows that share vertices (J J' not diagonal)
};

inline int grid_vertex(const GridQpParams& p, int i, int j, int k) { return i + p.nx * (j + p.ny * k); }

inline Qp make_grid_qp(const GridQpParams& p)
{
    const int nv = p.nx * p.ny * p.nz, n = 3 * nv;
    Eigen::Matrix3d C;
    C << 1.0, 0.3, 0.1, 0.3, 1.0, 0.2, 0.1, 0.2, 1.0;
    std::vector<Triplet> t;
    auto couple = [&](int a, int b) {
        for (int r = 0; r < 3; ++r)
            for (int s = 0; s < 3; ++s) {
                const double v = p.stiffness * C(r, s);
                t.emplace_back(3 * a + r, 3 * a + s, v);
                t.emplace_back(3 * b + r, 3 * b + s, v);
                t.emplace_back(3 * a + r, 3 * b + s, -v);
                t.emplace_back(3 * b + r, 3 * a + s, -v);
            }
    };
    Vec rest(n);
    for (int k = 0; k < p.nz; ++k)
        for (int j = 0; j < p.ny; ++j)
            for (int i = 0; i < p.nx; ++i) {
                const int v = grid_vertex(p, i, j, k);
                rest.segment<3>(3 * static_cast<Eigen::Index>(v)) << 0.1 * i, 0.1 * j, 0.1 * k;
                if (i + 1 < p.nx) couple(v, grid_vertex(p, i + 1, j, k));
                if (j + 1 < p.ny) couple(v, grid_vertex(p, i, j + 1, k));
                if (k + 1 < p.nz) couple(v, grid_vertex(p, i, j, k + 1));
            }
    for (int d = 0; d < n; ++d) t.emplace_back(d, d, p.mass);
    Qp qp;
    qp.A.resize(n, n);
    qp.A.setFromTriplets(t.begin(), t.end());
    Vec pred = rest;
    for (int v = 0; v < nv; ++v) pred[3 * v + 1] -= p.drop * (1.0 + 0.3 * std::sin(1.7 * v));
    qp.b = qp.A * pred;  // the unconstrained minimiser is the predicted (penetrating) body
    qp.x0 = pred;
    const double sx = std::sin(p.tilt), sy = std::cos(p.tilt);
    std::vector<Triplet> jt;
    std::vector<double> c;
    int row = 0;
    for (int v = 0; v < nv; ++v) {
        if (rest[3 * v + 1] > 0.15) continue;  // the two lowest layers touch the plane
        jt.emplace_back(row, 3 * v, sx);
        jt.emplace_back(row, 3 * v + 1, sy);
        c.push_back(0.0);
        ++row;
    }
    if (p.coupled) {
        // Vertex-"triangle"-like rows: y_v - 0.5 (y_a + y_b) >= -0.02 between neighbours.
        for (int k = 0; k + 1 < p.nz; ++k)
            for (int i = 0; i + 1 < p.nx; ++i) {
                const int v = grid_vertex(p, i, 1, k), a = grid_vertex(p, i, 0, k), b = grid_vertex(p, i + 1, 0, k + 1);
                jt.emplace_back(row, 3 * v + 1, 1.0);
                jt.emplace_back(row, 3 * a + 1, -0.5);
                jt.emplace_back(row, 3 * b + 1, -0.5);
                jt.emplace_back(row, 3 * b, 0.2);
                c.push_back(0.12);
                ++row;
            }
    }
    qp.J.resize(row, n);
    qp.J.setFromTriplets(jt.begin(), jt.end());
    qp.c = Eigen::Map<Vec>(c.data(), static_cast<Eigen::Index>(c.size()));
    return qp;
}

/// Relative common KKT error of (x, lambda), computed the harness's way.
inline double relative_kkt(const Qp& qp, const Vec& x, const Vec& lambda)
{
    return accuracy(qp.view(), x, lambda).max();
}

}  // namespace cb::test
