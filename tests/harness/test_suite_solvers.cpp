// Suite solver entries that a build may lack (`optional`) or that apply to some snapshots only
// (`problems`, `skip_problems`): parsing, the notices, and which jobs a suite has.
#include "harness/suite.hpp"
#include "solvers/core/types.hpp"

#include <gtest/gtest.h>
#include <functional>

using cb::parse_suite;
using cb::Suite;

namespace {

std::string suite_error_of(const std::function<void()>& f)
{
    try {
        f();
    } catch (const cb::InputError& e) {
        return e.what();
    }
    return "(no InputError)";
}

nlohmann::json suite_with(const nlohmann::json& solvers)
{
    return {{"name", "t"}, {"snapshots", {"x.qpsnap"}}, {"solvers", solvers}};
}

}  // namespace

TEST(SuiteSolvers, ParsesOptionalAndProblemFilters)
{
    const Suite s = parse_suite(suite_with({{{"solver", "bullet-dantzig"}, {"optional", true}},
                                            {{"solver", "mprgp-box"}, {"problems", {"box-*"}}},
                                            {{"solver", "pgs"}, {"skip_problems", {"dino-*", "big"}}},
                                            "cg"}),
                                "s.json");
    ASSERT_EQ(s.solvers.size(), 4u);
    EXPECT_TRUE(s.solvers[0].optional);
    EXPECT_FALSE(s.solvers[1].optional);
    EXPECT_EQ(s.solvers[1].problems, std::vector<std::string>{"box-*"});
    EXPECT_EQ(s.solvers[2].skip_problems, (std::vector<std::string>{"dino-*", "big"}));
    EXPECT_TRUE(s.solvers[3].problems.empty());
}

TEST(SuiteSolvers, RejectsBadEntriesNamingTheField)
{
    EXPECT_EQ(suite_error_of([] {
                  parse_suite(suite_with({{{"solver", "cg"}, {"optional", "yes"}}}), "s.json");
              }),
              "s.json: /solvers/0: /optional: expected true or false, got \"yes\"");
    EXPECT_EQ(suite_error_of([] {
                  parse_suite(suite_with({{{"solver", "cg"}, {"problems", "box-*"}}}), "s.json");
              }),
              "s.json: /solvers/0: /problems: expected a non-empty array of snapshot id globs, got \"box-*\"");
    EXPECT_EQ(
        suite_error_of([] {
            parse_suite(suite_with({{{"solver", "cg"}, {"skip_problems", nlohmann::json::array({"a", 3})}}}), "s.json");
        }),
        "s.json: /solvers/0: /skip_problems/1: expected a non-empty string (a snapshot id glob), got 3");
    EXPECT_EQ(suite_error_of([] {
                  parse_suite(suite_with({{{"solver", "cg"}, {"colour", 1}}}), "s.json");
              }),
              "s.json: /solvers/0: /colour: unknown key; known: label, optional, problems, settings, "
              "skip_problems, solver");
}

TEST(SuiteSolvers, UnbuiltOptionalEntriesAreDroppedWithANotice)
{
    Suite s = parse_suite(suite_with({{{"label", "dantzig"}, {"solver", "bullet-dantzig"}, {"optional", true}},
                                      {{"solver", "ipopt"}, {"optional", true}},
                                      "no-such-solver"}),
                          "s.json");
    const std::vector<std::string> notices = cb::drop_unbuilt_optional_solvers(s, {"cg", "ipopt", "mprgp"});
    ASSERT_EQ(notices.size(), 1u);
    EXPECT_EQ(notices[0],
              "optional solver 'dantzig' (bullet-dantzig) is not built into this contactbench; its runs are skipped");
    ASSERT_EQ(s.solvers.size(), 2u);
    EXPECT_EQ(s.solvers[0].solver, "ipopt");           // optional and built: kept
    EXPECT_EQ(s.solvers[1].solver, "no-such-solver");  // not optional: kept, its runs say it is not registered
}

TEST(SuiteSolvers, ProblemsAndSkipProblemsSelectSnapshotIds)
{
    cb::SuiteSolver sv;
    EXPECT_TRUE(cb::solver_applies(sv, "anything"));
    sv.problems = {"box-*", "plane-s1"};
    EXPECT_TRUE(cb::solver_applies(sv, "box-3"));
    EXPECT_TRUE(cb::solver_applies(sv, "plane-s1"));
    EXPECT_FALSE(cb::solver_applies(sv, "plane-s2"));
    sv.skip_problems = {"box-3"};
    EXPECT_FALSE(cb::solver_applies(sv, "box-3"));
    EXPECT_TRUE(cb::solver_applies(sv, "box-4"));
    cb::SuiteSolver skip_only;
    skip_only.skip_problems = {"two_dinos_*"};
    EXPECT_FALSE(cb::solver_applies(skip_only, "two_dinos_9381_f11"));
    EXPECT_TRUE(cb::solver_applies(skip_only, "plane-s1"));
}
