// Every registered solver through the one solve-loop protocol (solvers/core/solve_loop.hpp): its
// history starts at its setup time, and time_limit_s counts setup.
#include "harness/history.hpp"
#include "harness/runner.hpp"
#include "problems/synthetic.hpp"
#include "solvers/core/registry.hpp"
#include "solvers/methods/template_solver.hpp"

#include <gtest/gtest.h>

namespace cb {
namespace {

/// A problem the solver takes: a falling body on a plane (decoupled rows, which every general
/// solver accepts), or bound rows for a solver that answers not_applicable on it.
Qp problem_for(const std::string& solver)
{
    Qp plane = make_synthetic("plane", {{"nx", 3}}, 1);
    SolverRegistry own;
    own.add("template", template_entry());
    const SolverRegistry& registry = solver == "template" ? own : builtin_registry();
    if (registry.create(solver, nlohmann::json::object())->solve(plane.view(), SolveContext{}).status !=
        SolveStatus::NOT_APPLICABLE)
        return plane;
    return make_synthetic("box", {{"nx", 3}}, 1);
}

std::vector<std::string> every_registered_solver()
{
    std::vector<std::string> names = builtin_registry().names();
    return names;
}

TEST(SolveLoopSolvers, HistoryStartsAtTheSetupTime)
{
    for (const std::string& name : every_registered_solver()) {
        SCOPED_TRACE(name);
        const Qp qp = problem_for(name);
        RunOptions options;
        options.record_history = true;
        const RunOutcome run = run_solver(qp, name, nlohmann::json::object(), options);
        ASSERT_TRUE(run.record.contains("history"));
        const auto& history = run.record["history"];
        const auto& columns = history["columns"];
        ASSERT_EQ(columns[1], "time_s");
        ASSERT_EQ(columns.back(), "solve_time_s");
        const auto& rows = history["rows"];
        ASSERT_FALSE(rows.empty());
        const double setup_s = run.record["time"]["setup_s"].get<double>();
        const double first = rows[0][1].get<double>();
        EXPECT_GT(setup_s, 0.0);
        EXPECT_GE(first, setup_s);  // the curve starts at the setup time
        // solve_time_s is the same stamp without the setup
        EXPECT_NEAR(rows[0].back().get<double>(), first - setup_s, 1e-12 * (1.0 + first));
        // the last row is the run's time, setup included
        const double total = run.result.setup_s + run.result.solve_s;
        EXPECT_LE(rows.back()[1].get<double>(), total * (1.0 + 1e-12));
        for (size_t k = 1; k < rows.size(); ++k) EXPECT_GE(rows[k][1].get<double>(), rows[k - 1][1].get<double>());
    }
}

TEST(SolveLoopSolvers, TimeLimitCountsSetup)
{
    // A limit far below any setup (a CHOLMOD factorisation, the power method, forming a dual):
    // every solver stops as TIME_LIMIT and says the limit was reached during setup.
    for (const std::string& name : every_registered_solver()) {
        SCOPED_TRACE(name);
        const Qp qp = problem_for(name);
        const auto solver = builtin_registry().create(name, {{"time_limit_s", 1e-12}});
        const SolverResult r = solver->solve(qp.view(), SolveContext{});
        EXPECT_EQ(r.status, SolveStatus::TIME_LIMIT) << r.message;
        EXPECT_NE(r.message.find("time limit of 1e-12 s reached during setup"), std::string::npos) << r.message;
        EXPECT_EQ(r.iterations, 0);
        EXPECT_EQ(r.x.size(), qp.n());
        EXPECT_EQ(r.lambda.size(), qp.m());
    }
}

TEST(SolveLoopSolvers, TemplateFollowsTheProtocol)
{
    SolverRegistry registry;
    registry.add("template", template_entry());
    const Qp qp = problem_for("template");
    const auto solver = registry.create("template", {{"time_limit_s", 1e-12}});
    const SolverResult r = solver->solve(qp.view(), SolveContext{});
    EXPECT_EQ(r.status, SolveStatus::TIME_LIMIT);
    EXPECT_EQ(r.message.rfind("template: time limit of 1e-12 s reached during setup (after ", 0), 0u) << r.message;
}

}  // namespace
}  // namespace cb
