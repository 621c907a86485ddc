// Metamorphic tests of the frictional accuracy error (docs/accuracy.md "e for Coulomb friction",
// issue 48), beside tests/solvers/test_accuracy_metamorphic.cpp: on a frictional snapshot and a
// point off its solution in every part (the friction part included), the maps
//   (a) A, b -> a A, a b                           (lambda, lambda_T -> a lambda, a lambda_T)
//   (b) contact i's three rows and offsets x s_i    (lambda_i, lambda_T,i -> / s_i)
//   (c) a rigid translation t: x0 -> x0 + t, b -> b + A t, c -> c + J t, cT -> cT + T t   (x -> x + t)
//   (d) a change of length unit k: x -> k x, A -> A / k^2, b -> b / k, c, cT -> k c, k cT (lambdas -> / k)
//   (e) another start: x0 -> x0 + t (the problem unchanged, the point too)
// leave every part unchanged (power-of-two factors: to 1e-9 relative; (c) and (e), where sums
// cancel, to tol / 10). And with mu = 0 the frictional e is today's e bit for bit.
#include "friction_test_qps.hpp"
#include "harness/runner.hpp"
#include "solvers/measure/accuracy.hpp"

#include <gtest/gtest.h>
#include <cmath>
#include <cstring>
#include <functional>
#include <string>
#include <vector>

namespace cb {
namespace {

constexpr double FRICTION_METAMORPHIC_TOL = 1e-6;

/// A frictional plane (mu cycling through 0.1 .. 0.9 and 0) and a point near its solution: the
/// frictionless solution perturbed, with tangential multipliers of a fixed pattern.
struct Probe {
    Qp qp;
    Vec x, lambda, lambda_t;
};

Probe probe()
{
    Probe p;
    p.qp = make_synthetic("plane", {{"nx", 3}, {"ny", 2}, {"nz", 3}}, 3);
    testing_qps::add_friction(p.qp, [](Eigen::Index i) { return 0.1 * static_cast<double>(i % 10); });
    RunOptions options;
    options.record_history = false;
    const RunOutcome ref = run_solver(p.qp, "active-set", {{"tol", 1e-10}}, options);
    const AccuracyScale s = accuracy_scale(p.qp.view());
    p.x = ref.result.x;
    p.lambda = ref.lambda_full;
    for (Eigen::Index j = 0; j < p.x.size(); ++j) p.x[j] += 1e-4 * s.length * std::sin(0.7 * static_cast<double>(j));
    for (Eigen::Index i = 0; i < p.lambda.size(); ++i)
        p.lambda[i] *= 1.0 + 0.25 * std::cos(1.3 * static_cast<double>(i));
    p.lambda_t.resize(2 * p.qp.m());
    for (Eigen::Index k = 0; k < p.lambda_t.size(); ++k)
        p.lambda_t[k] = 0.3 * p.lambda[k / 2] * std::sin(0.9 * static_cast<double>(k) + 0.2);
    return p;
}

struct MappedFrictionQp {
    std::string name;
    Qp qp;
    std::function<Vec(const Vec&)> map_x, map_lambda, map_lambda_t;
    bool exact = true;
};

std::vector<MappedFrictionQp> friction_maps_of(const Qp& qp)
{
    std::vector<MappedFrictionQp> maps;
    const auto same = [](const Vec& v) { return v; };
    const Eigen::Index m = qp.m(), n = qp.n();
    for (int e : {-26, 26}) {
        const double a = std::ldexp(1.0, e);
        Qp out = qp;
        out.A *= a;
        out.b *= a;
        const auto times_a = [a](const Vec& l) { return Vec(a * l); };
        maps.push_back({"(a) objective x 2^" + std::to_string(e), out, same, times_a, times_a, true});
    }
    {
        Vec s(m), s2(2 * m);
        for (Eigen::Index i = 0; i < m; ++i) s[i] = std::ldexp(1.0, static_cast<int>((7 * i) % 41) - 20);
        for (Eigen::Index k = 0; k < 2 * m; ++k) s2[k] = s[k / 2];
        Qp out = qp;
        out.J = s.asDiagonal() * qp.J;
        out.c = s.cwiseProduct(qp.c);
        out.friction.T = s2.asDiagonal() * qp.friction.T;
        out.friction.cT = s2.cwiseProduct(qp.friction.cT);
        maps.push_back({"(b) contacts x 2^-20..2^20", out, same, [s](const Vec& l) { return Vec(l.cwiseQuotient(s)); },
                        [s2](const Vec& l) { return Vec(l.cwiseQuotient(s2)); }, true});
    }
    for (int e : {-10, 10}) {
        const double k = std::ldexp(1.0, e);
        Qp out = qp;
        out.A /= k * k;
        out.b /= k;
        out.c *= k;
        out.x0 *= k;
        out.friction.cT *= k;
        const auto over_k = [k](const Vec& l) { return Vec(l / k); };
        maps.push_back({"(d) length unit x 2^" + std::to_string(e), out, [k](const Vec& x) { return Vec(k * x); },
                        over_k, over_k, true});
    }
    Vec t(n);
    for (Eigen::Index j = 0; j < n; ++j) t[j] = (j % 3 == 0) ? 1000.0 : (j % 3 == 1 ? -700.0 : 300.0);
    {
        Qp out = qp;
        out.x0 += t;
        out.b += qp.A * t;
        out.c += qp.J * t;
        out.friction.cT += qp.friction.T * t;
        maps.push_back({"(c) translation by 1.3 km", out, [t](const Vec& x) { return Vec(x + t); }, same, same, false});
    }
    {
        Qp out = qp;
        out.x0 += 1e-3 * t;  // the same problem from another start (same extent)
        maps.push_back({"(e) start moved by 1.3 m", out, same, same, same, false});
    }
    return maps;
}

void expect_same_friction_measure(const AccuracyParts& e, const AccuracyParts& f, bool exact, const std::string& what)
{
    const double parts_e[] = {e.stationarity, e.primal, e.dual, e.complementarity, e.gap, e.friction, e.max()};
    const double parts_f[] = {f.stationarity, f.primal, f.dual, f.complementarity, f.gap, f.friction, f.max()};
    const char* names[] = {"stationarity", "primal", "dual", "complementarity", "gap", "friction", "max"};
    for (int k = 0; k < 7; ++k) {
        const double bound = exact ? 1e-9 * std::abs(parts_e[k]) : FRICTION_METAMORPHIC_TOL / 10;
        EXPECT_NEAR(parts_f[k], parts_e[k], bound) << what << ": " << names[k];
    }
}

}  // namespace

TEST(AccuracyMetamorphicFriction, MeasureOfMappedPointsAgrees)
{
    const Probe p = probe();
    ASSERT_TRUE(p.qp.frictional());
    const AccuracyParts e = accuracy(p.qp.view(), accuracy_scale(p.qp.view()), p.x, p.lambda, &p.lambda_t);
    // Off the solution in the friction part too, so the agreement is not 0 = 0.
    ASSERT_TRUE(e.frictional);
    ASSERT_GT(e.friction, 1e-8);
    ASSERT_GT(e.stationarity, 1e-8);
    ASSERT_GT(e.gap, 1e-12);
    for (const MappedFrictionQp& mp : friction_maps_of(p.qp)) {
        const Vec lambda_t = mp.map_lambda_t(p.lambda_t);
        const AccuracyParts f =
            accuracy(mp.qp.view(), accuracy_scale(mp.qp.view()), mp.map_x(p.x), mp.map_lambda(p.lambda), &lambda_t);
        expect_same_friction_measure(e, f, mp.exact, mp.name);
    }
}

TEST(AccuracyMetamorphicFriction, MuZeroIsTodaysErrorBitForBit)
{
    const Probe p = probe();
    Qp zero = p.qp;
    zero.friction.mu.setZero();
    Qp plain = p.qp;
    plain.friction = Friction{};
    const AccuracyScale scale = accuracy_scale(plain.view());
    const Vec g = plain.A * p.x - plain.b;
    const AccuracyParts today = accuracy_from_gradient(plain.view(), scale, p.x, g, p.lambda);
    const Vec no_t = Vec::Zero(2 * p.qp.m());
    for (const Vec* lambda_t : {static_cast<const Vec*>(nullptr), &no_t}) {
        const AccuracyParts f =
            accuracy_from_gradient(zero.view(), accuracy_scale(zero.view()), p.x, g, p.lambda, lambda_t);
        const double a[] = {today.stationarity,    today.primal, today.dual,
                            today.complementarity, today.gap,    today.max()};
        const double b[] = {f.stationarity, f.primal, f.dual, f.complementarity, f.gap, f.max()};
        EXPECT_EQ(std::memcmp(a, b, sizeof a), 0) << (lambda_t ? "lambda_T = 0" : "no lambda_T");
        EXPECT_EQ(f.friction, 0.0);
        EXPECT_TRUE(f.frictional);       // the fields are there: the record shows friction 0
        EXPECT_FALSE(today.frictional);  // no fields: the record is today's
        EXPECT_FALSE(today.to_json().contains("friction"));
    }
}

TEST(AccuracyMetamorphicFriction, FrictionPartVanishesOnlyOnCoulombsLaw)
{
    // One vertex on the plane y >= 0 (A = I, b = force), mu = 0.5: three hand-solved states.
    // Sticking: b = (0.3, -1, 0) -> x = 0, lambda_N = 1, lambda_T along t holding the 0.3.
    Qp qp;
    qp.A = SpMat(3, 3);
    qp.A.setIdentity();
    qp.J = SpMat(1, 3);
    qp.J.insert(0, 1) = 1.0;
    qp.c = Vec::Zero(1);
    qp.x0 = Vec::Zero(3);
    qp.friction.mu = Vec::Constant(1, 0.5);
    qp.friction.T = SpMat(2, 3);
    qp.friction.T.insert(0, 0) = 1.0;  // t1 = x
    qp.friction.T.insert(1, 2) = 1.0;  // t2 = z
    qp.friction.cT = Vec::Zero(2);
    qp.length.value = 1.0;
    qp.length.source = "given";
    const Vec lambda = Vec::Constant(1, 1.0);
    qp.b = Eigen::Vector3d(0.3, -1.0, 0.0);
    Vec lt = Eigen::Vector2d(-0.3, 0.0);  // A x - b = J'lambda + T'lambda_T at x = 0
    EXPECT_EQ(accuracy(qp.view(), Vec::Zero(3), lambda, &lt).max(), 0.0);
    // The same force is not enough to stick with mu = 0.2: the friction part says so.
    qp.friction.mu[0] = 0.2;
    EXPECT_GT(accuracy(qp.view(), Vec::Zero(3), lambda, &lt).friction, 0.05);
    // Sliding with mu = 0.2: x = (0.1, 0, 0), friction -0.2 against the motion.
    lt = Eigen::Vector2d(-0.2, 0.0);
    const Vec x = Eigen::Vector3d(0.1, 0.0, 0.0);
    const AccuracyParts slide = accuracy(qp.view(), x, lambda, &lt);
    EXPECT_NEAR(slide.max(), 0.0, 1e-15);
    // Friction along the motion (wrong sign) violates the law.
    lt = Eigen::Vector2d(0.2, 0.0);
    EXPECT_GT(accuracy(qp.view(), x, lambda, &lt).friction, 0.05);
}

}  // namespace cb
