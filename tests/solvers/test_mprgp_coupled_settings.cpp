// mprgp-coupled's settings after issue 44: the variants measured worse (trial=project,
// expansion=precond|feasible_step; docs/ALGORITHMS.md §4, the paragraph on retired variants) are refused
// as unknown settings, and the kept ones read as before.
#include "solvers/core/registry.hpp"

#include <gtest/gtest.h>

#include <string>

namespace {

std::string refusal(const nlohmann::json& settings)
{
    try {
        cb::builtin_registry().create("mprgp-coupled", settings);
    } catch (const std::exception& e) {
        return e.what();
    }
    return "";
}

TEST(MprgpCoupledSettings, RetiredVariantsAreUnknownSettings)
{
    for (const nlohmann::json& retired :
         {nlohmann::json{{"trial", "project"}}, nlohmann::json{{"trial", "chain"}},
          nlohmann::json{{"expansion", "precond"}}, nlohmann::json{{"expansion", "feasible_step"}}}) {
        const std::string key = retired.begin().key();
        EXPECT_NE(refusal(retired).find("mprgp-coupled: /" + key + ": unknown setting"), std::string::npos)
            << refusal(retired);
    }
    const nlohmann::json record = cb::builtin_registry().create("mprgp-coupled", nlohmann::json::object())->settings();
    EXPECT_FALSE(record.contains("trial"));
    EXPECT_FALSE(record.contains("expansion"));
    EXPECT_EQ(record["expansion_projection"], "face");
    EXPECT_EQ(refusal({{"expansion_projection", "all"}, {"operators", "global"}}), "");
}

}  // namespace
