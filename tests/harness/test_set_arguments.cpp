// Settings typed as text (harness/set_arguments.hpp) and the run's setting defaults
// (RunOptions::defaults): one rule for a value's type, one place where the harness adds a setting,
// and the runner's tol read typed from the solver's effective settings.
#include "harness/runner.hpp"
#include "harness/set_arguments.hpp"
#include "problems/qpsnap.hpp"
#include "solvers/core/types.hpp"

#include <gtest/gtest.h>

using namespace cb;

namespace {

std::string assignment_error_of(const std::vector<std::string>& assignments)
{
    try {
        settings_from_assignments(assignments);
    } catch (const InputError& e) {
        return e.what();
    }
    return "no error";
}

Qp small_qp() { return read_qpsnap(std::string(CB_TEST_DATA_DIR) + "/plane_2x2x2.qpsnap"); }

}  // namespace

TEST(SetArguments, OneRuleForTheTypeOfAValue)
{
    EXPECT_EQ(setting_from_text("true"), nlohmann::json(true));
    EXPECT_EQ(setting_from_text("false"), nlohmann::json(false));
    EXPECT_TRUE(setting_from_text("500").is_number_integer());
    EXPECT_EQ(setting_from_text("500").get<long>(), 500);
    EXPECT_TRUE(setting_from_text("1e-8").is_number_float());
    EXPECT_DOUBLE_EQ(setting_from_text("1e-8").get<double>(), 1e-8);
    EXPECT_EQ(setting_from_text("jacobi"), nlohmann::json("jacobi"));
    EXPECT_EQ(setting_from_text(""), nlohmann::json(""));
    EXPECT_EQ(setting_from_text("12abc"), nlohmann::json("12abc"));
    const nlohmann::json s = settings_from_assignments({"tol=1e-8", "precond=ichol", "max_iterations=20", "tol=1e-9"});
    EXPECT_EQ(s, nlohmann::json({{"tol", 1e-9}, {"precond", "ichol"}, {"max_iterations", 20}}));
    EXPECT_EQ(assignment_error_of({"tol"}), "--set: tol: expected key=value");
    EXPECT_EQ(assignment_error_of({"=1"}), "--set: =1: expected key=value");
}

TEST(RunDefaults, TheSuiteTolIsADefaultAndTheSolversOwnWins)
{
    const Qp qp = small_qp();
    RunOptions options;
    options.record_history = false;
    options.defaults.tol = 1e-3;
    options.defaults.time_limit_s = 7.0;
    const RunOutcome given = run_solver(qp, "mprgp", {}, options);
    EXPECT_DOUBLE_EQ(given.record["tol"].get<double>(), 1e-3);
    EXPECT_DOUBLE_EQ(given.record["settings"]["time_limit_s"].get<double>(), 7.0);
    EXPECT_DOUBLE_EQ(given.record["accuracy_tol"].get<double>(), 1e-3);
    EXPECT_LE(given.accuracy.max(), 1e-3);
    const RunOutcome own = run_solver(qp, "mprgp", {{"tol", 1e-8}, {"time_limit_s", 0}}, options);
    EXPECT_DOUBLE_EQ(own.record["tol"].get<double>(), 1e-8);
    EXPECT_DOUBLE_EQ(own.record["settings"]["time_limit_s"].get<double>(), 0.0);
    EXPECT_LE(own.accuracy.max(), 1e-8);
    // Without a default the solver's own default holds, read typed from its effective settings:
    // active-set's is 1e-10, not the common 1e-6.
    const RunOutcome exact = run_solver(qp, "active-set", {}, RunOptions{});
    EXPECT_DOUBLE_EQ(exact.record["tol"].get<double>(), 1e-10);
    EXPECT_DOUBLE_EQ(exact.record["accuracy_tol"].get<double>(), 1e-10);
    // stop=native: e must still reach the default tol of the common settings.
    const RunOutcome native = run_solver(qp, "mprgp", {{"stop", "native"}, {"tol", 1e-3}}, RunOptions{});
    EXPECT_DOUBLE_EQ(native.record["accuracy_tol"].get<double>(), CommonSettings{}.tol);
}
