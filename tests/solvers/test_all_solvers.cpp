// Every registered solver (builtin_registry().names(), so solvers registered later are covered
// automatically) on tiny hand-derived QPs (STYLE.md §7). Solvers that require a decoupled J get
// only decoupled problems; a solver that reports info.ignores_constraints (cg) must return the
// unconstrained minimiser instead.
#include "solvers/core/registry.hpp"
#include "solvers/measure/accuracy.hpp"
#include "tests/solvers/tiny_qps.hpp"

#include <Eigen/Dense>
#include <gtest/gtest.h>
#include <algorithm>
#include <string>
#include <vector>

namespace {

using cb::Qp;
using cb::SolverResult;
using cb::SolveStatus;
using cb::Vec;

constexpr double ALL_SOLVERS_TOL = 1e-9;

struct HandCase {
    std::string name;
    Qp qp;
    Vec x_star;
    Vec lambda_star;  ///< empty when not unique
    bool decoupled;
};

std::vector<HandCase> hand_cases()
{
    namespace tq = cb::testing_qps;
    std::vector<HandCase> cases;
    cases.push_back({"style_example", tq::tiny_active_qp(), Eigen::Vector2d(1, 1), Vec::Constant(1, 2.0), true});
    cases.push_back(
        {"two_rows_decoupled", tq::two_row_decoupled_qp(), tq::two_row_decoupled_x(), Eigen::Vector2d(2, 4), true});
    cases.push_back({"unconstrained", tq::unconstrained_qp(), tq::unconstrained_x(), Vec(0), true});
    cases.push_back(
        {"two_rows_coupled", tq::two_row_coupled_qp(), Eigen::Vector2d(1, 1), Eigen::Vector2d(3, 3), false});
    return cases;
}

class AllSolvers : public ::testing::TestWithParam<std::string> {};

}  // namespace

TEST_P(AllSolvers, TinyHandDerivedQpsSatisfyKkt)
{
    for (const HandCase& hc : hand_cases()) {
        SCOPED_TRACE(GetParam() + " on " + hc.name);
        const auto solver = cb::builtin_registry().create(GetParam(), {{"tol", ALL_SOLVERS_TOL}});
        if (solver->requires_decoupled() && !hc.decoupled) continue;
        const SolverResult r = solver->solve(hc.qp.view(), cb::SolveContext{});
        ASSERT_EQ(r.x.size(), hc.qp.n());
        ASSERT_EQ(r.lambda.size(), hc.qp.m());
        const bool ignores = r.info.is_object() && r.info.value("ignores_constraints", false);
        if (ignores) {
            // The unconstrained minimiser, whatever J says.
            const Vec x_unc = Eigen::MatrixXd(hc.qp.A).ldlt().solve(hc.qp.b);
            ASSERT_EQ(r.status, SolveStatus::CONVERGED) << r.message;
            EXPECT_LE((r.x - x_unc).lpNorm<Eigen::Infinity>(), 1e-6);
            continue;
        }
        ASSERT_EQ(r.status, SolveStatus::CONVERGED) << cb::to_string(r.status) << ": " << r.message;
        const cb::AccuracyParts e = cb::accuracy(hc.qp.view(), r.x, r.lambda);
        if (r.criterion == cb::StopCriterion::ACCURACY) {
            EXPECT_LE(e.max(), ALL_SOLVERS_TOL * (1 + 1e-6)) << "status honesty";
        }
        EXPECT_LE(e.stationarity, 1e-6);
        EXPECT_LE(e.primal, 1e-6);
        EXPECT_LE(e.dual, 1e-6);
        EXPECT_LE(e.complementarity, 1e-6);
        // hand-derived, independent of accuracy()
        EXPECT_LE((r.x - hc.x_star).lpNorm<Eigen::Infinity>(), 1e-6);
        if (hc.lambda_star.size()) {
            EXPECT_LE((r.lambda - hc.lambda_star).lpNorm<Eigen::Infinity>(), 1e-5);
        }
    }
}

// "converged" must mean what it says, on a problem that takes a few iterations.
TEST_P(AllSolvers, ConvergedStatusIsConfirmedByTheAccuracyMeasure)
{
    // 3 decoupled vertices, A tridiagonal-coupled in each coordinate, two rows active.
    const int n = 9;
    Eigen::MatrixXd A = 4.0 * Eigen::MatrixXd::Identity(n, n);
    for (int i = 0; i + 3 < n; ++i) A(i, i + 3) = A(i + 3, i) = -1.0;
    Vec b = Vec::LinSpaced(n, -1.0, 1.0);
    Eigen::MatrixXd J = Eigen::MatrixXd::Zero(2, n);
    J(0, 1) = 1.0;  // vertex 0, y >= 0.5
    J(1, 7) = 1.0;  // vertex 2, y >= 1
    const Qp qp = cb::testing_qps::dense_qp(A, b, J, Eigen::Vector2d(0.5, 1.0), Vec::Zero(n));
    for (double tol : {1e-4, 1e-8}) {
        const auto solver = cb::builtin_registry().create(GetParam(), {{"tol", tol}});
        const SolverResult r = solver->solve(qp.view(), cb::SolveContext{});
        // Every registered solver converges here at both tolerances, on the accuracy error (its
        // default stop): a solver that stops converging, or on another criterion, fails instead
        // of being passed over.
        ASSERT_EQ(r.status, SolveStatus::CONVERGED) << GetParam() << " at tol " << tol << ": " << r.message;
        ASSERT_EQ(r.criterion, cb::StopCriterion::ACCURACY) << GetParam() << " at tol " << tol;
        if (r.info.is_object() && r.info.value("ignores_constraints", false)) {
            EXPECT_EQ(GetParam(), "cg");  // the one relaxation: its e is judged on the unconstrained QP
            continue;
        }
        const double rel = cb::accuracy(qp.view(), r.x, r.lambda).max();
        EXPECT_LE(rel, tol * (1 + 1e-6)) << GetParam() << " claims convergence at tol " << tol;
    }
}

// A solver's setup in the record (info.setup_phases_s): the parts sum to time.setup_s, and the
// accuracy measure's scale is one of them for the solvers that form it (all of the project's own
// iterative solvers; a later solver is checked whenever it reports the field).
TEST_P(AllSolvers, SetupPhasesSumToTheSetupAndNameTheMeasureScale)
{
    const Qp qp = cb::testing_qps::two_row_decoupled_qp();
    const SolverResult r = cb::builtin_registry().create(GetParam(), {{"tol", 1e-8}})->solve(qp.view(), {});
    // Every solver of ours and the friction peers, whose local problem is formed here (the other peers
    // form the scale only for their verdict, after the library returns).
    const std::vector<std::string> split = {"mprgp",
                                            "mprgp-coupled",
                                            "mprgp-box",
                                            "cg",
                                            "ica",
                                            "pgs",
                                            "active-set",
                                            "nsgs-friction",
                                            "mprgp-staggered",
                                            "mprgp-tresca-fp",
                                            "mprgp+ica-friction",
                                            "siconos-fc3d-nsgs",
                                            "siconos-fc3d-nsn"};
    const bool must = std::find(split.begin(), split.end(), GetParam()) != split.end();
    if (!r.info.is_object() || !r.info.contains("setup_phases_s")) {
        EXPECT_FALSE(must) << GetParam() << " reports no setup phases";
        return;
    }
    double sum = 0.0;
    for (const auto& [key, value] : r.info["setup_phases_s"].items()) {
        EXPECT_GE(value.get<double>(), 0.0) << key;
        sum += value.get<double>();
    }
    EXPECT_NEAR(sum, r.setup_s, 1e-9);
    if (must) {
        EXPECT_TRUE(r.info["setup_phases_s"].contains("measure_scale")) << r.info["setup_phases_s"].dump();
    }
}

TEST_P(AllSolvers, UnknownSettingIsAnInputError)
{
    EXPECT_THROW(cb::builtin_registry().create(GetParam(), {{"no_such_setting", 1}}), cb::InputError);
}

// The effective settings a results file records can be fed back unchanged.
TEST_P(AllSolvers, EffectiveSettingsRoundTrip)
{
    const auto solver = cb::builtin_registry().create(GetParam(), nlohmann::json::object());
    const nlohmann::json effective = solver->settings();
    ASSERT_TRUE(effective.is_object());
    for (const char* key : {"tol", "stop", "max_iterations", "time_limit_s", "seed"})
        EXPECT_TRUE(effective.contains(key)) << key;
    const auto again = cb::builtin_registry().create(GetParam(), effective);
    EXPECT_EQ(again->settings(), effective);
    EXPECT_FALSE(cb::builtin_registry().entry(GetParam()).description.empty());
}

INSTANTIATE_TEST_SUITE_P(Registry, AllSolvers, ::testing::ValuesIn(cb::builtin_registry().names()),
                         [](const auto& info) {
                             std::string name = info.param;
                             for (char& ch : name)
                                 if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
                             return name;
                         });
