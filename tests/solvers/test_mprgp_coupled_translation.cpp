// Issue 17: mprgp-coupled on a problem moved by 100 m (x0 + t, b + A t, c + J t) behaves as on
// the original one: same status, nearly the same iteration count, the solution moved by t.
#include "harness/stress_families.hpp"
#include "solvers/core/registry.hpp"
#include "solvers/measure/accuracy.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <ostream>

namespace {

using cb::Qp;
using cb::SolveStatus;

struct TranslationPair {
    const char* original;
    const char* translated;
};
/// ctest names an instance by its printed parameter: the case's name, not its bytes (pointers that
/// moved from build to build).
// NOLINTNEXTLINE(readability-identifier-naming): GoogleTest looks up this name
void PrintTo(const TranslationPair& p, std::ostream* os) { *os << p.translated; }

class CoupledTranslation : public ::testing::TestWithParam<TranslationPair> {};

TEST_P(CoupledTranslation, ConvergesAsUntranslated)
{
    const auto all = cb::stress_cases(false);
    const Qp base = cb::make_stress_qp(cb::select_stress_cases(all, {GetParam().original}).at(0));
    const Qp moved = cb::make_stress_qp(cb::select_stress_cases(all, {GetParam().translated}).at(0));
    ASSERT_EQ(base.n(), moved.n());
    ASSERT_LE((moved.x0 - base.x0).cwiseAbs().minCoeff(), 1e-9);  // only x moved, by 100 m
    const nlohmann::json settings = {{"tol", 1e-9}, {"max_iterations", 10000}};
    const cb::SolverResult r0 = cb::builtin_registry().create("mprgp-coupled", settings)->solve(base.view(), {});
    const cb::SolverResult r1 = cb::builtin_registry().create("mprgp-coupled", settings)->solve(moved.view(), {});
    ASSERT_EQ(r0.status, SolveStatus::CONVERGED) << r0.message;
    ASSERT_EQ(r1.status, SolveStatus::CONVERGED) << r1.message;
    const double kkt1 = cb::accuracy(moved.view(), r1.x, r1.lambda).max();
    EXPECT_LE(kkt1, 1e-9);
    EXPECT_LE(std::abs(r1.iterations - r0.iterations), r0.iterations / 5 + 10)
        << "untranslated " << r0.iterations << ", translated " << r1.iterations;
    EXPECT_LE(r1.counters.expansion_steps, 2 * r0.counters.expansion_steps + 10);
    // Same solution, moved by t = 100 m along x.
    cb::Vec back = r1.x;
    for (Eigen::Index v = 0; v < back.size() / 3; ++v) back[3 * v] -= 100.0;
    EXPECT_LE((back - r0.x).lpNorm<Eigen::Infinity>(), 1e-6 * std::max(1.0, r0.x.lpNorm<Eigen::Infinity>()));
}

INSTANTIATE_TEST_SUITE_P(Stress, CoupledTranslation,
                         ::testing::Values(TranslationPair{"baseline-coupled", "coupled-translated-100m"},
                                           TranslationPair{"stiffness-coupled-1e9", "coupled-stiff-translated-100m"}));

}  // namespace
