// A QP built in code may hold A or J in Eigen's uncompressed mode (after insert() without
// makeCompressed()); files are always read compressed. Every registered solver must give the
// same answer on both storages (or refuse honestly), never read past a row's entries.
#include "solvers/core/registry.hpp"
#include "tests/solvers/tiny_qps.hpp"

#include <gtest/gtest.h>

#include <cctype>
#include <utility>
#include <vector>

namespace {

/// The same matrix with room left after each outer vector: Eigen's uncompressed mode.
void make_uncompressed(cb::SpMat& m) { m.reserve(Eigen::VectorXi::Constant(m.outerSize(), 2)); }

class UncompressedInput : public ::testing::TestWithParam<std::string> {};

}  // namespace

TEST_P(UncompressedInput, SolversGiveTheCompressedAnswer)
{
    namespace tq = cb::testing_qps;
    const std::vector<std::pair<cb::Qp, bool>> cases = {
        {tq::tiny_active_qp(), true}, {tq::two_row_decoupled_qp(), true}, {tq::two_row_coupled_qp(), false}};
    for (const auto& [compressed, decoupled] : cases) {
        cb::Qp loose = compressed;
        make_uncompressed(loose.A);
        make_uncompressed(loose.J);
        ASSERT_FALSE(loose.A.isCompressed());
        ASSERT_FALSE(loose.J.isCompressed());
        const auto make = [&] { return cb::builtin_registry().create(GetParam(), {{"tol", 1e-9}}); };
        if (make()->requires_decoupled() && !decoupled) continue;
        const cb::SolverResult want = make()->solve(compressed.view(), cb::SolveContext{});
        const cb::SolverResult got = make()->solve(loose.view(), cb::SolveContext{});
        EXPECT_EQ(got.status, want.status) << got.message;
        ASSERT_EQ(got.x.size(), want.x.size());
        if (want.x.size() > 0) {
            EXPECT_LE((got.x - want.x).lpNorm<Eigen::Infinity>(), 1e-12);
        }
    }
}

INSTANTIATE_TEST_SUITE_P(EveryRegisteredSolver, UncompressedInput, ::testing::ValuesIn(cb::builtin_registry().names()),
                         [](const ::testing::TestParamInfo<std::string>& p) {
                             std::string name = p.param;
                             for (char& ch : name)
                                 if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
                             return name;
                         });
