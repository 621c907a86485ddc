// Issue 45: the Tresca set (solvers/mprgp/tresca_set.hpp) against brute force, and the MPRGP-based
// frictional solvers (solvers/friction/mprgp_tresca.hpp): mprgp-tresca-fp at mu = 0 takes mprgp-box's iterates
// on (W_NN, q_N) in one Tresca solve; on a random SPD frictional problem it reaches FCLIB's error
// 1e-8; what it does with a W that is not symmetric or not semidefinite; mprgp+ica-friction; nsgs's
// start vector; and both on the real local files of tests/data/fclib.
#include "problems/fclib_io.hpp"
#include "solvers/friction/friction_nsgs.hpp"
#include "solvers/friction/mprgp_tresca.hpp"
#include "solvers/measure/friction_error.hpp"
#include "solvers/mprgp/mprgp_box.hpp"
#include "solvers/mprgp/tresca_set.hpp"
#include "tests/harness/cli_test_util.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <filesystem>
#include <random>

namespace {

using cb::TrescaSet;
using cb::Vec;
namespace fs = std::filesystem;
constexpr double PI = 3.14159265358979323846;

Vec random_vector(std::mt19937& rng, Eigen::Index n, double half_width)
{
    std::uniform_real_distribution<double> u(-half_width, half_width);
    Vec v(n);
    for (Eigen::Index k = 0; k < n; ++k) v[k] = u(rng);
    return v;
}

/// A frictional local problem W = H M^-1 H' (H random 3m x dofs, dofs > 3m: W SPD), q pushing the
/// contacts in (q_n < 0), every contact's mu the same.
cb::FrictionLocal random_problem(Eigen::Index contacts, Eigen::Index dofs, double mu, unsigned seed)
{
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-1.0, 1.0), mass(0.5, 2.0);
    Eigen::MatrixXd H(3 * contacts, dofs);
    for (Eigen::Index i = 0; i < H.rows(); ++i)
        for (Eigen::Index j = 0; j < dofs; ++j) H(i, j) = u(rng);
    Vec minv(dofs);
    for (Eigen::Index j = 0; j < dofs; ++j) minv[j] = 1.0 / mass(rng);
    const Eigen::MatrixXd W = H * minv.asDiagonal() * H.transpose();
    cb::FrictionLocal p;
    p.W = W.sparseView();
    p.q = random_vector(rng, 3 * contacts, 1.0);
    for (Eigen::Index i = 0; i < contacts; ++i) p.q[3 * i] = -0.2 - std::abs(p.q[3 * i]);
    p.mu = Vec::Constant(contacts, mu);
    p.name = "random";
    return p;
}

/// The inner MPRGP iterates (normal components only) as a monitor sees them.
class NormalIterates : public cb::Monitor {
public:
    explicit NormalIterates(int stride) : m_stride(stride) {}
    bool on_iteration(const cb::IterationInfo& info) override
    {
        Vec normal(info.x->size() / m_stride);
        for (Eigen::Index i = 0; i < normal.size(); ++i) normal[i] = (*info.x)[m_stride * i];
        iterates.push_back(normal);
        return true;
    }
    std::vector<Vec> iterates;

private:
    int m_stride;
};

// --- the set against brute force ---

TEST(TrescaSet, ProjectionIsTheNearestPointOfAGrid)
{
    std::mt19937 rng(3);
    const TrescaSet set((Vec(3) << 1.0, 0.5, 0.0).finished());
    for (int trial = 0; trial < 6; ++trial) {
        const Vec x = random_vector(rng, set.size(), 3.0);
        Vec p = x;
        set.project(p);
        EXPECT_TRUE(set.contains(p));
        for (Eigen::Index i = 0; i < set.contacts(); ++i) {
            EXPECT_EQ(p[3 * i], std::max(x[3 * i], 0.0));  // the half-line's nearest point
            const double s = set.slip(i);
            const double d_proj = std::hypot(p[3 * i + 1] - x[3 * i + 1], p[3 * i + 2] - x[3 * i + 2]);
            double d_best = std::hypot(x[3 * i + 1], x[3 * i + 2]);  // the centre
            const int radii = 100, angles = 2000;
            for (int a = 0; a < radii; ++a)
                for (int b = 0; b < angles; ++b) {
                    const double rho = s * (a + 1) / radii, th = 2.0 * PI * b / angles;
                    d_best = std::min(d_best,
                                      std::hypot(rho * std::cos(th) - x[3 * i + 1], rho * std::sin(th) - x[3 * i + 2]));
                }
            EXPECT_LE(d_proj, d_best + 1e-12) << "contact " << i;
            EXPECT_NEAR(d_proj, d_best, s * (1.0 / radii + 2.0 * PI / angles) + 1e-15) << "contact " << i;
        }
    }
}

TEST(TrescaSet, FeasibleStepIsTheLargestStepOfABisection)
{
    std::mt19937 rng(5);
    const TrescaSet set((Vec(3) << 1.0, 0.25, 2.0).finished());
    int bounded = 0;
    for (int trial = 0; trial < 40; ++trial) {
        Vec x = random_vector(rng, set.size(), 1.0);
        set.project(x);
        const Vec p = random_vector(rng, set.size(), 1.0);
        const double step = set.feasible_step(x, p);
        if (!std::isfinite(step)) continue;
        ++bounded;
        EXPECT_GE(step, 0.0);
        // Brute force: bisection on "x - a p in the set" between 0 and a far step.
        double lo = 0.0, hi = 1e3;
        for (int k = 0; k < 200; ++k) {
            const double mid = 0.5 * (lo + hi);
            (set.contains(x - mid * p) ? lo : hi) = mid;
        }
        EXPECT_NEAR(step, lo, 1e-9 * (1.0 + lo)) << "trial " << trial;
    }
    EXPECT_GT(bounded, 30);
}

TEST(TrescaSet, FreePlusChoppedIsTheProjectedGradientOfADifferenceQuotient)
{
    // -(phi + beta) is the steepest feasible descent: (x - P(x - t g)) / t -> phi + beta as t -> 0.
    std::mt19937 rng(9);
    TrescaSet set((Vec(4) << 1.0, 0.5, 0.0, 2.0).finished());
    int on_circle = 0, on_bound = 0;
    for (int trial = 0; trial < 60; ++trial) {
        Vec x = random_vector(rng, set.size(), 2.0);
        if (trial % 2 == 0) {  // put some blocks exactly on their faces
            x[0] = 0.0;
            x[4] = 3.0;
            x[5] = 4.0;
        }
        set.project(x);
        const Vec g = random_vector(rng, set.size(), 1.0);
        set.classify(x);
        Vec phi, beta;
        set.gradients(g, phi, beta);
        for (Eigen::Index i = 0; i < set.contacts(); ++i) {
            on_bound += x[3 * i] == 0.0;
            on_circle += set.slip(i) > 0.0 && std::hypot(x[3 * i + 1], x[3 * i + 2]) >= set.slip(i) * (1 - 1e-12);
        }
        const double t = 1e-7;
        Vec y = x - t * g;
        set.project(y);
        const Vec quotient = (x - y) / t;
        EXPECT_LE((quotient - (phi + beta)).cwiseAbs().maxCoeff(), 1e-5) << "trial " << trial;
        // The reduced free gradient: (x - P(x - a phi)) / a dotted with phi.
        const double a = 0.3;
        Vec z = x - a * phi;
        set.project(z);
        EXPECT_NEAR(set.reduced_free_gradient_dot(x, phi, a), (x - z).dot(phi) / a, 1e-12);
    }
    EXPECT_GT(on_circle, 20);
    EXPECT_GT(on_bound, 20);
}

// --- mprgp-tresca-fp ---

TEST(MprgpTrescaFp, AtMuZeroOneTrescaSolveWithMprgpBoxsIteratesOnTheNormalBlock)
{
    const cb::FrictionLocal p = random_problem(12, 60, 0.0, 21);
    NormalIterates ours(3), box(1);
    cb::MprgpTrescaSettings s;
    s.monitor = &ours;
    const cb::MprgpTrescaRun fp = cb::mprgp_tresca_fp(p, s);
    EXPECT_EQ(fp.run.status, "converged") << fp.run.note;
    EXPECT_EQ(fp.outer, 1);
    EXPECT_LE(fp.run.error, 1e-8);

    // mprgp-box on min 1/2 x'W_NN x + q_N'x, x >= 0, with the same power-method tolerance.
    const Eigen::Index m = p.contacts();
    cb::Qp qp;
    Eigen::MatrixXd wnn(m, m);
    for (Eigen::Index i = 0; i < m; ++i)
        for (Eigen::Index j = 0; j < m; ++j) wnn(i, j) = p.W.coeff(3 * i, 3 * j);
    qp.A = wnn.sparseView();
    qp.b = Vec(m);
    for (Eigen::Index i = 0; i < m; ++i) qp.b[i] = -p.q[3 * i];
    qp.J = cb::SpMat(m, m);
    qp.J.setIdentity();
    qp.c = Vec::Zero(m);
    qp.x0 = Vec::Zero(m);
    cb::MprgpBoxSettings bs;
    bs.common.stop = cb::StopRule::NATIVE;
    bs.common.tol = s.power_tol;  // mprgp-box's power method stops on the solve's tol
    cb::SolveContext context;
    context.monitor = &box;
    const cb::SolverResult r = cb::MprgpBoxSolver(bs).solve(qp.view(), context);
    ASSERT_EQ(r.status, cb::SolveStatus::CONVERGED) << r.message;
    ASSERT_GT(ours.iterates.size(), 5u);
    const size_t common = std::min(ours.iterates.size(), box.iterates.size());
    EXPECT_GE(common + 2, std::max(ours.iterates.size(), box.iterates.size()));  // same path, other stop
    for (size_t k = 0; k < common; ++k)
        EXPECT_LE((ours.iterates[k] - box.iterates[k]).norm(), 1e-12 * (1.0 + box.iterates[k].norm()))
            << "iterate " << k;
}

TEST(MprgpTrescaFp, ReachesTheFclibErrorOnARandomSpdFrictionalProblem)
{
    for (double mu : {0.1, 0.3, 0.8}) {
        const cb::FrictionLocal p = random_problem(20, 100, mu, 31);
        cb::MprgpTrescaSettings s;  // tol 1e-8
        const cb::MprgpTrescaRun fp = cb::mprgp_tresca_fp(p, s);
        EXPECT_EQ(fp.run.status, "converged") << "mu " << mu << ": " << fp.run.note;
        EXPECT_LE(fp.run.error, 1e-8) << "mu " << mu;
        EXPECT_EQ(fp.run.error, cb::fclib_relative_error(p, fp.run.r));  // the harness's number
        EXPECT_GT(fp.outer, 1) << "mu " << mu;                           // friction needs the fixed point
        EXPECT_FALSE(fp.symmetrised);
        // An independent solver on the same problem: nsgs reaches the same tolerance; the two
        // solutions agree where Coulomb's solution is unique (W SPD, small mu).
        const cb::FrictionRun nsgs = cb::friction_nsgs(p, {});
        ASSERT_EQ(nsgs.status, "converged");
        if (mu <= 0.1) {
            EXPECT_LE((nsgs.r - fp.run.r).norm(), 1e-6 * nsgs.r.norm()) << "mu " << mu;
        }
    }
}

TEST(MprgpTrescaFp, ANonSymmetricWIsSplitAndItsSkewPartLagged)
{
    cb::FrictionLocal p = random_problem(10, 50, 0.3, 41);
    Eigen::MatrixXd w(p.W);
    w(0, 3) += 0.05 * w(0, 0);  // a normal row sees a neighbour more than the neighbour sees it
    w(4, 1) -= 0.05 * w(0, 0);
    p.W = w.sparseView();
    // Default: the skew part at the outer iterate in q, so the fixed point is the given problem's.
    const cb::MprgpTrescaRun lag = cb::mprgp_tresca_fp(p, {});
    EXPECT_TRUE(lag.symmetrised);
    EXPECT_EQ(lag.run.status, "converged") << lag.run.note;
    EXPECT_LE(lag.run.error, 1e-8);
    EXPECT_EQ(lag.run.error, cb::fclib_relative_error(p, lag.run.r));
    EXPECT_NE(lag.run.note.find("the Tresca QPs use (W + W')/2 with the skew part (W - W')/2 r at the outer "
                                "iterate in q"),
              std::string::npos)
        << lag.run.note;
    // The skew part dropped: (W + W')/2's problem, which is not the given one; never `converged`.
    cb::MprgpTrescaSettings drop;
    drop.lag_skew = false;
    const cb::MprgpTrescaRun fp = cb::mprgp_tresca_fp(p, drop);
    EXPECT_NE(fp.run.note.find("the Tresca QPs use (W + W')/2 (skew part dropped); the error is on the given W"),
              std::string::npos)
        << fp.run.note;
    EXPECT_EQ(fp.run.error, cb::fclib_relative_error(p, fp.run.r));
    EXPECT_GT(fp.run.error, 1e-8);
    EXPECT_NE(fp.run.status, "converged");
    EXPECT_NE(fp.run.note.find("; FCLIB error on (W + W')/2: "), std::string::npos);
}

TEST(MprgpTrescaFp, AnIndefiniteWIsRefused)
{
    cb::FrictionLocal p = random_problem(4, 20, 0.3, 51);
    Eigen::MatrixXd w(p.W);
    w(0, 3) = w(3, 0) = 2.0 * std::sqrt(w(0, 0) * w(3, 3));  // a 2x2 minor with a negative eigenvalue
    p.W = w.sparseView();
    const cb::MprgpTrescaRun fp = cb::mprgp_tresca_fp(p, {});
    EXPECT_EQ(fp.run.status, "not_applicable");
    EXPECT_EQ(fp.run.note, "0 Tresca solves; W is not positive semidefinite (no Cholesky factor of W + 1e-10 "
                           "max|W_jj| I): the Tresca dual is not a convex QP");
    EXPECT_EQ(fp.run.iterations, 0);
}

// --- nsgs's start and mprgp+ica-friction ---

TEST(FrictionNsgsStart, StartsFromTheGivenReactionAndRefusesAWrongOne)
{
    const cb::FrictionLocal p = random_problem(8, 40, 0.3, 61);
    const cb::FrictionRun cold = cb::friction_nsgs(p, {});
    ASSERT_EQ(cold.status, "converged");
    cb::FrictionNsgsSettings warm;
    warm.start = &cold.r;
    const cb::FrictionRun again = cb::friction_nsgs(p, warm);
    EXPECT_EQ(again.status, "converged");
    EXPECT_EQ(again.iterations, 0);  // already at the tolerance
    EXPECT_EQ(again.r, cold.r);
    const Vec short_start = Vec::Zero(5);
    warm.start = &short_start;
    try {
        cb::friction_nsgs(p, warm);
        ADD_FAILURE() << "a start of 5 numbers was taken";
    } catch (const cb::InputError& e) {
        EXPECT_STREQ(e.what(), "random: nsgs start: needs 24 finite numbers (3 per contact)");
    }
}

TEST(MprgpIcaFriction, ReachesTheFclibErrorFromMprgpsNormalReactions)
{
    const cb::FrictionLocal p = random_problem(20, 100, 0.3, 71);
    const cb::FrictionRun run = cb::mprgp_ica_friction(p, {});
    EXPECT_EQ(run.solver, "mprgp+ica-friction");
    EXPECT_EQ(run.status, "converged") << run.note;
    EXPECT_LE(run.error, 1e-8);
    EXPECT_EQ(run.note.rfind("mprgp-box on W_NN: converged, ", 0), 0u) << run.note;
}

// --- the real local files ---

const fs::path DATA = fs::path(CB_TEST_DATA_DIR) / "fclib";
const fs::path CAPSULES = DATA / "Capsules-i125-1213.hdf5";
const fs::path LMGC = DATA / "LMGC_100_PR_PerioBox-i00361-60-03000.hdf5";

TEST(MprgpTrescaFclib, ConvergesOnBothFilesAndStallsOnCapsulesWithoutItsSkewPart)
{
    if (cb::fclib_version().empty()) GTEST_SKIP() << "FCLIB import not built (libfclib-dev missing)";
    const cb::FrictionLocal lmgc = cb::read_fclib_local_friction(LMGC.string());
    const cb::MprgpTrescaRun ok = cb::mprgp_tresca_fp(lmgc, {});
    EXPECT_EQ(ok.run.status, "converged") << ok.run.note;
    EXPECT_LE(ok.run.error, 1e-8);
    // Capsules' W is not symmetric (3.4e-4): with its skew part lagged the fixed point converges;
    // dropped, it solves (W + W')/2's problem and stops when the FCLIB error on the given W no
    // longer falls (measured 2.556e-5).
    const cb::FrictionLocal capsules = cb::read_fclib_local_friction(CAPSULES.string());
    const cb::MprgpTrescaRun lag = cb::mprgp_tresca_fp(capsules, {});
    EXPECT_TRUE(lag.symmetrised);
    EXPECT_NEAR(lag.asymmetry, 3.42e-4, 0.01e-4);
    EXPECT_EQ(lag.run.status, "converged") << lag.run.note;
    EXPECT_LE(lag.run.error, 1e-8);
    cb::MprgpTrescaSettings drop;
    drop.lag_skew = false;
    const cb::MprgpTrescaRun stuck = cb::mprgp_tresca_fp(capsules, drop);
    EXPECT_EQ(stuck.run.status, "stalled") << stuck.run.note;
    EXPECT_NEAR(stuck.run.error, 2.556e-5, 0.01e-5) << stuck.run.note;
}

TEST(MprgpIcaFrictionFclib, ConvergesOnBothFiles)
{
    if (cb::fclib_version().empty()) GTEST_SKIP() << "FCLIB import not built (libfclib-dev missing)";
    for (const fs::path& file : {CAPSULES, LMGC}) {
        const cb::FrictionLocal p = cb::read_fclib_local_friction(file.string());
        const cb::FrictionRun run = cb::mprgp_ica_friction(p, {});
        EXPECT_EQ(run.status, "converged") << file << ": " << run.note;
        EXPECT_LE(run.error, 1e-8) << file;
    }
}

TEST(MprgpTrescaFclib, FrictionSolveRunsBothByName)
{
    if (cb::fclib_version().empty()) GTEST_SKIP() << "FCLIB import not built (libfclib-dev missing)";
    const fs::path dir = cb::test::make_test_work_dir("mprgp_tresca_cli");
    const cb::test::Output o =
        cb::test::run_captured(cb::test::contactbench_binary() + " friction-solve '" + LMGC.string() +
                                   "' --solver mprgp-tresca-fp --solver mprgp+ica-friction --tol 1e-6 --json '" +
                                   (dir / "r.json").string() + "'",
                               dir);
    ASSERT_EQ(o.status, 0) << o.err;
    const nlohmann::json j = nlohmann::json::parse(cb::test::slurp(dir / "r.json"));
    ASSERT_EQ(j["runs"].size(), 2u);
    for (size_t k = 0; k < 2; ++k) {
        EXPECT_EQ(j["runs"][k]["solver"], k == 0 ? "mprgp-tresca-fp" : "mprgp+ica-friction");
        EXPECT_EQ(j["runs"][k]["status"], "converged");
        EXPECT_LE(j["runs"][k]["fclib_error"].get<double>(), 1e-6);
    }
    EXPECT_NE(j["runs"][0]["note"].get<std::string>().find(" Tresca solves, setup "), std::string::npos);
}

}  // namespace
