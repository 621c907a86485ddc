// run_solver: the harness-side measurements (accuracy recomputed, the run's status, history
// stride, nonfinite and monotone detection, repeat, decoupling) on toy solvers with
// hand-derived solutions.
#include "harness/history.hpp"
#include "harness/runner.hpp"
#include "problems/synthetic.hpp"
#include "solvers/core/registry.hpp"
#include "solvers/mprgp/decouple.hpp"

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
    t.reserve(n);
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
        m_mode = reader.choice("mode", "honest", {"honest", "lie", "nan", "inf", "climb"});
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
        const AccuracyScale scale = accuracy_scale(qp);
        const Vec d = qp.A.diagonal();
        Vec x = qp.x0;
        if (m_mode == "lie") {
            r.x = x;
            r.status = SolveStatus::CONVERGED;
            r.criterion = StopCriterion::ACCURACY;
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
            if (m_mode == "inf" && it == 3) x[x.size() - 1] = -std::numeric_limits<double>::infinity();
            if (m_mode == "nan" && it == 4) x[0] = 0.0;
            if (m_mode == "inf" && it == 4) x[x.size() - 1] = 0.0;
            g = qp.A * x - qp.b;
            const Vec lambda = fit_multipliers(qp, scale, x, g);
            IterationInfo info;
            info.iteration = it + 1;
            info.step = StepKind::OUTER;
            info.x = &x;
            info.native_residual = g.norm();
            info.counters = &r.counters;
            notify_monitor(context, watch, info);
            if (m_mode == "honest" && accuracy_converged(qp, scale, x, g, lambda, m_common.tol)) {
                ++it;
                r.status = SolveStatus::CONVERGED;
                r.criterion = StopCriterion::ACCURACY;
                break;
            }
        }
        if (r.status == SolveStatus::NOT_RUN) r.status = SolveStatus::MAX_ITERATIONS;
        r.iterations = it;
        r.counters.iterations = it;
        r.x = x;
        r.lambda = fit_multipliers(qp, accuracy_scale(qp), x, qp.A * x - qp.b);
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
        r.add("toy",
              {[](const nlohmann::json& s) { return std::make_unique<ToySolver>(s); }, "test solver", {}, "any J", ""});
        return r;
    }();
    return registry;
}

RunOutcome run_toy(const nlohmann::json& settings, const RunOptions& options = {})
{
    return run_solver(toy_registry(), diagonal_qp(), "toy", settings, options, {{"id", "diag"}}, SolveContext{});
}

}  // namespace

TEST(Runner, HonestSolverMatchesHandSolution)
{
    const RunOutcome run = run_toy({{"tol", 1e-10}});
    ASSERT_EQ(run.result.status, SolveStatus::CONVERGED);
    // x* = max(b/d, 0) = (1, 0, 1, 0, 1, 0); lambda* = d x* - b = (0, 2, 0, 4, 0, 6).
    const Vec expected = (Vec(6) << 1, 0, 1, 0, 1, 0).finished();
    EXPECT_LT((run.result.x - expected).lpNorm<Eigen::Infinity>(), 1e-9);
    EXPECT_TRUE(run.status_confirmed);
    EXPECT_LE(run.accuracy.max(), 1e-10 * (1 + 1e-9));
    EXPECT_EQ(run.status, "converged");
    EXPECT_EQ(run.m_solved, 6);
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
    for (const char* key : {"solver",           "label",         "settings",          "snapshot",
                            "decouple",         "status",        "criterion",         "message",
                            "iterations",       "objective",     "accuracy",          "violation",
                            "native_residual",  "lambda_fitted", "nonfinite",         "monotone",
                            "status_confirmed", "tol",           "counters",          "time",
                            "memory",           "info",          "history",           "provenance",
                            "solver_status",    "m_solved",      "length_scale",      "length_scale_source",
                            "stiffness_scale",  "accuracy_tol",  "violation_original"})
        EXPECT_TRUE(run.record.contains(key)) << key;
    for (const char* key : {"stationarity", "primal", "dual", "complementarity", "gap", "max"})
        EXPECT_TRUE(run.record["accuracy"].contains(key)) << key;
    // One name for the accuracy error: the old alias is no longer written (harness/record_schema.hpp).
    EXPECT_FALSE(run.record.contains("kkt_relative"));
    // x0 = -1 everywhere has no extent: l falls back on the extent of x_u = b / d =
    // (1, -1, 1, -1, 1, -1), i.e. of the points (1, -1, 1) and (-1, 1, -1): 2.
    EXPECT_EQ(run.record["length_scale_source"], "unconstrained_extent");
    EXPECT_DOUBLE_EQ(run.record["length_scale"].get<double>(), 2.0);
    EXPECT_DOUBLE_EQ(run.record["stiffness_scale"].get<double>(), 3.5);  // mean of 1..6
    EXPECT_FALSE(run.record.contains("accuracy_solved"));                // the problem was not changed
    for (const char* key : {"setup_s", "solve_s", "total_s", "repeat"})
        EXPECT_TRUE(run.record["time"].contains(key)) << key;
    // Peak memory beside time: this process's (reset at the run's start), a child's, their sum.
    const auto& memory = run.record["memory"];
    for (const char* key : {"peak_rss_mb", "process_peak_rss_mb", "children_peak_rss_mb", "peak_reset"})
        EXPECT_TRUE(memory.contains(key)) << key;
    EXPECT_GT(memory["process_peak_rss_mb"].get<double>(), 1.0);  // a gtest binary holds more than 1 MiB
    EXPECT_DOUBLE_EQ(memory["peak_rss_mb"].get<double>(),
                     memory["process_peak_rss_mb"].get<double>() + memory["children_peak_rss_mb"].get<double>());
    for (const char* key : {"git_commit", "git_dirty", "build_type", "compiler", "cpu", "cores", "date", "eigen",
                            "suitesparse", "blas", "hostname"})
        EXPECT_TRUE(run.record["provenance"].contains(key)) << key;
    for (const char* key : {"order", "seed", "rows_before", "rows_after", "applied"})
        EXPECT_TRUE(run.record["decouple"].contains(key)) << key;
    const auto& columns = run.record["history"]["columns"];
    EXPECT_EQ(columns, nlohmann::json(HistoryMonitor::columns()));
    EXPECT_EQ(columns.size(), 15u);
    for (const auto& row : run.record["history"]["rows"]) EXPECT_EQ(row.size(), columns.size());
    // The work unit (docs/work.md): the toy solver does nothing but A-products, so its work is
    // its A-product count, in the record and along the history.
    EXPECT_EQ(columns[13], "work");
    EXPECT_EQ(columns[14], "solve_time_s");
    EXPECT_EQ(run.record["counters"]["work_flops"].get<double>(), 0.0);
    EXPECT_EQ(run.record["counters"]["work"].get<double>(), run.record["counters"]["a_products"].get<double>());
    for (const auto& row : run.record["history"]["rows"]) EXPECT_EQ(row[13].get<double>(), row[2].get<double>());
    EXPECT_DOUBLE_EQ(run.record["tol"].get<double>(), 1e-8);
}

TEST(Runner, HistoryKktMatchesFinalAndDecreases)
{
    const RunOutcome run = run_toy({{"tol", 1e-12}});
    const auto& rows = run.record["history"]["rows"];
    ASSERT_GE(rows.size(), 10u);
    // Each damped Jacobi step halves the error on the free coordinates: the accuracy error e falls.
    ASSERT_EQ(run.record["history"]["columns"][9], "accuracy");
    const double first = rows[1][9].get<double>(), last = rows.back()[9].get<double>();
    EXPECT_LT(last, first * 1e-6);
    EXPECT_NEAR(last, run.accuracy.max(), 1e-15 + 1e-9 * run.accuracy.max());
    EXPECT_EQ(rows.back()[0].get<long>(), run.result.iterations);
    EXPECT_EQ(rows[0][3], "outer");
}

TEST(Runner, LyingSolverIsNotConfirmed)
{
    const RunOutcome run = run_toy({{"mode", "lie"}});
    EXPECT_EQ(run.result.status, SolveStatus::CONVERGED);
    EXPECT_FALSE(run.status_confirmed);
    EXPECT_EQ(run.status, "unconfirmed");
    EXPECT_EQ(run.record["status"], "unconfirmed");
    EXPECT_EQ(run.record["solver_status"], "converged");
    EXPECT_EQ(run.record["status_confirmed"], false);
    // lambda came from the harness's fit because the solver returned none.
    EXPECT_TRUE(run.record["lambda_fitted"].get<bool>());
    // At x0 = -1 (l = 2): the fit gives lambda = g = d x0 - b = (-2, 0, -6, 0, -10, 0); every row
    // penetrates by 1 (primal 1/2), pulls with lambda / d = 2 (dual 2/2 = 1), complementarity
    // min(2, 1) / 2 = 1/2, gap (2 + 6 + 10) * 1 / (d_ref l^2 = 3.5 * 4) = 18/14.
    // (The fit's Tikhonov term, 1e-12 of the diagonal, shows in the last digits.)
    EXPECT_NEAR(run.accuracy.primal, 0.5, 1e-9);
    EXPECT_NEAR(run.accuracy.dual, 1.0, 1e-9);
    EXPECT_NEAR(run.accuracy.complementarity, 0.5, 1e-9);
    EXPECT_NEAR(run.accuracy.gap, 18.0 / 14.0, 1e-9);
    EXPECT_NEAR(run.accuracy.max(), 18.0 / 14.0, 1e-9);
}

TEST(Runner, StrideKeepsHistoryUnderMaxWithFirstAndLast)
{
    RunOptions options;
    options.history_max = 16;
    const RunOutcome run = run_toy({{"mode", "climb"}, {"max_iterations", 1000}}, options);
    const auto& rows = run.record["history"]["rows"];
    EXPECT_LE(rows.size(), 16u);
    EXPECT_GE(rows.size(), 8u);
    EXPECT_EQ(rows.front()[0].get<long>(), 1);                    // first monitor call (iteration 1)
    EXPECT_EQ(rows.back()[0].get<long>(), 1000);                  // the returned point
    EXPECT_EQ(run.record["history"]["stride"].get<long>(), 128);  // 1000 calls into 15 rows
    // Recorded iterations are on the stride: call index = iteration - 1.
    for (size_t i = 0; i + 1 < rows.size(); ++i) EXPECT_EQ((rows[i][0].get<long>() - 1) % 128, 0);
}

TEST(Runner, DetectsNonfiniteAndNonMonotone)
{
    const RunOutcome nan_run = run_toy({{"mode", "nan"}, {"max_iterations", 20}});
    EXPECT_TRUE(nan_run.nonfinite);
    EXPECT_TRUE(nan_run.record["nonfinite"].get<bool>());
    // An infinite entry for one iteration only, in the last place: seen by the per-iteration check.
    const RunOutcome inf_run = run_toy({{"mode", "inf"}, {"max_iterations", 20}});
    EXPECT_TRUE(inf_run.nonfinite);
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
        // The run is measured on the ORIGINAL rows; the solved (decoupled) QP's error stays beside.
        ASSERT_EQ(run.lambda_full.size(), qp.m());
        ASSERT_EQ(static_cast<long>(run.kept_rows.size()), d["rows_after"].get<long>());
        EXPECT_EQ(run.m_solved, d["rows_after"].get<long>());
        EXPECT_EQ(run.record["m_solved"], d["rows_after"]);
        EXPECT_EQ(run.record["solved_problem"], "decoupled");
        ASSERT_TRUE(run.record.contains("accuracy_solved"));
        const Vec g = qp.A * run.result.x - qp.b;
        const AccuracyParts full =
            accuracy_from_gradient(qp.view(), accuracy_scale(qp.view()), run.result.x, g, run.lambda_full);
        EXPECT_DOUBLE_EQ(full.max(), run.accuracy.max());
        EXPECT_DOUBLE_EQ(run.record["violation_original"].get<double>(), max_violation(qp.view(), run.result.x));
        // Its status says on which problem tol was met.
        ASSERT_EQ(run.result.status, SolveStatus::CONVERGED) << run.result.message;
        EXPECT_LE(run.accuracy_solved.max(), 1e-6 * (1 + 1e-9));
        if (run.accuracy.max() <= 1e-6) {
            EXPECT_EQ(run.status, "converged");
        } else {
            EXPECT_EQ(run.status, "solved_relaxation");
        }
    }
    EXPECT_EQ(d["rows_before"].get<long>(), qp.m());
    options.decouple = "none";
    const RunOutcome plain = run_solver(qp, "cg", {{"tol", 1e-6}}, options);
    EXPECT_FALSE(plain.record["decouple"]["applied"].get<bool>());
}

namespace {

/// The monitor's verdict on a given sequence of iterates.
bool monotone_over(const Qp& qp, const std::vector<Vec>& iterates)
{
    HistoryMonitor monitor(qp.view(), accuracy_scale(qp.view()), 100);
    long it = 0;
    for (const Vec& x : iterates) {
        IterationInfo info;
        info.iteration = ++it;
        info.step = StepKind::OUTER;
        info.x = &x;
        monitor.on_iteration(info);
    }
    return monitor.monotone();
}

}  // namespace

TEST(HistoryMonitor, MonotonicityIsJudgedOnChangesFromTheStartNotAbsoluteObjectives)
{
    // The diagonal QP moved by T = 1e6 along every axis (x0 + T, b + A T, c + T): the solution
    // moves by T and every objective difference is unchanged, but |F| grows to ~1e13, so a
    // slack relative to |F| (the former check: 1e-12 |F| = 10) hid an increase of 5e-3.
    Qp qp = diagonal_qp();
    const Vec t = Vec::Constant(qp.n(), 1e6);
    qp.b += qp.A * t;
    qp.c += t;
    qp.x0 += t;
    Vec solution(6);
    solution << 1, 0, 1, 0, 1, 0;
    solution += t;
    Vec up = solution;
    up[0] += 0.1;  // free coordinate (d_0 = 1): F rises by 0.005
    EXPECT_FALSE(monotone_over(qp, {solution, up}));
    // Decreases of the same size are not flagged.
    Vec half = solution;
    half[0] += 0.05;
    EXPECT_TRUE(monotone_over(qp, {up, half, solution}));
    // And untranslated, the same steps get the same verdicts.
    const Qp plain = diagonal_qp();
    Vec s0(6), u0(6), h0(6);
    s0 << 1, 0, 1, 0, 1, 0;
    u0 = s0;
    u0[0] += 0.1;
    h0 = s0;
    h0[0] += 0.05;
    EXPECT_FALSE(monotone_over(plain, {s0, u0}));
    EXPECT_TRUE(monotone_over(plain, {u0, h0, s0}));
}

TEST(HistoryMonitor, WantsOnlyTheIteratesOnItsStride)
{
    // history_max 4: the stride doubles once the rows would exceed it, and the monitor then asks
    // for the iterate (pgs forms x for it) only on calls it records.
    const Qp qp = diagonal_qp();
    const QpView view = qp.view();
    HistoryMonitor monitor(view, accuracy_scale(view), 4);
    const Vec x = qp.x0;
    std::vector<long> wanted;
    for (long call = 0; call < 16; ++call) {
        if (monitor.wants_iterate()) wanted.push_back(call);
        IterationInfo info;
        info.iteration = call;
        info.step = StepKind::OUTER;
        info.x = monitor.wants_iterate() ? &x : nullptr;
        monitor.on_iteration(info);
    }
    EXPECT_EQ(wanted, (std::vector<long>{0, 1, 2, 3, 4, 6, 8, 12}));
    EXPECT_EQ(monitor.stride(), 8);
    EXPECT_EQ(monitor.calls(), 16);
    // Recording off: no iterate is wanted (only the finiteness checks on what is passed).
    HistoryMonitor silent(view, accuracy_scale(view), 4, false);
    EXPECT_FALSE(silent.wants_iterate());
}
