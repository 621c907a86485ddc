// The scene size l of a problem without geometry (docs/accuracy.md "Length scale", issue 41):
// fixed before any solver runs from the problem's own solution, so that a nearly singular A that
// pushes the unconstrained minimiser away changes no verdict, and every `converged` run on a box
// problem (J = I, c = 0) has solved it, checked here outside the measure.
#include "harness/length_scale.hpp"
#include "harness/reference.hpp"
#include "harness/runner.hpp"
#include "problems/qpsnap.hpp"
#include "solvers/core/registry.hpp"
#include "solvers/measure/accuracy.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <random>
#include <unistd.h>

using namespace cb;
namespace fs = std::filesystem;

namespace {

/// A fresh reference cache for this test process.
std::string test_cache(const std::string& name)
{
    const fs::path dir = fs::temp_directory_path() / ("cb_test_length_scale_" + std::to_string(::getpid())) / name;
    fs::remove_all(dir);
    fs::create_directories(dir);
    return dir.string();
}

/// A box QP (J = I, c = 0, x0 = 0, n = 30) whose matrix A = I - (1 - eps) v v' (v: a unit ramp,
/// v_i ~ i - 14.5) has eigenvalue eps along v and 1 elsewhere. b = A x* - mu for a fixed KKT pair
/// (x* >= 0, mu >= 0, x*'mu = 0), so x* solves the QP for every eps, while the unconstrained
/// minimiser x* - A^-1 mu moves along v by (v'mu) / eps: eps 1 -> 1e-10 pushes it 4.9e8 times further.
Qp ramp_box(double eps, int n = 30)
{
    Vec v(n);
    for (int i = 0; i < n; ++i) v[i] = i - 0.5 * (n - 1);
    v.normalize();
    const Eigen::MatrixXd A = Eigen::MatrixXd::Identity(n, n) - (1.0 - eps) * v * v.transpose();
    Qp qp;
    qp.A = A.sparseView();
    Vec x_star = Vec::Zero(n), mu = Vec::Zero(n);
    for (int i = 0; i < n; ++i) {
        if (i % 3 == 0)
            mu[i] = 0.5 + 0.1 * (i % 7);  // held by its row
        else
            x_star[i] = 1.0 + 0.25 * (i % 5);  // free
    }
    qp.b = A * x_star - mu;
    qp.J.resize(n, n);
    qp.J.setIdentity();
    qp.c = Vec::Zero(n);
    qp.x0 = Vec::Zero(n);
    return qp;
}

/// A random SPD box problem: A = B'B + 0.1 I (n = 24), b with both signs, J = I, c = 0, x0 = 0.
Qp random_box(unsigned seed)
{
    const int n = 24;
    std::mt19937 rng(seed);
    std::normal_distribution<double> normal;
    Eigen::MatrixXd B(n, n);
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) B(i, j) = normal(rng);
    const Eigen::MatrixXd A = B.transpose() * B + 0.1 * Eigen::MatrixXd::Identity(n, n);
    Qp qp;
    qp.A = A.sparseView();
    qp.b.resize(n);
    for (int i = 0; i < n; ++i) qp.b[i] = 10.0 * normal(rng);
    qp.J.resize(n, n);
    qp.J.setIdentity();
    qp.c = Vec::Zero(n);
    qp.x0 = Vec::Zero(n);
    return qp;
}

/// |min(x, Ax - b)|_inf / |b|_inf: the box problem's own residual, computed without the measure.
/// It compares x with forces, so it depends on the units: `balanced` evaluates it in the length
/// unit where |x|_inf = |b|_inf (x -> kx, A -> A / k^2, b -> b / k; only x's entries change by
/// k^2 against g's), which is the given unit for the generated problems below and not for LMGC's
/// (x of 1e5 against b of 0.2).
double box_residual(const Qp& qp, const Vec& x, bool balanced = false)
{
    if (x.size() != qp.n()) return INFINITY;
    const Vec g = qp.A * x - qp.b;
    const double b_max = qp.b.lpNorm<Eigen::Infinity>(), x_max = x.lpNorm<Eigen::Infinity>();
    const double k2 = balanced && x_max > 0.0 ? b_max / x_max : 1.0;
    return (k2 * x).cwiseMin(g).lpNorm<Eigen::Infinity>() / b_max;
}

/// Every registered solver that runs without settings of its own.
std::vector<std::string> every_solver_without_settings()
{
    std::vector<std::string> names;
    for (const auto& name : builtin_registry().names())
        if (!builtin_registry().entry(name).needs_settings) names.push_back(name);
    return names;
}

/// Claims convergence at its start point: what a lazy solver does.
class StartPointSolver : public Solver {
public:
    explicit StartPointSolver(const nlohmann::json& settings) : m_common(SettingsReader(settings, "start").common()) {}
    std::string name() const override { return "start-point"; }
    nlohmann::json settings() const override { return m_common.to_json(); }
    SolverResult solve(const QpView& qp, const SolveContext&) override
    {
        SolverResult r;
        r.x = qp.x0;
        r.status = SolveStatus::CONVERGED;
        return r;
    }

private:
    CommonSettings m_common;
};

RunOutcome run_scaled(const Qp& qp, const std::string& solver)
{
    RunOptions options;
    options.record_history = false;
    if (solver == "start-point") {
        static const SolverRegistry registry = [] {
            SolverRegistry r;
            SolverEntry e;
            e.make = [](const nlohmann::json& s) { return std::make_unique<StartPointSolver>(s); };
            r.add("start-point", e);
            return r;
        }();
        return run_solver(registry, qp, solver, {{"tol", 1e-6}}, options, {}, SolveContext{});
    }
    return run_solver(qp, solver, {{"tol", 1e-6}, {"time_limit_s", 20}}, options);
}

}  // namespace

TEST(LengthScale, GivenThenSnapshotThenGeometryThenReference)
{
    const std::string cache = test_cache("order");
    Qp qp = ramp_box(1.0);
    fix_length_scale(qp, "p.qpsnap", "k1", GivenLength{2.5, "given"}, cache);
    EXPECT_EQ(qp.length.value, 2.5);
    EXPECT_EQ(qp.length.source, "given");
    EXPECT_FALSE(fs::exists(fs::path(cache) / "reference"));  // a given l costs no solve

    Qp snap = ramp_box(1.0);
    snap.meta["length_scale"] = 0.75;
    fix_length_scale(snap, "p.qpsnap", "k1", GivenLength{}, cache);
    EXPECT_EQ(snap.length.value, 0.75);
    EXPECT_EQ(snap.length.source, "snapshot");
    EXPECT_EQ(accuracy_scale(snap.view()).length, 0.75);
    EXPECT_EQ(accuracy_scale(snap.view()).length_source, "snapshot");

    // A start with geometry: nothing fixed, no reference computed, x0's extent as before.
    Qp geometry = ramp_box(1.0);
    for (Eigen::Index i = 0; i < geometry.n(); ++i) geometry.x0[i] = 0.1 * static_cast<double>(i);
    fix_length_scale(geometry, "g.qpsnap", "k2", GivenLength{}, cache);
    EXPECT_EQ(geometry.length.value, 0.0);
    EXPECT_FALSE(fs::exists(fs::path(cache) / "reference"));
    EXPECT_EQ(accuracy_scale(geometry.view()).length_source, "x0_extent");

    // No geometry: the extent of x* read as 3-D points. x*'s entries 1 mod 3 and 2 mod 3 are
    // 1 + 0.25 (i mod 5), ranging over [1, 2]; those 0 mod 3 are 0: l = 1.
    Qp free = ramp_box(1.0);
    fix_length_scale(free, "f.qpsnap", "k3", GivenLength{}, cache);
    EXPECT_EQ(free.length.source, "reference_extent");
    EXPECT_NEAR(free.length.value, 1.0, 1e-8);
    EXPECT_EQ(free.length.value, reference_solution(free, "k3", cache)["solution_extent"].get<double>());
    EXPECT_TRUE(reference_solution(free, "k3", cache)["cached"].get<bool>());  // computed once
}

TEST(LengthScale, BadValuesAreRefusedNamingTheField)
{
    Qp qp = ramp_box(1.0);
    qp.meta["length_scale"] = -1.0;
    try {
        fix_length_scale(qp, "p.qpsnap", "k", GivenLength{}, test_cache("bad"));
        FAIL() << "a negative meta.length_scale was accepted";
    } catch (const InputError& e) {
        EXPECT_STREQ(e.what(), "p.qpsnap: meta.length_scale: expected a finite number > 0, got -1.0");
    }
    for (const char* text : {"0", "-2", "nan", "inf", "1e999", "abc", ""}) {
        try {
            parse_length_scale("solve", text);
            FAIL() << "--length-scale " << text << " was accepted";
        } catch (const InputError& e) {
            EXPECT_EQ(std::string(e.what()),
                      std::string("solve: --length-scale: expected a finite number > 0, got '") + text + "'");
        }
    }
    EXPECT_EQ(parse_length_scale("solve", "0.25"), 0.25);
}

// Metamorphic: eps 1 -> 1e-10 pushes the unconstrained minimiser 4.9e8 times further along v
// while x* stays put. l (fixed from x*) must not change, nor the verdict of any solver whose own
// word is the same on both (pgs's dual matrix A^-1 has condition 1e10 on the second: its
// max_iterations there is the solver's), and a solver that returns its start point is never
// `converged`. Before issue 41, l was the minimiser's
// extent (1e8 times larger), so the start point x0 = 0 read e ~ 1e-8 there: `converged`.
TEST(LengthScale, NearlySingularAKeepsTheVerdicts)
{
    const std::string cache = test_cache("metamorphic");
    Qp near = ramp_box(1.0), far = ramp_box(1e-10);
    // The premise: the unconstrained minimiser moved about 1e8 times further.
    std::string kind;
    const Eigen::MatrixXd An = Eigen::MatrixXd(near.A), Af = Eigen::MatrixXd(far.A);
    const double reach_near = point_extent(Vec(An.ldlt().solve(near.b)), kind);
    const double reach_far = point_extent(Vec(Af.ldlt().solve(far.b)), kind);
    EXPECT_GT(reach_far / reach_near, 1e8);

    fix_length_scale(near, "near", qp_content_key(near), GivenLength{}, cache);
    fix_length_scale(far, "far", qp_content_key(far), GivenLength{}, cache);
    EXPECT_EQ(near.length.source, "reference_extent");
    EXPECT_EQ(far.length.source, "reference_extent");
    EXPECT_NEAR(far.length.value / near.length.value, 1.0, 1e-6);

    std::vector<std::string> solvers = every_solver_without_settings();
    solvers.push_back("start-point");
    int same_word = 0;
    for (const auto& solver : solvers) {
        SCOPED_TRACE(solver);
        const RunOutcome a = run_scaled(near, solver), b = run_scaled(far, solver);
        EXPECT_EQ(a.scale.length, near.length.value);
        EXPECT_EQ(b.scale.length, far.length.value);
        if (a.result.status == b.result.status) {
            ++same_word;
            EXPECT_EQ(a.status, b.status);
        }
        for (const RunOutcome* r : {&a, &b})
            if (r->status == "converged") {
                EXPECT_LE(box_residual(r == &a ? near : far, r->result.x), 100 * 1e-6);
            }
    }
    EXPECT_GE(same_word, 6);  // the relation was tested on real verdicts
    EXPECT_NE(run_scaled(near, "start-point").status, "converged");
    EXPECT_NE(run_scaled(far, "start-point").status, "converged");
}

// Every solver's `converged` run on a geometry-free box problem has solved it:
// |min(x, Ax - b)|_inf / |b|_inf <= 100 tol, computed here, not by the measure. The problems:
// the ramp boxes, random SPD boxes, and the normal block of an LMGC90 FCLIB problem
// (tests/data/lmgc_perio_normal.qpsnap, see tests/data/lmgc_perio_normal.README.md).
TEST(LengthScale, ConvergedOnABoxProblemMeansSolved)
{
    const std::string cache = test_cache("box");
    std::vector<std::pair<std::string, Qp>> problems = {{"ramp-1", ramp_box(1.0)},
                                                        {"ramp-1e-10", ramp_box(1e-10)},
                                                        {"random-1", random_box(1)},
                                                        {"random-2", random_box(2)}};
    problems.emplace_back("lmgc", read_qpsnap(std::string(CB_TEST_DATA_DIR) + "/lmgc_perio_normal.qpsnap"));
    std::vector<std::string> solvers = every_solver_without_settings();
    solvers.push_back("start-point");
    int converged = 0;
    for (auto& [name, qp] : problems) {
        SCOPED_TRACE(name);
        ASSERT_EQ(qp.J.nonZeros(), qp.n());  // J = I, c = 0, x0 = 0: a box problem without geometry
        ASSERT_EQ(qp.c.lpNorm<Eigen::Infinity>(), 0.0);
        fix_length_scale(qp, name, qp_content_key(qp), GivenLength{}, cache);
        // LMGC's W_NN is singular: no Cholesky factor, no active-set reference; the load
        // displacement stands in (3.33e4, the solution's extent being about 1.1e5; 2.69e8 before).
        EXPECT_EQ(qp.length.source, name == "lmgc" ? "load_displacement" : "reference_extent");
        for (const auto& solver : solvers) {
            SCOPED_TRACE(solver);
            const RunOutcome r = run_scaled(qp, solver);
            if (r.status != "converged") continue;
            ++converged;
            EXPECT_LE(box_residual(qp, r.result.x, true), 100 * 1e-6) << "e = " << r.accuracy.max();
            if (name != "lmgc") {
                EXPECT_LE(box_residual(qp, r.result.x), 100 * 1e-6) << "e = " << r.accuracy.max();
            }
        }
    }
    EXPECT_GT(converged, 10);  // the check ran on real verdicts
}
