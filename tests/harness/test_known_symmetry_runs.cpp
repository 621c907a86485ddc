// Whole runs through the harness (run_solver) on a QP read from a snapshot: the readers' word that
// A equals A' (Qp::a_symmetric) reaches every solver's AOperator, through the harness's decoupled
// view and the solvers' compressed views, so SBSR checks A's mirror only on QPs no reader made.
// The same run on the generated QP (the flag unset) checks it: the counter can move.
#include "harness/runner.hpp"
#include "problems/qpsnap.hpp"
#include "problems/synthetic.hpp"
#include "solvers/linalg/a_product.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <unistd.h>

using namespace cb;

namespace {

/// Mirror checks done by one harness run of `solver` on `qp` with the upper blocks asked for.
long known_symmetry_mirror_checks(const Qp& qp, const std::string& solver)
{
    RunOptions options;
    options.record_history = false;
    const long before = mirror_check_count();
    const RunOutcome run =
        run_solver(qp, solver, {{"a_format", "sbsr"}, {"max_iterations", 20}}, options, nlohmann::json::object());
    EXPECT_EQ(run.result.info.value("a_format", ""), "sbsr") << solver;
    return mirror_check_count() - before;
}

}  // namespace

TEST(KnownSymmetryRuns, ReadQpsSkipTheMirrorCheckGeneratedOnesDoNot)
{
    const auto dir = std::filesystem::temp_directory_path() / ("cb_test_known_symmetry_" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir);
    // coupled: J's rows share vertices, so mprgp runs on the harness's decoupled view.
    for (const std::string family : {"plane", "coupled"}) {
        const Qp generated = make_synthetic(family, nlohmann::json::object(), 3);
        ASSERT_EQ(generated.n() % 3, 0);
        const std::string path = (dir / (family + ".qpsnap")).string();
        write_qpsnap(path, generated);
        const Qp read = read_qpsnap(path);
        ASSERT_TRUE(read.a_symmetric);
        for (const std::string solver : {"mprgp-coupled", "mprgp", "cg", "ica"}) {
            SCOPED_TRACE(family);
            SCOPED_TRACE(solver);
            EXPECT_EQ(known_symmetry_mirror_checks(read, solver), 0);
            EXPECT_GE(known_symmetry_mirror_checks(generated, solver), 1);
        }
    }
    std::filesystem::remove_all(dir);
}
