// The solve-loop protocol (solvers/core/solve_loop.hpp): the stop rule, exit order, `>=` on both
// limits, setup counted in the time limit, the monitor on a paused clock, the finisher's criterion
// and standard messages.
#include "solvers/core/solve_loop.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>

namespace cb {
namespace {

struct Fixture {
    SpMat A, J;
    Vec b, c, x0;
    Fixture() : A(2, 2), J(1, 2), b(Vec::Ones(2)), c(Vec::Zero(1)), x0(Vec::Constant(2, 3.0))
    {
        A.insert(0, 0) = 1.0;
        A.insert(1, 1) = 1.0;
        J.insert(0, 0) = 1.0;
    }
    QpView view() const { return QpView{A, b, J, c, x0}; }
};

CommonSettings limits(long max_iterations, double time_limit_s, StopRule stop = StopRule::ACCURACY, double tol = 1e-6)
{
    CommonSettings s;
    s.max_iterations = max_iterations;
    s.time_limit_s = time_limit_s;
    s.stop = stop;
    s.tol = tol;
    return s;
}

/// Busy-waits until the loop's clock (from the start of setup) has passed `seconds`.
void spend(const SolveLoop& loop, double seconds)
{
    volatile double sink = 0.0;
    while (loop.elapsed_s() <= seconds) sink = sink + 1.0;
}

/// Records what the clock said during its call, and spends time there.
class ClockMonitor : public Monitor {
public:
    std::function<void(const IterationInfo&)> body;
    bool answer = true;
    bool on_iteration(const IterationInfo& info) override
    {
        if (body) body(info);
        return answer;
    }
};

TEST(SolveLoop, ExitChecksInOneOrder)
{
    const Fixture f;
    const SolveContext context;
    SolveLoop loop("t", f.view(), limits(5, 1e-9), context);
    spend(loop, 1e-8);  // the time limit is reached as well
    ASSERT_TRUE(loop.time_up());
    // non-finite first, even when every other exit holds
    EXPECT_EQ(loop.check(5, false, true), SolveStatus::DIVERGED);
    EXPECT_EQ(loop.check(5, false, 0.0, 0.0), SolveStatus::DIVERGED);
    // then converged, before the cap and the time
    EXPECT_EQ(loop.check(5, true, true), SolveStatus::CONVERGED);
    EXPECT_EQ(loop.check(5, true, 1.0, 1e-7), SolveStatus::CONVERGED);  // stop=kkt reads the accuracy error
    // then the iteration cap, before the time
    EXPECT_EQ(loop.check(5, true, false), SolveStatus::MAX_ITERATIONS);
    EXPECT_EQ(loop.check(5, true, 0.0, 1e-5), SolveStatus::MAX_ITERATIONS);
    // then the time
    EXPECT_EQ(loop.check(4, true, false), SolveStatus::TIME_LIMIT);
    EXPECT_EQ(loop.limit_status(4), SolveStatus::TIME_LIMIT);
}

TEST(SolveLoop, ConvergenceTestIsNotEvaluatedOnANonFiniteIterate)
{
    const Fixture f;
    const SolveContext context;
    SolveLoop loop("t", f.view(), limits(10, 0.0), context);
    int calls = 0;
    auto error = [&] {
        ++calls;
        return 1.0;
    };
    EXPECT_EQ(loop.check(0, false, 0.0, error), SolveStatus::DIVERGED);
    EXPECT_EQ(calls, 0);
    EXPECT_EQ(loop.check(0, true, 0.0, error), SolveStatus::NOT_RUN);
    EXPECT_EQ(calls, 1);
}

TEST(SolveLoop, IterationCapIsGreaterOrEqual)
{
    const Fixture f;
    const SolveContext context;
    SolveLoop loop("t", f.view(), limits(3, 0.0), context);
    EXPECT_EQ(loop.limit_status(2), SolveStatus::NOT_RUN);
    EXPECT_EQ(loop.limit_status(3), SolveStatus::MAX_ITERATIONS);
    EXPECT_EQ(loop.limit_status(4), SolveStatus::MAX_ITERATIONS);
    SolveLoop none("t", f.view(), limits(0, 0.0), context);  // max_iterations = 0: no iteration
    EXPECT_EQ(none.limit_status(0), SolveStatus::MAX_ITERATIONS);
}

TEST(SolveLoop, NoTimeLimitWhenZero)
{
    const Fixture f;
    const SolveContext context;
    SolveLoop loop("t", f.view(), limits(10, 0.0), context);
    spend(loop, 1e-6);
    EXPECT_FALSE(loop.time_up());
    EXPECT_TRUE(loop.end_setup());
    EXPECT_EQ(loop.limit_status(0), SolveStatus::NOT_RUN);
}

TEST(SolveLoop, TimeLimitCountsSetup)
{
    const Fixture f;
    const SolveContext context;
    SolveLoop loop("my-solver", f.view(), limits(10, 1e-6), context);
    spend(loop, 2e-6);  // setup longer than the limit
    EXPECT_FALSE(loop.end_setup());
    EXPECT_GE(loop.setup_s(), 2e-6);
    const std::string message = loop.time_limit_message();
    EXPECT_EQ(message.rfind("my-solver: time limit of 1e-06 s reached during setup (after ", 0), 0u) << message;
    SolverResult result;
    const SolverResult out = loop.finish(result, SolveStatus::TIME_LIMIT);
    EXPECT_EQ(out.status, SolveStatus::TIME_LIMIT);
    EXPECT_EQ(out.message, message);
    EXPECT_DOUBLE_EQ(out.setup_s, loop.setup_s());
    EXPECT_GE(out.solve_s, 0.0);
    // x and lambda default to x0 and zeros
    EXPECT_EQ(out.x, f.x0);
    EXPECT_EQ(out.lambda, Vec::Zero(1));
}

TEST(SolveLoop, TimeLimitAfterSetupNamesBothParts)
{
    const Fixture f;
    const SolveContext context;
    SolveLoop loop("s", f.view(), limits(10, 1e-3), context);
    EXPECT_TRUE(loop.end_setup());  // at once: far below 1 ms
    spend(loop, 1.1e-3);
    EXPECT_TRUE(loop.time_up());
    EXPECT_EQ(loop.time_limit_message().rfind("s: time limit of 0.001 s reached (setup ", 0), 0u)
        << loop.time_limit_message();
}

TEST(SolveLoop, MonitorAndItsPreparationRunOnAPausedClock)
{
    const Fixture f;
    ClockMonitor monitor;
    SolveContext context;
    context.monitor = &monitor;
    SolveLoop loop("t", f.view(), limits(10, 0.0), context);
    spend(loop, 1e-5);
    ASSERT_TRUE(loop.end_setup());
    const double setup = loop.setup_s();
    spend(loop, setup + 2e-5);
    double seen_in_prepare = -1.0, seen_in_monitor = -1.0, stamped = -1.0, stamped_setup = -1.0;
    monitor.body = [&](const IterationInfo& info) {
        seen_in_monitor = loop.elapsed_s();
        stamped = info.elapsed_s;
        stamped_setup = info.setup_s;
    };
    IterationInfo info;
    const bool go_on = loop.notify(info, [&] {
        const double before = loop.elapsed_s();
        volatile double sink = 0.0;
        for (int k = 0; k < 200000; ++k) sink = sink + 1.0;  // monitor-only work
        EXPECT_EQ(loop.elapsed_s(), before);                 // the clock did not move
        seen_in_prepare = before;
    });
    EXPECT_TRUE(go_on);
    EXPECT_EQ(seen_in_monitor, seen_in_prepare);  // paused through prepare and the monitor
    EXPECT_EQ(stamped, seen_in_monitor);
    EXPECT_DOUBLE_EQ(stamped_setup, setup);
    EXPECT_GE(stamped, setup + 2e-5);      // stamped from the start of setup
    EXPECT_GT(loop.elapsed_s(), stamped);  // and running again afterwards
    monitor.answer = false;
    EXPECT_FALSE(loop.notify(info));
}

TEST(SolveLoop, NoMonitorNoPreparation)
{
    const Fixture f;
    const SolveContext context;
    SolveLoop loop("t", f.view(), limits(10, 0.0), context);
    bool prepared = false;
    EXPECT_TRUE(loop.notify(IterationInfo{}, [&] { prepared = true; }));
    EXPECT_FALSE(prepared);
}

/// A monitor that reads only some iterates (a recorder on a stride).
class PickyMonitor : public ClockMonitor {
public:
    bool wants = true;
    bool wants_iterate() const override { return wants; }
};

TEST(SolveLoop, PreparationOnlyForIteratesTheMonitorReads)
{
    const Fixture f;
    PickyMonitor monitor;
    const Vec x = Vec::Zero(3);
    const Vec* seen = &x;
    monitor.body = [&](const IterationInfo& info) { seen = info.x; };
    SolveContext context;
    context.monitor = &monitor;
    SolveLoop loop("t", f.view(), limits(10, 0.0), context);
    IterationInfo info;
    info.x = &x;
    int prepared = 0;
    monitor.wants = false;
    EXPECT_TRUE(loop.notify(info, [&] { ++prepared; }));
    EXPECT_EQ(prepared, 0);
    EXPECT_EQ(seen, nullptr);  // not formed: no stale iterate reaches the monitor
    monitor.wants = true;
    EXPECT_TRUE(loop.notify(info, [&] { ++prepared; }));
    EXPECT_EQ(prepared, 1);
    EXPECT_EQ(seen, &x);
    // without a preparation step the iterate is passed as it is
    monitor.wants = false;
    EXPECT_TRUE(loop.notify(info));
    EXPECT_EQ(seen, &x);
    // a preparation step may fill in what only the monitor shows (active-set's violation)
    double shown = -1.0;
    monitor.body = [&](const IterationInfo& i) { shown = i.native_residual; };
    monitor.wants = true;
    EXPECT_TRUE(loop.notify(info, [](IterationInfo& i) { i.native_residual = 7.0; }));
    EXPECT_EQ(shown, 7.0);
}

TEST(SolveLoop, FinishFillsCountersAndTimes)
{
    const Fixture f;
    const SolveContext context;
    SolveLoop loop("t", f.view(), limits(10, 0.0), context);
    ASSERT_TRUE(loop.end_setup());
    spend(loop, loop.setup_s() + 1e-6);
    SolverResult result;
    result.counters.iterations = 7;
    result.x = Vec::Constant(2, 1.0);
    result.message = "kept";
    const SolverResult out = loop.finish(result, SolveStatus::STALLED);  // the solver's own word: kept
    EXPECT_EQ(out.iterations, 7);
    EXPECT_EQ(out.criterion, StopCriterion::NONE);
    EXPECT_EQ(out.message, "kept");
    EXPECT_EQ(out.x, Vec::Constant(2, 1.0));
    EXPECT_GE(out.solve_s, 1e-6);
    EXPECT_DOUBLE_EQ(out.setup_s, loop.setup_s());
}

// Setup phases (info.setup_phases_s): each mark takes the time since the last one, a repeated name
// adds up, the unmarked rest is `other`, and together they are the setup time; marks after the
// setup and a loop without marks add nothing.
TEST(SolveLoop, SetupPhasesPartTheSetupTime)
{
    const Fixture f;
    const SolveContext context;
    SolveLoop loop("t", f.view(), limits(10, 0.0), context);
    spend(loop, 2e-3);
    loop.setup_phase("first");
    spend(loop, loop.elapsed_s() + 2e-3);
    loop.setup_phase("second");
    spend(loop, loop.elapsed_s() + 1e-3);
    loop.setup_phase("first");
    spend(loop, loop.elapsed_s() + 1e-3);  // unmarked
    ASSERT_TRUE(loop.end_setup());
    loop.setup_phase("after");
    SolverResult result;
    const SolverResult out = loop.finish(result, SolveStatus::STALLED);
    ASSERT_TRUE(out.info.contains("setup_phases_s")) << out.info.dump();
    const nlohmann::json& p = out.info["setup_phases_s"];
    EXPECT_EQ(p.size(), 3U) << p.dump();
    EXPECT_FALSE(p.contains("after"));
    EXPECT_GE(p["first"].get<double>(), 3e-3);
    EXPECT_GE(p["second"].get<double>(), 2e-3);
    EXPECT_GE(p["other"].get<double>(), 1e-3);
    EXPECT_NEAR(p["first"].get<double>() + p["second"].get<double>() + p["other"].get<double>(), out.setup_s, 1e-12);
    EXPECT_NEAR(loop.setup_phase_s("first"), p["first"].get<double>(), 1e-12);  // the accessor sums the same parts
    EXPECT_LT(loop.setup_phase_s("after"), 1e-12);  // a mark after the setup records nothing

    SolveLoop unmarked("t", f.view(), limits(10, 0.0), context);
    ASSERT_TRUE(unmarked.end_setup());
    SolverResult plain;
    EXPECT_FALSE(unmarked.finish(plain, SolveStatus::STALLED).info.contains("setup_phases_s"));
}

TEST(SolveLoop, TheRuleReadsOnlyItsOwnMeasure)
{
    const Fixture f;
    const SolveContext context;
    int native_calls = 0, accuracy_calls = 0;
    auto native = [&] {
        ++native_calls;
        return 0.5;
    };
    auto accuracy = [&] {
        ++accuracy_calls;
        return 1e-9;
    };
    SolveLoop kkt("t", f.view(), limits(10, 0.0, StopRule::ACCURACY, 1e-6), context);
    EXPECT_TRUE(kkt.criterion_met(native, accuracy));
    EXPECT_EQ(native_calls, 0);
    EXPECT_EQ(accuracy_calls, 1);
    SolveLoop own("t", f.view(), limits(10, 0.0, StopRule::NATIVE, 1e-6), context);
    EXPECT_FALSE(own.criterion_met(native, accuracy));  // 0.5 > 1e-6
    EXPECT_EQ(native_calls, 1);
    EXPECT_EQ(accuracy_calls, 1);
    EXPECT_TRUE(own.rule_holds(1e-7, 1.0));
    EXPECT_FALSE(kkt.rule_holds(1e-7, 1.0));
    // `<=`: a measure exactly at tol meets the rule; NaN never does
    EXPECT_TRUE(kkt.criterion_met(0.0, 1e-6));
    EXPECT_FALSE(kkt.criterion_met(0.0, std::nan("")));
}

TEST(SolveLoop, FinishRecordsTheCriterionAndWritesTheStandardMessages)
{
    const Fixture f;
    const SolveContext context;
    {
        SolveLoop loop("s", f.view(), limits(10, 0.0, StopRule::ACCURACY, 1e-6), context);
        ASSERT_EQ(loop.check(3, true, 9.0, 2.5e-7), SolveStatus::CONVERGED);
        SolverResult r;
        const SolverResult out = loop.finish(r, SolveStatus::CONVERGED, "3 steps");
        EXPECT_EQ(out.criterion, StopCriterion::ACCURACY);
        EXPECT_STREQ(to_string(out.criterion), "kkt");
        EXPECT_EQ(out.message, "s: converged: accuracy error 2.5e-07 <= tol 1e-06; 3 steps");
    }
    {
        SolveLoop loop("s", f.view(), limits(10, 0.0, StopRule::NATIVE, 1e-3), context);
        ASSERT_EQ(loop.check(3, true, 5e-4, 1.0), SolveStatus::CONVERGED);
        SolverResult r;
        const SolverResult out = loop.finish(r, SolveStatus::CONVERGED);
        EXPECT_EQ(out.criterion, StopCriterion::NATIVE);
        EXPECT_EQ(out.message, "s: converged: native residual 0.0005 <= tol 0.001");
    }
    {
        SolveLoop loop("s", f.view(), limits(10, 0.0), context);
        ASSERT_EQ(loop.check(10, true, 1.0, 1.0), SolveStatus::MAX_ITERATIONS);
        SolverResult r;
        const SolverResult out = loop.finish(r, SolveStatus::MAX_ITERATIONS, "detail");
        EXPECT_EQ(out.criterion, StopCriterion::NONE);
        EXPECT_EQ(out.message, "s: iteration cap 10 reached; detail");
    }
    {
        SolveLoop loop("s", f.view(), limits(10, 0.0), context);
        ASSERT_EQ(loop.check(0, false, 1.0, 1.0), SolveStatus::DIVERGED);
        SolverResult r;
        EXPECT_EQ(loop.finish(r, SolveStatus::DIVERGED).message, "s: non-finite iterate");
    }
    {
        // a DIVERGED the loop did not decide (a breakdown) keeps the solver's message
        SolveLoop loop("s", f.view(), limits(10, 0.0), context);
        SolverResult r;
        EXPECT_EQ(loop.finish(r, SolveStatus::DIVERGED, "s: p'Ap < 0").message, "s: p'Ap < 0");
        SolverResult m;
        EXPECT_EQ(loop.finish(m, SolveStatus::STOPPED_BY_MONITOR).message, "s: stopped by the monitor");
    }
    {
        // a finite method's or a peer's verdict
        SolveLoop loop("s", f.view(), limits(10, 0.0, StopRule::ACCURACY, 1e-6), context);
        EXPECT_EQ(loop.verdict(true, 0.0, 2e-6), SolveStatus::STALLED);
        SolverResult r;
        EXPECT_EQ(loop.finish(r, SolveStatus::STALLED).message,
                  "s: the stop rule does not hold at the returned point: accuracy error 2e-06 > tol 1e-06");
        EXPECT_EQ(loop.verdict(true, 0.0, 2e-6, SolveStatus::MAX_ITERATIONS), SolveStatus::MAX_ITERATIONS);
        EXPECT_EQ(loop.verdict(false, 0.0, 0.0), SolveStatus::DIVERGED);
        EXPECT_EQ(loop.verdict(true, 1.0, 1e-7), SolveStatus::CONVERGED);
    }
}

}  // namespace
}  // namespace cb
