#pragma once
/// Frictional test problems for the solver and measure tests (issue 48): a synthetic QP given
/// Coulomb friction (solvers/core/qp.hpp Friction) with tangent rows built from its normal rows.
#include "harness/runner.hpp"
#include "problems/synthetic.hpp"
#include "solvers/core/qp.hpp"

#include <cmath>
#include <functional>
#include <vector>

namespace cb::testing_qps {

/// Gives every contact row of `qp` two tangent rows and mu_i = mu_of(i). Row i's normal is its
/// first touched vertex's three entries, normalised; t1, t2 complete an orthonormal frame, and
/// each touched vertex v (entries a_v) gets (a_v . n) t_k in tangent row k, so the frame is the
/// row's own (a one-vertex plane row: exactly n, t1, t2). cT = T x0: slip is measured from the start.
inline void add_friction(Qp& qp, const std::function<double(Eigen::Index)>& mu_of)
{
    const Eigen::Index m = qp.m(), n = qp.n();
    std::vector<Triplet> t;
    for (Eigen::Index i = 0; i < m; ++i) {
        Eigen::Vector3d normal = Eigen::Vector3d::Zero();
        Eigen::Index first = -1;
        for (SpMat::InnerIterator it(qp.J, i); it; ++it) {
            if (first < 0) first = it.col() / 3;
            if (it.col() / 3 == first) normal[it.col() % 3] = it.value();
        }
        normal.normalize();
        const Eigen::Vector3d helper = std::abs(normal[0]) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
        const Eigen::Vector3d t1 = normal.cross(helper).normalized();
        const Eigen::Vector3d t2 = normal.cross(t1);
        // Per touched vertex, the weight a_v . n.
        std::vector<std::pair<Eigen::Index, double>> weight;
        for (SpMat::InnerIterator it(qp.J, i); it; ++it) {
            const Eigen::Index v = it.col() / 3;
            if (weight.empty() || weight.back().first != v) weight.push_back({v, 0.0});
            weight.back().second += it.value() * normal[it.col() % 3];
        }
        for (const auto& [v, w] : weight)
            for (int a = 0; a < 3; ++a) {
                if (t1[a] != 0.0) t.emplace_back(static_cast<int>(2 * i), static_cast<int>(3 * v + a), w * t1[a]);
                if (t2[a] != 0.0) t.emplace_back(static_cast<int>(2 * i + 1), static_cast<int>(3 * v + a), w * t2[a]);
            }
    }
    Friction& f = qp.friction;
    f.T.resize(2 * m, n);
    f.T.setFromTriplets(t.begin(), t.end());
    f.T.makeCompressed();
    f.mu.resize(m);
    for (Eigen::Index i = 0; i < m; ++i) f.mu[i] = mu_of(i);
    f.cT = f.T * qp.x0;
}

/// `plane` (a body falling onto the ground y >= 0) with a sideways load along x spread over its
/// vertices, `push` times the total contact force of the frictionless solution: with mu > push
/// the body tends to stick, with mu < push it slides.
inline Qp pushed_plane(double push, double mu, std::uint64_t seed = 3)
{
    Qp qp = make_synthetic("plane", {{"nx", 3}, {"ny", 2}, {"nz", 3}}, seed);
    RunOptions options;
    options.record_history = false;
    const RunOutcome frictionless = run_solver(qp, "active-set", {{"tol", 1e-10}}, options);
    const double load = push * frictionless.lambda_full.sum() / (static_cast<double>(qp.n()) / 3.0);
    for (Eigen::Index j = 0; j < qp.n(); j += 3) qp.b[j] += load;
    add_friction(qp, [mu](Eigen::Index) { return mu; });
    return qp;
}

/// k particles in a chain of weak springs on the plane z >= 0, pushed down and sideways: the first
/// half by 0.1 of the push, the second by 2 (mu = 0.5): the first half sticks, the second slides.
inline Qp particles_on_a_plane(int k)
{
    const Eigen::Index n = 3 * static_cast<Eigen::Index>(k);
    std::vector<Eigen::Triplet<double>> a;
    for (Eigen::Index j = 0; j < n; ++j) a.emplace_back(int(j), int(j), 1.0);  // masses
    for (int p = 0; p + 1 < k; ++p)                                            // springs of stiffness 0.02
        for (int d = 0; d < 3; ++d) {
            const int i = 3 * p + d, j = 3 * (p + 1) + d;
            a.emplace_back(i, i, 0.02);
            a.emplace_back(j, j, 0.02);
            a.emplace_back(i, j, -0.02);
            a.emplace_back(j, i, -0.02);
        }
    Qp qp;
    qp.A.resize(n, n);
    qp.A.setFromTriplets(a.begin(), a.end());
    qp.b = Vec::Zero(n);
    qp.J.resize(k, n);
    qp.friction.T.resize(2 * static_cast<Eigen::Index>(k), n);
    std::vector<Eigen::Triplet<double>> j, t;
    for (int p = 0; p < k; ++p) {
        j.emplace_back(p, 3 * p + 2, 1.0);
        t.emplace_back(2 * p, 3 * p, 1.0);
        t.emplace_back(2 * p + 1, 3 * p + 1, 1.0);
        const Eigen::Index at = 3 * static_cast<Eigen::Index>(p);
        qp.b[at + 2] = -1.0;
        qp.b[at] = 2 * p < k ? 0.1 : 2.0;
        qp.b[at + 1] = 0.05 * ((p % 3) - 1);
    }
    qp.J.setFromTriplets(j.begin(), j.end());
    qp.friction.T.setFromTriplets(t.begin(), t.end());
    qp.c = Vec::Zero(k);
    qp.x0 = Vec::Zero(n);
    qp.friction.mu = Vec::Constant(k, 0.5);
    return qp;
}

}  // namespace cb::testing_qps
