// run_solver: the harness-side measurements (KKT recomputed, status confirmation, history
// stride, nonfinite and monotone detection, repeat, decoupling) on toy solvers with
// hand-derived solutions.
#include "harness/history.hpp"
#include "harness/runner.hpp"
#include "problems/synthetic.hpp"
#include "solvers/decouple.hpp"
#include "solvers/registry.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

using namespace cb;

namespace {

/// min 1/2 x'Dx - b'x s.t. x >= c with D = diag(d): x*_i = max(b_i/d_i, c_i),
/// lambda*_i = d_i x*_i - b_i.
Qp diagonal_qp()
{
    Qp qp;
    const int n = 6;
    Vec d(n), b(n), c(n);
    d << 1, 2, 3, 4, 5, 6;
    b << 1, -2, 3, -4, 5, -6;
    c << 0, 0, 0, 0, 0, 0;
    std::vector<Triplet> t;
    for (int i = 0; i < n; ++i) t.emplace_back(i, i, d[i]);
    qp.A.resize(n, n);
    qp.A.setFromTriplets(t.begin(), t.end());
    qp.J.resize(n, n);
    qp.J.setIdentity();
    qp.b = b;
    qp.c = c;
    qp.x0 = Vec::Constant(n, -1.0);  // infeasible start
    return qp;
}

/// Damped projected Jacobi: x <- max(c, x - (Dx - b) / (2 d)); halves the distance to x* each
/// step. Options make it misbehave on purpose: "lie" (claims convergence at once), "nan"
/// (a NaN iterate), "climb" (feasible iterates with increasing objective), "calls" (extra
/// monitor calls for the stride test).
class ToySolver : public Solver {
public:
    explicit ToySolver(const nlohmann::json& settings)
    {
        SettingsReader reader(settings, "toy");
        m_common = reader.common();
        m_mode = reader.choice("mode", "honest", {"honest", "lie", "nan", "climb"});
        reader.finish();
    }
    std::string name() const override { return "toy"; }
    nlohmann::json settings() const override
    {
        nlohmann::json s = m_common.to_json();
        s["mode"] = m_mode;
        return s;
    }
    SolverResult solve(const QpView& qp, const SolveContext& context) override
    {
        Stopwatch watch;
        watch.start();
        SolverResult r;
        const KktScale scale = kkt_scale(qp);
        const Vec d = qp.A.diagonal();
        Vec x = qp.x0;
        if (m_mode == "lie") {
            r.x = x;
            r.status = SolveStatus::CONVERGED;
            r.criterion = "kkt";
            r.solve_s = watch.seconds();
            return r;
        }
        long it = 0;
        for (; it < m_common.max_iterations; ++it) {
            Vec g = qp.A * x - qp.b;
            ++r.counters.a_products;
            if (m_mode == "climb") {
                // Feasible and moving away from the minimiser: objective increases.
                x = qp.c + Vec::Constant(x.size(), 0.1 * (it + 1));
            } else {
                x = (x - g.cwiseQuotient(2.0 * d)).cwiseMax(qp.c);
            }
            if (m_mode == "nan" && it == 3) x[0] = std::numeric_limits<double>::quiet_NaN();
            if (m_mode == "nan" && it == 4) x[0] = 0.0;
            g = qp.A * x - qp.b;
            const Vec lambda = fit_multipliers(qp, x, g);
            IterationInfo info;
            info.iteration = it + 1;
            info.step = StepKind::OUTER;
            info.x = &x;
            info.native_residual = g.norm();
            info.counters = &r.counters;
            notify_monitor(context, watch, info);
            if (m_mode == "honest" && kkt_converged(qp, x, g, lambda, scale, m_common.tol)) {
                ++it;
                r.status = SolveStatus::CONVERGED;
                r.criterion = "kkt";
                break;
            }
        }
        if (r.status == SolveStatus::NOT_RUN) r.status = SolveStatus::MAX_ITERATIONS;
        r.iterations = it;
        r.counters.iterations = it;
        r.x = x;
        r.lambda = fit_multipliers(qp, x, qp.A * x - qp.b);
        r.lambda_fitted = true;
        r.solve_s = watch.seconds();
        return r;
    }

private:
    CommonSettings m_common;
    std::string m_mode;
};

const SolverRegistry& toy_registry()
{
    static const SolverRegistry registry = [] {
        SolverRegistry r;
        r.add("toy", {[](const nlohmann::json& s) { return std::make_unique<ToySolver>(s); }, "test solver", {}});
        return r;
    }();
    return registry;
}

RunOutcome run_toy(const nlohmann::json& settings, RunOptions options = {})
{
    return run_solver(toy_registry(), diagonal_qp(), "toy", settings, options, {{"id", "diag"}}, SolveContext{});
}

} // namespace

TEST(Runner, HonestSolverMatchesHandSolution)
{
    const RunOutcome run = run_toy({{"tol", 1e-10}});
    ASSERT_EQ(run.result.status, SolveStatus::CONVERGED);
    // x* = max(b/d, 0) = (1, 0, 1, 0, 1, 0); lambda* = d x* - b = (0, 2, 0, 4, 0, 6).
    const Vec expected = (Vec(6) << 1, 0, 1, 0, 1, 0).finished();
    EXPECT_LT((run.result.x - expected).lpNorm<Eigen::Infinity>(), 1e-9);
    EXPECT_TRUE(run.status_confirmed);
    EXPECT_LE(run.kkt_relative.max(), 1e-10 * (1 + 1e-9));
    // F(x*) = sum over the free coordinates of -b_i^2 / (2 d_i) = -(1/2 + 9/6 + 25/10) = -4.5.
    EXPECT_NEAR(run.objective, -4.5, 1e-9);
    EXPECT_EQ(run.violation, 0.0);
    EXPECT_FALSE(run.nonfinite);
    EXPECT_TRUE(run.monotone);
    EXPECT_EQ(run.record["status"], "converged");
    EXPECT_EQ(run.record["snapshot"]["id"], "diag");
    EXPECT_EQ(run.record["snapshot"]["n"], 6);
    EXPECT_EQ(run.record["decouple"]["applied"], false);
    EXPECT_TRUE(run.record["lambda_fitted"].get<bool>());
}

TEST(Runner, RecordHasEverySchemaKey)
{
    const RunOutcome run = run_toy({{"tol", 1e-8}});
    for (const char* key : {"solver", "label", "settings", "snapshot", "decouple", "status", "criterion", "message",
                            "iterations", "objective", "kkt", "kkt_relative", "violation", "native_residual",
                            "lambda_fitted", "nonfinite", "monotone", "status_confirmed", "tol", "counters", "time",
                            "info", "history", "provenance"})
        EXPECT_TRUE(run.record.contains(key)) << key;
    for (const char* key : {"stationarity", "primal", "dual", "complementarity", "max"}) {
        EXPECT_TRUE(run.record["kkt"].contains(key)) << key;
        EXPECT_TRUE(run.record["kkt_relative"].contains(key)) << key;
    }
    for (const char* key : {"setup_s", "solve_s", "total_s", "repeat"}) EXPECT_TRUE(run.record["time"].contains(key)) << key;
    for (const char* key : {"git_commit", "git_dirty", "build_type", "compiler", "cpu", "cores", "date", "eigen",
                            "suitesparse", "blas", "hostname"})
        EXPECT_TRUE(run.record["provenance"].contains(key)) << key;
    for (const char* key : {"order", "seed", "rows_before", "rows_after", "applied"})
        EXPECT_TRUE(run.record["decouple"].contains(key)) << key;
    const auto& columns = run.record["history"]["columns"];
    EXPECT_EQ(columns, nlohmann::json(HistoryMonitor::columns()));
    EXPECT_EQ(columns.size(), 13u);
    for (const auto& row : run.record["history"]["rows"]) EXPECT_EQ(row.size(), columns.size());
    EXPECT_DOUBLE_EQ(run.record["tol"].get<double>(), 1e-8);
}

TEST(Runner, HistoryKktMatchesFinalAndDecreases)
{
    const RunOutcome run = run_toy({{"tol", 1e-12}});
    const auto& rows = run.record["history"]["rows"];
    ASSERT_GE(rows.size(), 10u);
    // Each damped Jacobi step halves the error on the free coordinates: kkt_rel falls.
    const double first = rows[1][9].get<double>(), last = rows.back()[9].get<double>();
    EXPECT_LT(last, first * 1e-6);
    EXPECT_NEAR(last, run.kkt_relative.max(), 1e-15 + 1e-9 * run.kkt_relative.max());
    EXPECT_EQ(rows.back()[0].get<long>(), run.result.iterations);
    EXPECT_EQ(rows[0][3], "outer");
}

TEST(Runner, LyingSolverIsNotConfirmed)
{
    const RunOutcome run = run_toy({{"mode", "lie"}});
    EXPECT_EQ(run.result.status, SolveStatus::CONVERGED);
    EXPECT_FALSE(run.status_confirmed);
    EXPECT_EQ(run.record["status_confirmed"], false);
    // lambda came from the harness's fit because the solver returned none.
    EXPECT_TRUE(run.record["lambda_fitted"].get<bool>());
    EXPECT_NEAR(run.kkt_relative.max(), 1.0, 1e-9);  // measured at x0: the reference point
}

TEST(Runner, StrideKeepsHistoryUnderMaxWithFirstAndLast)
{
    RunOptions options;
    options.history_max = 16;
    const RunOutcome run = run_toy({{"mode", "climb"}, {"max_iterations", 1000}}, options);
    const auto& rows = run.record["history"]["rows"];
    EXPECT_LE(rows.size(), 16u);
    EXPECT_GE(rows.size(), 8u);
    EXPECT_EQ(rows.front()[0].get<long>(), 1);       // first monitor call (iteration 1)
    EXPECT_EQ(rows.back()[0].get<long>(), 1000);     // the returned point
    EXPECT_EQ(run.record["history"]["stride"].get<long>(), 128);  // 1000 calls into 15 rows
    // Recorded iterations are on the stride: call index = iteration - 1.
    for (size_t i = 0; i + 1 < rows.size(); ++i) EXPECT_EQ((rows[i][0].get<long>() - 1) % 128, 0);
}

TEST(Runner, DetectsNonfiniteAndNonMonotone)
{
    const RunOutcome nan_run = run_toy({{"mode", "nan"}, {"max_iterations", 20}});
    EXPECT_TRUE(nan_run.nonfinite);
    EXPECT_TRUE(nan_run.record["nonfinite"].get<bool>());
    const RunOutcome honest = run_toy({{"max_iterations", 20}});
    EXPECT_FALSE(honest.nonfinite);
    EXPECT_TRUE(honest.monotone);
    const RunOutcome climb = run_toy({{"mode", "climb"}, {"max_iterations", 5}});
    EXPECT_FALSE(climb.monotone);
    EXPECT_EQ(climb.result.status, SolveStatus::MAX_ITERATIONS);
    EXPECT_TRUE(climb.status_confirmed);  // not claimed, nothing to confirm
}

TEST(Runner, RepeatReportsMedianAndSamples)
{
    RunOptions options;
    options.repeat = 3;
    const RunOutcome run = run_toy({{"tol", 1e-8}}, options);
    EXPECT_EQ(run.record["time"]["repeat"], 3);
    ASSERT_EQ(run.record["time"]["samples_total_s"].size(), 3u);
    std::vector<double> s = run.record["time"]["samples_total_s"].get<std::vector<double>>();
    std::sort(s.begin(), s.end());
    EXPECT_DOUBLE_EQ(run.record["time"]["total_s"].get<double>(), s[1]);
}

TEST(Runner, TimeLimitOverrideReachesSolverSettings)
{
    RunOptions options;
    options.time_limit_s = 7.5;
    const RunOutcome run = run_toy({}, options);
    EXPECT_DOUBLE_EQ(run.record["settings"]["time_limit_s"].get<double>(), 7.5);
}

TEST(Runner, BadInputNamesTheProblem)
{
    try {
        run_toy({{"no_such_key", 1}});
        FAIL() << "expected InputError";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("no_such_key"), std::string::npos) << e.what();
    }
    try {
        run_solver(toy_registry(), diagonal_qp(), "nope", {}, RunOptions{}, {}, SolveContext{});
        FAIL() << "expected InputError";
    } catch (const InputError& e) {
        EXPECT_EQ(std::string(e.what()), "solver 'nope' is not registered; known: toy");
    }
    RunOptions bad;
    bad.decouple = "sideways";
    EXPECT_THROW(run_solver(toy_registry(), diagonal_qp(), "toy", {}, bad, {}, SolveContext{}), InputError);
}

TEST(Runner, DecouplesCoupledRowsForMprgp)
{
    if (!builtin_registry().contains("mprgp")) GTEST_SKIP() << "mprgp not registered";
    const Qp qp = make_synthetic("coupled", {{"nx", 3}, {"ny", 2}, {"nz", 3}}, 5);
    ASSERT_GT(qp.m(), 0);
    RunOptions options;
    options.record_history = false;
    const RunOutcome run = run_solver(qp, "mprgp", {{"tol", 1e-6}}, options);
    const auto& d = run.record["decouple"];
    ASSERT_FALSE(is_decoupled(qp.J));  // the family shares vertices between rows
    {
        EXPECT_TRUE(d["applied"].get<bool>());
        EXPECT_LT(d["rows_after"].get<long>(), d["rows_before"].get<long>());
        EXPECT_EQ(d["order"], "authors");
        // lambda on the original rows: the kept rows carry the solver's multipliers, the rest 0.
        ASSERT_EQ(run.lambda_full.size(), qp.m());
        ASSERT_EQ(static_cast<long>(run.kept_rows.size()), d["rows_after"].get<long>());
        std::vector<bool> kept(static_cast<size_t>(qp.m()), false);
        for (int r : run.kept_rows) kept[static_cast<size_t>(r)] = true;
        for (Eigen::Index i = 0; i < qp.m(); ++i)
            if (!kept[static_cast<size_t>(i)]) {
                EXPECT_EQ(run.lambda_full[i], 0.0);
            }
        // J' lambda_full on the original J equals J_kept' lambda: the stationarity is the same.
        const Vec g = qp.A * run.result.x - qp.b;
        const KktResiduals full = kkt_residuals_from_gradient(qp.view(), run.result.x, g, run.lambda_full);
        EXPECT_NEAR(full.stationarity, run.kkt.stationarity, 1e-12 * std::max(1.0, run.kkt.stationarity));
        EXPECT_TRUE(run.record.contains("violation_original"));
    }
    EXPECT_EQ(d["rows_before"].get<long>(), qp.m());
    options.decouple = "none";
    const RunOutcome plain = run_solver(qp, "cg", {{"tol", 1e-6}}, options);
    EXPECT_FALSE(plain.record["decouple"]["applied"].get<bool>());
}
