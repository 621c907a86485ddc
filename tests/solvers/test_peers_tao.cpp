// The PETSc TAO peers (solvers/peers/tao_*, compiled only when PETSc is found): tao-tron on bound
// rows against active-set and its refusals, the guard that ends TAOPDIPM's endless retries of a
// failing Newton step, and each child's own Open MPI session folder. A peer that is not built is
// skipped.
#include "problems/synthetic.hpp"
#include "solvers/core/registry.hpp"
#include "solvers/measure/accuracy.hpp"
#include "solvers/mprgp/mprgp_box.hpp"
#include "tests/solvers/ci_suite_cases.hpp"
#include "tiny_qps.hpp"

#include <gtest/gtest.h>
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <unistd.h>

namespace {

using cb::Qp;
using cb::SolverResult;
using cb::SolveStatus;
using cb::Vec;

bool built(const std::string& name) { return cb::builtin_registry().contains(name); }

SolverResult solve_peer(const std::string& name, const Qp& qp, const nlohmann::json& settings)
{
    return cb::builtin_registry().create(name, settings)->solve(qp.view(), cb::SolveContext{});
}

}  // namespace

// On bound rows TRON agrees with active-set (objective, feasibility, the common KKT test at 1e-8
// with the multipliers read off its gradient); on general rows it is not_applicable, naming the
// row, without starting PETSc (0 iterations, x = x0).
TEST(TaoTron, AgreesWithActiveSetOnBoundRowsAndRefusesOtherRows)
{
    if (!built("tao-tron")) GTEST_SKIP() << "tao-tron is not built";
    int solved = 0, refused = 0;
    for (const cb::test::CiCase& cc : cb::test::ci_cases()) {
        SCOPED_TRACE(cc.id);
        const Qp qp = cb::make_synthetic(cc.family, cc.params, cc.seed);
        const auto view = qp.view();
        const SolverResult r = solve_peer("tao-tron", qp, {{"tol", 1e-8}});
        if (!cb::is_bound_rows(qp.J)) {
            ++refused;
            EXPECT_EQ(r.status, SolveStatus::NOT_APPLICABLE) << r.message;
            EXPECT_EQ(r.message.rfind("tao-tron: row ", 0), 0u) << r.message;
            EXPECT_NE(r.message.find("nonzeros (bound rows only"), std::string::npos) << r.message;
            EXPECT_EQ(r.iterations, 0);
            EXPECT_EQ(r.x, qp.x0);
            continue;
        }
        ++solved;
        const SolverResult ref = solve_peer("active-set", qp, {{"tol", 1e-9}});
        ASSERT_EQ(ref.status, SolveStatus::CONVERGED) << ref.message;
        ASSERT_EQ(r.status, SolveStatus::CONVERGED) << r.message;
        ASSERT_EQ(r.lambda.size(), qp.m());
        const double f_ref = cb::objective(view, ref.x), f = cb::objective(view, r.x);
        EXPECT_LE(std::abs(f - f_ref), 1e-8 * std::max(1.0, std::abs(f_ref)));
        const Vec slack = qp.J * r.x - qp.c;
        EXPECT_GE(slack.minCoeff(), -1e-12 * std::max(1.0, qp.c.lpNorm<Eigen::Infinity>()));
        EXPECT_GE(r.lambda.minCoeff(), 0.0);
        const Vec g = qp.A * r.x - qp.b;
        EXPECT_TRUE(cb::accuracy_converged(view, cb::accuracy_scale(view), r.x, g, r.lambda, 1e-8));
        // stop=kkt: the harness's test, run as TAO's convergence test, ended the solve.
        EXPECT_EQ(r.info.value("tao_reason", ""), "CONVERGED_USER");
        EXPECT_TRUE(r.info.value("kkt_test_in_tao", false));
    }
    EXPECT_EQ(solved, 3);
    EXPECT_EQ(refused, 2);
}

// Contradictory bounds (x_0 >= 1 and x_0 <= 0) are infeasible, found before PETSc starts.
TEST(TaoTron, ContradictoryBoundsAreInfeasible)
{
    if (!built("tao-tron")) GTEST_SKIP() << "tao-tron is not built";
    Eigen::MatrixXd J(2, 2);
    J << 1, 0, -1, 0;
    const Qp qp = cb::testing_qps::dense_qp(2.0 * Eigen::MatrixXd::Identity(2, 2), Eigen::Vector2d(0, 2), J,
                                            Eigen::Vector2d(1, 0), Vec::Zero(2));
    const SolverResult r = solve_peer("tao-tron", qp, {});
    EXPECT_EQ(r.status, SolveStatus::INFEASIBLE) << r.message;
    EXPECT_EQ(r.message, "tao-tron: DOF 0 has lower bound 1 > upper bound 0");
}

// The hand-derived QP: x* = (1, 1), lambda* = 2 (tiny_qps.hpp), the multiplier read off the gradient.
TEST(TaoTron, TinyQpSolutionAndMultiplier)
{
    if (!built("tao-tron")) GTEST_SKIP() << "tao-tron is not built";
    const SolverResult r = solve_peer("tao-tron", cb::testing_qps::tiny_active_qp(), {{"tol", 1e-10}});
    ASSERT_EQ(r.status, SolveStatus::CONVERGED) << r.message;
    EXPECT_NEAR(r.x[0], 1.0, 1e-12);
    EXPECT_NEAR(r.x[1], 1.0, 1e-10);
    EXPECT_NEAR(r.lambda[0], 2.0, 1e-10);
}

// max_iterations maps onto TaoSetMaximumIterations (status max_iterations, TAO's reason kept), and
// time_limit_s ends the child process.
TEST(TaoTron, HonoursMaxIterationsAndTimeLimit)
{
    if (!built("tao-tron")) GTEST_SKIP() << "tao-tron is not built";
    const Qp qp = cb::make_synthetic("box", {{"nx", 4}, {"ny", 4}, {"nz", 4}}, 14);
    const SolverResult capped = solve_peer("tao-tron", qp, {{"max_iterations", 1}, {"tol", 1e-10}});
    EXPECT_EQ(capped.status, SolveStatus::MAX_ITERATIONS) << capped.message;
    EXPECT_EQ(capped.info.value("tao_reason", ""), "DIVERGED_MAXITS");
    EXPECT_EQ(capped.iterations, 1);
    const SolverResult timed = solve_peer("tao-tron", qp, {{"time_limit_s", 1e-9}});
    EXPECT_EQ(timed.status, SolveStatus::TIME_LIMIT) << timed.message;
    const std::string killed = "; the child process was killed";
    ASSERT_GE(timed.message.size(), killed.size());
    EXPECT_EQ(timed.message.substr(timed.message.size() - killed.size()), killed) << timed.message;
}

// The case that hung the metamorphic test (AccuracyMetamorphic.EverySolversConvergedHolds...): the
// coupled fixture with its objective scaled by 2^-26. TAOPDIPM's first Newton step fails
// (DIVERGED_LINEAR_SOLVE) and TAOPDIPM calls its SNES again from the same point without end; the
// guard ends it at iteration 0 with DIVERGED_USER, and the status says it did not converge.
TEST(TaoPdipm, EndlessNewtonRetriesAreEndedAndStalled)
{
    if (!built("tao-pdipm")) GTEST_SKIP() << "tao-pdipm is not built";
    Qp qp = cb::make_synthetic("coupled", {{"nx", 3}, {"ny", 2}, {"nz", 3}}, 5);
    const double a = std::ldexp(1.0, -26);
    qp.A *= a;
    qp.b *= a;
    const SolverResult r = solve_peer("tao-pdipm", qp, {{"tol", 1e-6}});
    EXPECT_EQ(r.status, SolveStatus::STALLED) << r.message;
    EXPECT_EQ(r.info.value("tao_reason", ""), "DIVERGED_USER");
    EXPECT_TRUE(r.info.value("tao_stuck", false));
    EXPECT_EQ(r.iterations, 0);
    EXPECT_NE(r.message.find("Newton step failed 50 times in a row at iteration 0"), std::string::npos) << r.message;
    // The same QP unscaled is solved (the guard does not fire on a run that advances).
    const SolverResult plain =
        solve_peer("tao-pdipm", cb::make_synthetic("coupled", {{"nx", 3}, {"ny", 2}, {"nz", 3}}, 5), {{"tol", 1e-6}});
    EXPECT_EQ(plain.status, SolveStatus::CONVERGED) << plain.message;
    EXPECT_FALSE(plain.info.value("tao_stuck", true));
}

// TAO's own tolerances are absolute: with the objective times 2^-26 TAO's residuals are below
// any gatol early. Under stop=kkt the harness's scale-free test decides when the solve ends, so
// the scaled problem is solved to tol, to the same point (x is unchanged by the scaling).
TEST(TaoPdipm, StopsOnTheHarnessTestWhateverTheObjectiveScale)
{
    if (!built("tao-pdipm")) GTEST_SKIP() << "tao-pdipm is not built";
    const Qp qp = cb::make_synthetic("plane", {{"nx", 3}, {"ny", 2}, {"nz", 3}}, 3);
    Qp scaled = qp;
    const double a = std::ldexp(1.0, -26);
    scaled.A *= a;
    scaled.b *= a;
    const SolverResult r = solve_peer("tao-pdipm", qp, {{"tol", 1e-6}});
    const SolverResult rs = solve_peer("tao-pdipm", scaled, {{"tol", 1e-6}});
    for (const SolverResult* p : {&r, &rs}) {
        EXPECT_EQ(p->status, SolveStatus::CONVERGED) << p->message;
        EXPECT_EQ(p->info.value("tao_reason", ""), "CONVERGED_USER") << p->message;
    }
    const SolverResult ref = solve_peer("active-set", qp, {{"tol", 1e-10}});
    const double scale = (ref.x - qp.x0).lpNorm<Eigen::Infinity>();
    EXPECT_LE((rs.x - ref.x).lpNorm<Eigen::Infinity>(), 1e-4 * scale);
}

// Each TAO child starts Open MPI in a session folder of its own (a fresh folder under TMPDIR,
// removed afterwards), not in the one shared folder TMPDIR/ompi.<host>.<uid> where two children
// starting at once raced ("mkdir ... File exists", MPI_Init_thread aborts). The shared name is
// taken here by a plain file, which makes Open MPI's mkdir fail every time it is used: both peers
// still converge, and nothing but that file is left in TMPDIR.
TEST(TaoPeers, StartOpenMpiInTheirOwnSessionFolder)
{
    if (!built("tao-pdipm") || !built("tao-tron")) GTEST_SKIP() << "the TAO peers are not built";
    namespace fs = std::filesystem;
    std::string pattern = (fs::temp_directory_path() / "cb-test-tao-tmp-XXXXXX").string();
    ASSERT_NE(::mkdtemp(pattern.data()), nullptr);
    const fs::path folder = pattern;
    char host[256] = {};
    ASSERT_EQ(::gethostname(host, sizeof host - 1), 0);
    std::string short_host = host;  // Open MPI drops the domain
    short_host = short_host.substr(0, short_host.find('.'));
    const fs::path shared = folder / ("ompi." + short_host + "." + std::to_string(::getuid()));
    std::ofstream(shared) << "a file where Open MPI's shared session folder would go\n";
    const char* old = std::getenv("TMPDIR");
    const std::string saved = old ? old : "";
    ::setenv("TMPDIR", folder.c_str(), 1);
    const Qp qp = cb::make_synthetic("box", {{"nx", 3}, {"ny", 3}, {"nz", 3}}, 2);
    const SolverResult pdipm = solve_peer("tao-pdipm", qp, {{"tol", 1e-6}});
    const SolverResult tron = solve_peer("tao-tron", qp, {{"tol", 1e-6}});
    if (old)
        ::setenv("TMPDIR", saved.c_str(), 1);
    else
        ::unsetenv("TMPDIR");
    EXPECT_EQ(pdipm.status, SolveStatus::CONVERGED) << pdipm.message;
    EXPECT_EQ(tron.status, SolveStatus::CONVERGED) << tron.message;
    std::vector<std::string> left;
    for (const auto& entry : fs::directory_iterator(folder)) left.push_back(entry.path().filename().string());
    EXPECT_EQ(left, std::vector<std::string>{shared.filename().string()});
    fs::remove_all(folder);
}
