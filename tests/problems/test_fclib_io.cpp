// FCLIB export (problems/fclib_io.*): a write/read round trip keeps every array bit for bit, and
// problems outside the frictionless mapping are refused with a message naming the field.
#include "problems/fclib_io.hpp"
#include "problems/synthetic.hpp"
#include "solvers/registry.hpp"

#include <gtest/gtest.h>
#include <filesystem>
#include <fstream>
#include <unistd.h>

namespace {

namespace fs = std::filesystem;

fs::path scratch(const std::string& name)
{
    const fs::path dir = fs::temp_directory_path() / ("cb_test_fclib_" + std::to_string(::getpid()));
    fs::create_directories(dir);
    return dir / name;
}

bool same_bits(const cb::SpMat& a, const cb::SpMat& b)
{
    if (a.rows() != b.rows() || a.cols() != b.cols() || a.nonZeros() != b.nonZeros()) return false;
    for (int k = 0; k <= a.outerSize(); ++k)
        if (a.outerIndexPtr()[k] != b.outerIndexPtr()[k]) return false;
    for (int k = 0; k < a.nonZeros(); ++k)
        if (a.innerIndexPtr()[k] != b.innerIndexPtr()[k] || a.valuePtr()[k] != b.valuePtr()[k]) return false;
    return true;
}

}  // namespace

TEST(FclibIo, RoundTripIsBitExactWithSolution)
{
    const fs::path path = scratch("coupled.hdf5");
    cb::Qp qp = cb::make_synthetic("coupled", {{"nx", 4}, {"ny", 2}, {"nz", 4}}, 13);
    qp.x0 = cb::Vec::LinSpaced(qp.n(), -1.0 / 3.0, 2.0 / 7.0);  // non-trivial bits in every entry
    const cb::SolverResult ref =
        cb::builtin_registry().create("active-set", {{"tol", 1e-10}})->solve(qp.view(), cb::SolveContext{});
    ASSERT_EQ(ref.status, cb::SolveStatus::CONVERGED) << ref.message;
    const cb::SnapshotExtras extras{ref.x, ref.lambda};
    if (cb::fclib_version().empty()) {
        EXPECT_THROW(cb::write_fclib_global(path.string(), qp, &extras), cb::InputError);
        GTEST_SKIP() << "FCLIB export not built";
    }
    cb::write_fclib_global(path.string(), qp, &extras);
    cb::SnapshotExtras back_extras;
    const cb::Qp back = cb::read_fclib_global(path.string(), &back_extras);
    EXPECT_TRUE(same_bits(back.A, qp.A));
    EXPECT_TRUE(same_bits(back.J, qp.J));
    EXPECT_TRUE(back.b == qp.b);
    EXPECT_TRUE(back.c == qp.c);
    EXPECT_TRUE(back.x0 == qp.x0);
    EXPECT_TRUE(back_extras.x_ref == ref.x);
    EXPECT_TRUE(back_extras.lambda_ref == ref.lambda);
    EXPECT_EQ(back.meta, qp.meta);
    fs::remove_all(path.parent_path());
}

TEST(FclibIo, WithoutSolutionNoReferenceIsRead)
{
    if (cb::fclib_version().empty()) GTEST_SKIP() << "FCLIB export not built";
    const fs::path path = scratch("plane.h5");
    const cb::Qp qp = cb::make_synthetic("plane", {{"nx", 2}, {"ny", 2}, {"nz", 2}}, 3);
    cb::write_fclib_global(path.string(), qp);
    cb::SnapshotExtras extras;
    const cb::Qp back = cb::read_fclib_global(path.string(), &extras);
    EXPECT_EQ(back.m(), qp.m());
    EXPECT_EQ(extras.x_ref.size(), 0);
    EXPECT_EQ(extras.lambda_ref.size(), 0);
    fs::remove_all(path.parent_path());
}

TEST(FclibIo, NotAnFclibFileIsAnInputErrorNamingTheGroup)
{
    if (cb::fclib_version().empty()) GTEST_SKIP() << "FCLIB export not built";
    const fs::path path = scratch("garbage.hdf5");
    {
        std::ofstream(path) << "not hdf5";
    }
    try {
        cb::read_fclib_global(path.string());
        FAIL() << "no error";
    } catch (const cb::InputError& e) {
        EXPECT_EQ(std::string(e.what()),
                  path.string() + ": /fclib_global: not an HDF5 file with an FCLIB global problem");
    }
    fs::remove_all(path.parent_path());
}

TEST(FclibIo, ExtensionsSelectFclib)
{
    EXPECT_TRUE(cb::is_fclib_path("a/b.hdf5"));
    EXPECT_TRUE(cb::is_fclib_path("b.h5"));
    EXPECT_FALSE(cb::is_fclib_path("b.qpsnap"));
    EXPECT_FALSE(cb::is_fclib_path("folder"));
}
