// Tests of the decoupled closed forms (ALGORITHMS.md §2) against their definitions, and of the
// power method against a dense eigensolver.
#include "problems/synthetic.hpp"
#include "solvers/mprgp/decouple.hpp"
#include "solvers/mprgp/mprgp_kernels.hpp"

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

namespace {

/// The bits of a double: equal bits mean the same value, sign of zero included.
std::uint64_t bits(double v)
{
    std::uint64_t b = 0;
    std::memcpy(&b, &v, sizeof b);
    return b;
}

using cb::Vec;

/// A decoupled J with rows of random sign/size over random vertices (some rows with 12 nnz),
/// c and x such that part of the rows are active, part violated, part slack.
struct KernelFixture {
    cb::SpMat J;
    Vec c, x, g, dinv;
    cb::DecoupledRows rows;
    std::vector<char> active;
};

KernelFixture make_fixture(std::uint64_t seed)
{
    std::mt19937_64 rng(seed);
    std::normal_distribution<double> normal(0.0, 1.0);
    const int vertices = 60, n = 3 * vertices;
    std::vector<int> perm(vertices);
    for (int i = 0; i < vertices; ++i) perm[i] = i;
    std::shuffle(perm.begin(), perm.end(), rng);
    std::vector<cb::Triplet> t;
    int row = 0, next = 0;
    while (next + 4 <= vertices && row < 14) {
        const int touched = (row % 3 == 0) ? 4 : 1;  // inter-body style rows touch 4 vertices
        for (int v = 0; v < touched; ++v, ++next)
            for (int d = 0; d < 3; ++d) t.emplace_back(row, 3 * perm[next] + d, normal(rng));
        ++row;
    }
    KernelFixture f;
    f.J.resize(row, n);
    f.J.setFromTriplets(t.begin(), t.end());
    f.x = Vec::NullaryExpr(n, [&]() { return normal(rng); });
    f.g = Vec::NullaryExpr(n, [&]() { return normal(rng); });
    f.dinv = Vec::NullaryExpr(n, [&]() { return 0.5 + std::abs(normal(rng)); });
    const Vec jx = f.J * f.x;
    f.c.resize(row);
    for (int i = 0; i < row; ++i)
        f.c[i] = jx[i] + (i % 3 == 0 ? 0.0 : (i % 3 == 1 ? -0.5 : 0.7));  // active / slack / violated
    f.rows = cb::make_decoupled_rows(f.J, f.dinv);
    // Put x on the feasible set first (the operators are defined at feasible points).
    cb::project_decoupled(f.J, f.c, f.rows, f.x, f.x);
    cb::active_rows(f.J, f.c, f.rows, f.x, f.active);
    return f;
}

TEST(MprgpKernels, FixtureIsDecoupledWithActiveRows)
{
    const KernelFixture f = make_fixture(1);
    EXPECT_TRUE(cb::is_decoupled(f.J));
    int active = 0;
    for (char a : f.active) active += a;
    EXPECT_GE(active, 8);  // the originally active and the violated (now projected) rows
    EXPECT_LT(active, f.J.rows());
}

TEST(MprgpKernels, ProjectionIsFeasibleAndOptimal)
{
    for (std::uint64_t seed : {1u, 2u, 3u}) {
        KernelFixture f = make_fixture(seed);
        std::mt19937_64 rng(seed + 100);
        std::normal_distribution<double> normal(0.0, 1.0);
        const Vec z = f.x + Vec::NullaryExpr(f.x.size(), [&]() { return normal(rng); });
        Vec p, lambda;
        cb::project_decoupled(f.J, f.c, f.rows, z, p, &lambda);
        const Vec slack = f.J * p - f.c;
        EXPECT_GE(slack.minCoeff(), -1e-12);
        // z - P(z) = -J' lambda with lambda >= 0 and lambda_i slack_i = 0: the normal cone.
        EXPECT_LE((z - p + f.J.transpose() * lambda).norm(), 1e-12);
        EXPECT_GE(lambda.minCoeff(), 0.0);
        EXPECT_LE(lambda.cwiseProduct(slack).cwiseAbs().maxCoeff(), 1e-12);
        // Variational inequality (z - P z)'(y - P z) <= 0 for feasible y (some projected points).
        for (int k = 0; k < 20; ++k) {
            Vec y = f.x + 3.0 * Vec::NullaryExpr(f.x.size(), [&]() { return normal(rng); });
            cb::project_decoupled(f.J, f.c, f.rows, y, y);
            EXPECT_LE((z - p).dot(y - p), 1e-10);
        }
    }
}

TEST(MprgpKernels, FreeAndChoppedGradientsMeetTheirDefinitions)
{
    for (std::uint64_t seed : {1u, 2u, 3u}) {
        const KernelFixture f = make_fixture(seed);
        Vec phi, beta;
        cb::free_gradient(f.J, f.rows, f.active, f.g, phi);
        cb::chopped_gradient(f.J, f.rows, f.active, f.g, beta);
        EXPECT_NEAR(phi.dot(beta), 0.0, 1e-12);
        EXPECT_GE(phi.dot(f.g), -1e-12);
        EXPECT_GE(beta.dot(f.g), -1e-12);
        const Vec jphi = f.J * phi, jbeta = f.J * beta;
        bool some_chopped = false;
        for (Eigen::Index i = 0; i < f.J.rows(); ++i) {
            if (!f.active[static_cast<size_t>(i)]) continue;
            EXPECT_NEAR(jphi[i], 0.0, 1e-12);  // J_A phi = 0
            EXPECT_LE(jbeta[i], 1e-12);        // -J_A beta >= 0: -beta moves into the set
            some_chopped = some_chopped || jbeta[i] < -1e-8;
        }
        EXPECT_TRUE(some_chopped || beta.norm() == 0.0);
        // phi is the orthogonal projection of g onto null(J_A): g - phi in range(J_A').
        std::vector<int> act;
        for (Eigen::Index i = 0; i < f.J.rows(); ++i)
            if (f.active[static_cast<size_t>(i)]) act.push_back(static_cast<int>(i));
        Eigen::MatrixXd JA(static_cast<Eigen::Index>(act.size()), f.J.cols());
        const Eigen::MatrixXd Jd = Eigen::MatrixXd(f.J);
        for (size_t r = 0; r < act.size(); ++r) JA.row(static_cast<Eigen::Index>(r)) = Jd.row(act[r]);
        const Vec mu = (JA * JA.transpose()).ldlt().solve(JA * f.g);
        EXPECT_LE((f.g - JA.transpose() * mu - phi).norm(), 1e-10);
        // beta solves min ||beta - (g - phi)|| s.t. J_A beta <= 0: KKT of eq. (17) with nu = -J_A beta-part.
        Vec lambda;
        cb::decoupled_multipliers(f.J, f.rows, f.active, f.g, lambda);
        EXPECT_LE((phi + beta - (f.g - f.J.transpose() * lambda)).norm(), 1e-12);
    }
}

TEST(MprgpKernels, ReducedFreeGradientMatchesItsDefinition)
{
    const KernelFixture f = make_fixture(4);
    Vec phi;
    cb::free_gradient(f.J, f.rows, f.active, f.g, phi);
    for (double alpha_bar : {1e-3, 0.1, 1.0, 10.0}) {
        Vec trial = f.x - alpha_bar * phi, projected;
        cb::project_decoupled(f.J, f.c, f.rows, trial, projected);
        const Vec phitilde = (f.x - projected) / alpha_bar;
        EXPECT_NEAR(cb::reduced_free_gradient_dot(f.J, f.c, f.rows, f.x, phi, alpha_bar), phitilde.dot(phi),
                    1e-10 * phi.squaredNorm());
        // phitilde'phi <= ||phi||^2 (the projection only shortens the step).
        EXPECT_LE(phitilde.dot(phi), phi.squaredNorm() * (1 + 1e-12));
    }
}

TEST(MprgpKernels, JacobiPreconditionerKeepsTheFace)
{
    for (std::uint64_t seed : {1u, 2u}) {
        const KernelFixture f = make_fixture(seed);
        Vec z;
        cb::jacobi_face_precondition(f.J, f.rows, f.active, f.dinv, f.g, z);
        const Vec jz = f.J * z;
        for (Eigen::Index i = 0; i < f.J.rows(); ++i)
            if (f.active[static_cast<size_t>(i)]) {
                EXPECT_NEAR(jz[i], 0.0, 1e-12);
            }
        // D-weighted projection: z minimises (z - D^-1 g)' D (z - D^-1 g) on null(J_A), so
        // D z - g lies in range(J_A'): it vanishes on every DOF outside active rows.
        const Vec resid = z.cwiseQuotient(f.dinv) - f.g;
        for (Eigen::Index j = 0; j < resid.size(); ++j) {
            bool in_active = false;
            for (Eigen::Index i = 0; i < f.J.rows(); ++i)
                if (f.active[static_cast<size_t>(i)] && f.J.coeff(i, j) != 0.0) in_active = true;
            if (!in_active) {
                EXPECT_NEAR(resid[j], 0.0, 1e-12);
            }
        }
        EXPECT_GT(z.dot(f.g), 0.0);  // a descent direction
    }
    // No rows: plain Jacobi.
    cb::SpMat empty(0, 6);
    const Vec dinv = Vec::LinSpaced(6, 1.0, 2.0), g = Vec::Ones(6);
    const cb::DecoupledRows rows = cb::make_decoupled_rows(empty, dinv);
    Vec z;
    cb::jacobi_face_precondition(empty, rows, {}, dinv, g, z);
    EXPECT_LE((z - dinv).norm(), 0.0);
}

TEST(MprgpKernels, PowerMethodEstimatesTheNormFromBelowAndWarmStartHelps)
{
    const cb::SpMat A_csr = cb::fem_like_matrix({3, 3, 3, 0.1, 1e6, 0.4, 1000.0, 0.01});
    const cb::AOperator A(A_csr);
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig{Eigen::MatrixXd(A_csr)};
    const double norm = eig.eigenvalues().maxCoeff();
    Vec v;
    const cb::PowerResult cold = cb::power_method(A, v, cb::PowerRule::POWER, 1000, 0.0, false, 1);
    EXPECT_LE(cold.estimate, norm * (1 + 1e-12));
    EXPECT_GE(cold.estimate, 0.9 * norm);
    EXPECT_FALSE(cold.warm);
    const cb::PowerResult warm = cb::power_method(A, v, cb::PowerRule::POWER, 1000, 0.0, true, 1);
    EXPECT_TRUE(warm.warm);
    EXPECT_LE(warm.products, 3);
    EXPECT_NEAR(warm.estimate, norm, 0.01 * norm);
    Vec u;
    const cb::PowerResult authors = cb::power_method(A, u, cb::PowerRule::AUTHORS, 1001, 1e-8, true, 1);
    EXPECT_FALSE(authors.warm);  // the authors' variant always starts cold
    EXPECT_NEAR(authors.estimate, norm, 1e-3 * norm);
    // Stopped by its rule (the unit vector moves by <= 1e-8 in a product; 376 products here), not
    // by the cap of 1001: one more product moves the returned vector by about the tolerance.
    EXPECT_LT(authors.products, 1001);
    EXPECT_GT(authors.products, 10);
    const Vec next = A_csr * u;
    EXPECT_LT((next / next.norm() - u).norm(), 1e-7);
    const cb::PowerResult capped = cb::power_method(A, u, cb::PowerRule::POWER, 2, 0.0, false, 1);
    EXPECT_EQ(capped.products, 2);
}

}  // namespace

// The accepted CG step's pass (AVX2 where the CPU has it) against the plain loop: x, g and phi to
// the bit and the same largest |g_j| w_j, on a length that leaves a tail, with zero weights (a face
// DOF's), signed zeros and entries whose product rounds.
TEST(MprgpKernels, CgStepPassEqualsThePlainLoopToTheBit)
{
    const Eigen::Index n = 1003;
    std::mt19937_64 rng(47);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    Vec p(n), ap(n), w(n), x(n), g(n);
    for (Eigen::Index j = 0; j < n; ++j) {
        p[j] = u(rng) * 1e3;
        ap[j] = u(rng) * 1e-2;
        w[j] = j % 5 == 0 ? 0.0 : std::abs(u(rng));
        x[j] = u(rng);
        g[j] = j % 11 == 0 ? -0.0 : u(rng) * 1e4;
    }
    const double alpha = 0.7390851332151607;
    // g - alpha ap = 0 exactly, weighted by inf: a NaN term, which std::max skips; at DOF 5 and in
    // the first lane of the last whole packet (996), where a NaN-propagating maximum would keep it.
    for (Eigen::Index j : {Eigen::Index{5}, Eigen::Index{996}}) {
        g[j] = alpha * ap[j];
        w[j] = std::numeric_limits<double>::infinity();
    }
    Vec x_plain = x, g_plain = g, phi_plain(n);
    double widest_plain = 0.0;
    for (Eigen::Index j = 0; j < n; ++j) {
        x_plain[j] -= alpha * p[j];
        g_plain[j] = g_plain[j] - alpha * ap[j];
        phi_plain[j] = g_plain[j];
        widest_plain = std::max(widest_plain, std::abs(g_plain[j]) * w[j]);
    }
    Vec phi(n);
    const double widest = cb::cg_step_pass(alpha, p, ap, w, x, g, phi);
    long differing = 0;
    for (Eigen::Index j = 0; j < n; ++j)
        differing += (x[j] != x_plain[j]) + (g[j] != g_plain[j]) + (phi[j] != phi_plain[j]) +
                     (std::signbit(g[j]) != std::signbit(g_plain[j]));
    EXPECT_EQ(differing, 0);
    EXPECT_EQ(widest, widest_plain);
    EXPECT_FALSE(std::isnan(widest));
    EXPECT_GT(widest, 0.0);
}

// The fused pair of dots is Eigen's two dots to the bit, on every size around the packets' edges
// (none, one packet, an odd packet after the pairs, a tail) and on sums that cancel.
TEST(MprgpKernels, TwoDotsEqualEigensDotsToTheBit)
{
    std::mt19937_64 rng(2047);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    long differing = 0, compared = 0;
    for (Eigen::Index n : {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 15, 16, 17, 1001, 1003, 4096}) {
        Vec a(n), b(n), c(n);
        for (Eigen::Index j = 0; j < n; ++j) {
            a[j] = u(rng) * (j % 7 == 0 ? 1e8 : 1.0);
            b[j] = u(rng) * (j % 3 == 0 ? 1e-6 : 1e4);
            c[j] = j % 13 == 0 ? -0.0 : u(rng);
        }
        double ab = 1.0, ac = 1.0;
        cb::two_dots(a, b, c, ab, ac);
        const double want_ab = a.dot(b), want_ac = a.dot(c);
        differing += bits(ab) != bits(want_ab);
        differing += bits(ac) != bits(want_ac);
        compared += 2;
    }
    EXPECT_EQ(differing, 0) << "of " << compared;
    Vec a = Vec::NullaryExpr(4096, [&] { return u(rng) * 1e8; });
    Vec b = Vec::NullaryExpr(4096, [&] { return u(rng); });
    double plain = 0.0;
    for (Eigen::Index j = 0; j < a.size(); ++j) plain += a[j] * b[j];
    double ab = 0.0, aa = 0.0;
    cb::two_dots(a, b, a, ab, aa);
    EXPECT_NE(ab, plain);  // so the comparison above can tell one order from another
    const double want_aa = a.dot(a);
    EXPECT_EQ(bits(aa), bits(want_aa));
}

// cg_update_pass against the plain loop it replaced in decoupled MPRGP's CG step: x, g, z and the
// four results to the bit, on sizes around the packet of four, rows on a fifth of the DOFs, and a
// DOF whose weighted gradient is 0 * inf = NaN (skipped by the maximum, as std::max skips it).
TEST(MprgpKernels, CgUpdatePassEqualsThePlainLoopToTheBit)
{
    std::mt19937_64 rng(4099);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    long differing = 0, compared = 0;
    for (Eigen::Index n : {0, 1, 3, 4, 5, 7, 8, 9, 17, 1001, 4099}) {
        const double alpha = n % 2 == 0 ? 1.0 : 0.37;
        Vec p(n), ap(n), dinv(n), w(n), x(n), g(n);
        std::vector<char> in_row(static_cast<size_t>(n));
        for (Eigen::Index j = 0; j < n; ++j) {
            p[j] = u(rng) * (j % 7 == 0 ? 1e6 : 1.0);
            ap[j] = u(rng) * (j % 3 == 0 ? 1e-5 : 1e3);
            dinv[j] = 0.5 + u(rng) * 0.25;
            w[j] = 1.0 + u(rng) * 0.5;
            x[j] = u(rng) * 10.0;
            g[j] = u(rng) * 1e2;
            in_row[static_cast<size_t>(j)] = static_cast<char>(rng() % 5 == 0);
        }
        if (n > 5) {  // g - alpha ap = 0 exactly at DOF 5, weighted by inf: a NaN term
            ap[5] = g[5] / alpha;
            g[5] = alpha * ap[5];
            w[5] = std::numeric_limits<double>::infinity();
            in_row[5] = 0;
        }
        Vec x1 = x, g1 = g, z1(n);
        const cb::CgUpdateSums got = cb::cg_update_pass(alpha, p, ap, dinv, w, in_row.data(), x1, g1, z1);
        Vec x2 = x, g2 = g, z2(n);
        double zg = 0.0, zap = 0.0, gg = 0.0, ginf = 0.0;
        for (Eigen::Index j = 0; j < n; ++j) {  // the loop decoupled MPRGP ran before
            x2[j] -= alpha * p[j];
            const double gj = g2[j] - alpha * ap[j];
            g2[j] = gj;
            const double zj = dinv[j] * gj;
            z2[j] = zj;
            if (!in_row[static_cast<size_t>(j)]) {
                zg += zj * gj;
                zap += zj * ap[j];
                ginf = std::max(ginf, std::abs(gj) * w[j]);
                gg += gj * gj;
            }
        }
        for (Eigen::Index j = 0; j < n; ++j)
            differing += (bits(x1[j]) != bits(x2[j])) + (bits(g1[j]) != bits(g2[j])) + (bits(z1[j]) != bits(z2[j]));
        differing += (bits(got.zg) != bits(zg)) + (bits(got.zap) != bits(zap)) + (bits(got.gg) != bits(gg)) +
                     (bits(got.ginf) != bits(ginf));
        compared += 3 * n + 4;
        EXPECT_FALSE(std::isnan(got.ginf)) << "n = " << n;
    }
    EXPECT_EQ(differing, 0) << "of " << compared;
}
