// The sweep start of a large component's LCPs (solvers/mprgp/coupled_sparse_blocks.cpp,
// CoupledOperatorOptions::sweep_start_sweeps): the set it picks is only a warm start, so the
// projection and chopped multipliers must equal those of the old path (every negative row dropped)
// and of the global oracle to rounding, meet the LCP's KKT conditions, and take fewer LCP steps on
// a cold start (all rows violated).
#include "coupled_test_qps.hpp"
#include "problems/synthetic.hpp"
#include "solvers/linalg/row_components.hpp"
#include "solvers/mprgp/coupled_face_operators.hpp"
#include "solvers/mprgp/coupled_sparse_lcp.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

namespace {

using cb::Qp;
using cb::SpMat;
using cb::Vec;

namespace sweep_start_test {

/// A 196-row patch (one component) with, optionally, a duplicated and a parallel row.
Qp patch(bool dependent)
{
    const Qp qp =
        cb::coupled_test_qps::loaded(cb::make_synthetic("coupled", {{"nx", 13}, {"ny", 2}, {"nz", 13}}, 7), 7);
    return dependent ? cb::coupled_test_qps::with_dependent_row(cb::coupled_test_qps::with_dependent_row(qp, 40, 1.0),
                                                                90, 3.0)
                     : qp;
}

/// The operators with the component on CHOLMOD (dense_max_rows below its size); a drop of more
/// than 8 rows starts the sweeps (flank_press's 1152 rows: 64, the default).
std::unique_ptr<cb::CoupledFaceOperators> operators(const SpMat& J, long sweeps, bool global = false)
{
    cb::CoupledOperatorOptions opt;
    opt.global = global;
    opt.jacobi = false;
    opt.dense_max_rows = 8;
    opt.sparse_max_updates = 8;
    opt.sweep_start_sweeps = sweeps;
    return std::make_unique<cb::CoupledFaceOperators>(J, Vec::Ones(J.cols()), opt);
}

/// Strongly coupled rows, as where two bodies press flank to flank: a chain of m rows on m + 1
/// DOFs, row i = e_i + e_(i+1) (its Gram matrix tridiagonal, neighbours correlated by 1/2), with,
/// optionally, row 40 duplicated and row 90 repeated times 3 (dependent rows).
SpMat chain(int m, bool dependent)
{
    std::vector<cb::Triplet> t;
    int rows = 0;
    auto add = [&](int i, double s) {
        t.emplace_back(rows, i, s);
        t.emplace_back(rows, i + 1, s);
        ++rows;
    };
    for (int i = 0; i < m; ++i) add(i, 1.0);
    if (dependent) {
        add(40, 1.0);
        add(90, 3.0);
    }
    SpMat J(rows, m + 1);
    J.setFromTriplets(t.begin(), t.end());
    return J;
}

/// A cold projection's right-hand side: every row violated (q > 0). The solution on all rows then
/// alternates in sign along the chain, and dropping all its negative rows drops far too many.
Vec cold_q(const SpMat& J, std::uint64_t seed)
{
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> u(0.5, 1.5);
    Vec q(J.rows());
    for (Eigen::Index i = 0; i < J.rows(); ++i) q[i] = J.row(i).squaredNorm() * u(rng);
    return q;
}

struct Kkt {
    double negative = 0.0, infeasible = 0.0, complementarity = 0.0;
};

/// 0 <= lam perp G lam - q >= 0 on `rows` (G = J J' there, lam zero elsewhere), relative to |q|.
Kkt kkt(const SpMat& J, const Vec& q, const Vec& lam, const std::vector<char>& rows)
{
    Vec masked = lam;
    for (Eigen::Index i = 0; i < lam.size(); ++i)
        if (!rows[static_cast<size_t>(i)]) masked[i] = 0.0;
    const Vec w = J * Vec(J.transpose() * masked) - q;
    const double scale = std::max(1e-300, q.lpNorm<Eigen::Infinity>());
    Kkt k;
    for (Eigen::Index i = 0; i < lam.size(); ++i) {
        if (!rows[static_cast<size_t>(i)]) continue;
        k.negative = std::max(k.negative, -lam[i] / scale);
        k.infeasible = std::max(k.infeasible, -w[i] / scale);
        k.complementarity = std::max(k.complementarity, std::abs(lam[i] * w[i]) / (scale * scale));
    }
    return k;
}

void expect_kkt(const SpMat& J, const Vec& q, const Vec& lam, const std::vector<char>& rows, const std::string& what)
{
    // lam scales as q / |J_i|^2 (about 1 here): the tolerances are the LCP's own (1e-12 relative)
    // with room for the rounding of a 196-row factor.
    const Kkt k = kkt(J, q, lam, rows);
    EXPECT_LE(k.negative, 1e-12) << what;
    EXPECT_LE(k.infeasible, 1e-9) << what;
    EXPECT_LE(k.complementarity, 1e-9) << what;
}

/// J'(a - b) relative to J'a: the multipliers of dependent rows are split, J'lam is unique.
double force_difference(const SpMat& J, const Vec& a, const Vec& b)
{
    const Vec fa = J.transpose() * a;
    return Vec(J.transpose() * Vec(a - b)).lpNorm<Eigen::Infinity>() / std::max(1e-300, fa.lpNorm<Eigen::Infinity>());
}

}  // namespace sweep_start_test

}  // namespace

using namespace sweep_start_test;

TEST(CoupledSweepStart, ColdProjectionEqualsTheOldPathAndTheOracleWithFewerSteps)
{
    for (bool dependent : {false, true}) {
        const SpMat J = chain(300, dependent);
        const std::string what = dependent ? "chain with a duplicated and a parallel row" : "300-row chain";
        ASSERT_EQ(cb::find_row_components(J).largest(), J.rows()) << what;
        const std::vector<char> all(static_cast<size_t>(J.rows()), 1);
        for (std::uint64_t seed : {1u, 2u, 3u}) {
            const Vec q0 = cold_q(J, seed);
            Vec lam_new, lam_old, lam_oracle;
            cb::Counters c_new, c_old, c_oracle;
            for (auto* run : {&lam_new, &lam_old, &lam_oracle}) {
                const bool oracle = run == &lam_oracle;
                // 3 sweeps on a warm start: the cold start's own rule (sweep until the sign pattern
                // rests, at least 5 sweeps) shows in the count.
                auto ops = operators(J, run == &lam_new ? 3 : 0, oracle);
                Vec q = q0;
                run->setZero(J.rows());
                cb::Counters& c = run == &lam_new ? c_new : run == &lam_old ? c_old : c_oracle;
                ASSERT_EQ(ops->projection_multipliers(q, all, *run, c), 1) << what;
                EXPECT_EQ(ops->lcp_failures(), 0) << what;
            }
            const std::string at = what + ", seed " + std::to_string(seed);
            expect_kkt(J, q0, lam_new, all, at + ", sweep start");
            expect_kkt(J, q0, lam_old, all, at + ", old path");
            EXPECT_LE(force_difference(J, lam_old, lam_new), 1e-10) << at;
            EXPECT_LE(force_difference(J, lam_oracle, lam_new), 1e-9) << at;
            if (!dependent) {
                EXPECT_LE((lam_new - lam_old).lpNorm<Eigen::Infinity>(), 1e-9 * lam_old.lpNorm<Eigen::Infinity>())
                    << at;
            }
            // The sweeps ran, and the set they picked saved LCP steps (each a factor change and a solve).
            EXPECT_GT(c_new.pgs_sweeps, 3) << at;
            EXPECT_LE(c_new.pgs_sweeps, 200) << at;
            EXPECT_EQ(c_old.pgs_sweeps, 0) << at;
            EXPECT_LT(c_new.lcp_iterations, c_old.lcp_iterations) << at;
        }
    }
}

TEST(CoupledSweepStart, ProjectionWithKeptRowsAndChoppedMultipliersEqualTheOldPath)
{
    const Qp qp = patch(false);
    const Eigen::Index m = qp.m();
    const std::vector<char> all(static_cast<size_t>(m), 1);
    std::vector<char> keep(static_cast<size_t>(m), 0), face(static_cast<size_t>(m), 0);
    for (Eigen::Index i = 0; i < m; ++i) {
        keep[static_cast<size_t>(i)] = i % 7 == 0;  // equalities: lam of either sign
        face[static_cast<size_t>(i)] = i % 5 != 0;
    }
    const Vec q0 = cold_q(qp.J, 9);
    std::mt19937_64 rng(4);
    std::normal_distribution<double> n01;
    Vec g(qp.n());
    for (Eigen::Index j = 0; j < g.size(); ++j) g[j] = n01(rng);
    const Vec jg = qp.J * g;
    Vec lam[2], mu[2];
    cb::Counters cnt[2];
    for (int k = 0; k < 2; ++k) {
        auto ops = operators(qp.J, k == 0 ? 20 : 0);
        Vec q = q0;
        lam[k].setZero(m);
        ops->projection_multipliers(q, all, lam[k], cnt[k], &keep);
        // The chopped LCP on a face: q = J_A g on the face rows, nu = (J_A J_A')^-1 J_A g.
        ops->set_face(face, cnt[k]);
        Vec nu = Vec::Zero(m);
        ops->face_multipliers(jg, nu, cnt[k]);
        mu[k].setZero(m);
        ops->chopped_multipliers(jg, nu, mu[k], cnt[k]);
        EXPECT_EQ(ops->lcp_failures(), 0);
    }
    EXPECT_GT(cnt[0].pgs_sweeps, 0) << "the sweep start ran";
    EXPECT_LE((lam[0] - lam[1]).lpNorm<Eigen::Infinity>(), 1e-9 * lam[1].lpNorm<Eigen::Infinity>());
    EXPECT_LE((mu[0] - mu[1]).lpNorm<Eigen::Infinity>(), 1e-9 * std::max(1e-300, mu[1].lpNorm<Eigen::Infinity>()));
    // Kept rows are equalities (w = 0 there, lam of either sign); the others the LCP's conditions.
    const Vec w = qp.J * Vec(qp.J.transpose() * lam[0]) - q0;
    std::vector<char> free_rows(static_cast<size_t>(m), 0);
    for (Eigen::Index i = 0; i < m; ++i) {
        if (keep[static_cast<size_t>(i)]) {
            EXPECT_LE(std::abs(w[i]), 1e-9 * q0.lpNorm<Eigen::Infinity>()) << "kept row " << i;
        } else {
            free_rows[static_cast<size_t>(i)] = 1;
        }
    }
    EXPECT_LE(kkt(qp.J, q0, lam[0], free_rows).negative, 1e-12);
    Vec q_face = jg;
    for (Eigen::Index i = 0; i < m; ++i)
        if (!face[static_cast<size_t>(i)]) q_face[i] = 0.0;
    expect_kkt(qp.J, q_face, mu[0], face, "chopped multipliers on the face");
}

TEST(CoupledSweepStart, ColumnDotInFourSumsEqualsTheSequentialSum)
{
    // Every length up to 13 (all tails) at an offset: small integers sum exactly in any order, so a
    // term left out or counted twice shows; random reals agree to rounding.
    std::mt19937 rng(31);
    std::uniform_int_distribution<int> small(-9, 9);
    std::uniform_real_distribution<double> real(-1.0, 1.0);
    std::vector<double> y(40);
    for (double& v : y) v = small(rng);
    for (int length = 0; length <= 13; ++length) {
        const int begin = 5;
        std::vector<int> inner(static_cast<size_t>(begin + length));
        std::vector<double> value(inner.size()), real_value(inner.size());
        for (size_t k = 0; k < inner.size(); ++k) {
            inner[k] = static_cast<int>(rng() % y.size());
            value[k] = small(rng);
            real_value[k] = real(rng);
        }
        double exact = 0.0, sequential = 0.0;
        for (int k = begin; k < begin + length; ++k) {
            exact += value[static_cast<size_t>(k)] * y[static_cast<size_t>(inner[static_cast<size_t>(k)])];
            sequential += real_value[static_cast<size_t>(k)] * y[static_cast<size_t>(inner[static_cast<size_t>(k)])];
        }
        EXPECT_EQ(cb::sparse_column_dot(begin, begin + length, inner.data(), value.data(), y.data()), exact)
            << "length " << length;
        EXPECT_NEAR(cb::sparse_column_dot(begin, begin + length, inner.data(), real_value.data(), y.data()), sequential,
                    1e-13 * (1.0 + std::abs(sequential)))
            << "length " << length;
    }
}
