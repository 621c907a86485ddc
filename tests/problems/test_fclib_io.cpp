// FCLIB export (problems/fclib_io.*): a write/read round trip keeps every array bit for bit, and
// problems outside the frictionless mapping are refused with a message naming the field.
#include "problems/fclib_io.hpp"
#include "problems/synthetic.hpp"
#include "solvers/registry.hpp"

#ifdef CB_HAVE_FCLIB
#include "tests/problems/hdf5_edit.hpp"
#endif

#include <gtest/gtest.h>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sys/stat.h>
#include <sys/wait.h>
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
        EXPECT_EQ(std::string(e.what()), path.string() + ": file: not an HDF5 file");
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

#ifdef CB_HAVE_FCLIB
namespace {

/// A valid export of the 2x2x2 plane (n, m and nnz read back from it), edited by `edit`, then
/// read: the InputError's message, or "no error". Any crash or exit ends the test binary.
struct Hostile {
    fs::path path = scratch("hostile.hdf5");
    cb::Qp qp = cb::make_synthetic("plane", {{"nx", 2}, {"ny", 2}, {"nz", 2}}, 3);
    long n = 0, m = 0, nnz_a = 0, nnz_j = 0;
    Hostile()
    {
        n = long(qp.n());
        m = long(qp.m());
        nnz_a = long(qp.A.nonZeros());
        nnz_j = long(qp.J.nonZeros());
    }
    std::string read_after(const std::function<void(cb::test::Hdf5Edit&)>& edit)
    {
        fs::remove(path);
        cb::SnapshotExtras extras;
        extras.x_ref = cb::Vec::Ones(qp.n());
        extras.lambda_ref = cb::Vec::Ones(qp.m());
        cb::write_fclib_global(path.string(), qp, &extras);
        {
            cb::test::Hdf5Edit file(path.string(), false);
            edit(file);
        }
        try {
            cb::read_fclib_global(path.string(), &extras);
        } catch (const cb::InputError& e) {
            const std::string prefix = path.string() + ": ";
            const std::string what = e.what();
            return what.rfind(prefix, 0) == 0 ? what.substr(prefix.size()) : "(no file named) " + what;
        }
        return "no error";
    }
};

std::vector<long long> iota(long long count, long long first = 0)
{
    std::vector<long long> v(static_cast<size_t>(count));
    for (long long k = 0; k < count; ++k) v[size_t(k)] = first + k;
    return v;
}

}  // namespace

// Issue 27: each of these ended in SIGSEGV, SIGABRT, libfclib's exit(1) or uninitialised memory.
TEST(FclibHostile, LengthsMustEqualTheDeclaredSizes)
{
    Hostile h;
    const std::string n = std::to_string(h.n), nnz = std::to_string(h.nnz_a);
    EXPECT_EQ(h.read_after([](auto&) {}), "no error");
    EXPECT_EQ(
        h.read_after([&](auto& f) { f.put_reals("/fclib_global/M/x", std::vector<double>(size_t(h.nnz_a + 5), 1.0)); }),
        "/fclib_global/M/x: holds " + std::to_string(h.nnz_a + 5) + " values, /fclib_global/M/nzmax declares " + nnz);
    EXPECT_EQ(
        h.read_after([&](auto& f) { f.put_reals("/fclib_global/M/x", std::vector<double>(size_t(h.nnz_a - 1), 1.0)); }),
        "/fclib_global/M/x: holds " + std::to_string(h.nnz_a - 1) + " values, /fclib_global/M/nzmax declares " + nnz);
    EXPECT_EQ(h.read_after([&](auto& f) { f.put_ints("/fclib_global/M/nzmax", {h.nnz_a + 1000}); }),
              "/fclib_global/M/x: holds " + nnz + " values, /fclib_global/M/nzmax declares " +
                  std::to_string(h.nnz_a + 1000));
    EXPECT_EQ(h.read_after([&](auto& f) { f.put_ints("/fclib_global/M/i", iota(h.nnz_a - 2)); }),
              "/fclib_global/M/i: holds " + std::to_string(h.nnz_a - 2) + " values, /fclib_global/M/nzmax declares " +
                  nnz);
    EXPECT_EQ(h.read_after(
                  [&](auto& f) { f.put_reals("/fclib_global/vectors/f", std::vector<double>(size_t(h.n - 1), 0.0)); }),
              "/fclib_global/vectors/f: holds " + std::to_string(h.n - 1) + " values, /fclib_global/M/m declares " + n);
    EXPECT_EQ(h.read_after([&](auto& f) { f.put_reals("/guesses/1/v", std::vector<double>(size_t(h.n + 3), 0.0)); }),
              "/guesses/1/v: holds " + std::to_string(h.n + 3) + " values, /fclib_global/M/n declares " + n);
    EXPECT_EQ(h.read_after([&](auto& f) { f.put_reals("/solution/r", std::vector<double>(2, 0.0)); }),
              "/solution/r: holds 2 values, /fclib_global/H/n declares " + std::to_string(3 * h.m));
    // A huge declared size costs nothing: the vectors' lengths are checked before any matrix array.
    EXPECT_EQ(h.read_after([&](auto& f) {
        f.put_ints("/fclib_global/M/m", {2000000000});
        f.put_ints("/fclib_global/M/n", {2000000000});
        f.put_ints("/fclib_global/H/m", {2000000000});
    }),
              "/fclib_global/vectors/f: holds " + n + " values, /fclib_global/M/m declares 2000000000");
    EXPECT_EQ(h.read_after([&](auto& f) { f.put_unwritten("/fclib_global/vectors/f", hsize_t(h.n)); }),
              "/fclib_global/vectors/f: declares " + std::to_string(8 * h.n) +
                  " bytes but stores 0 (compressed or unwritten data are not read)");
}

TEST(FclibHostile, IndicesPointersTypesAndShapesAreChecked)
{
    Hostile h;
    EXPECT_EQ(h.read_after([&](auto& f) {
        std::vector<long long> p = iota(h.n + 1);
        p[1] = -5;
        p[0] = 0;
        f.put_ints("/fclib_global/M/p", p);
    }),
              "/fclib_global/M/p: entry 1 is -5: column pointers must be non-decreasing within 0..nzmax (" +
                  std::to_string(h.nnz_a) + ")");
    EXPECT_EQ(h.read_after([&](auto& f) {
        std::vector<long long> i = iota(h.nnz_a);
        for (auto& v : i) v = 0;
        i[3] = 1000000;
        f.put_ints("/fclib_global/M/i", i);
    }),
              "/fclib_global/M/i: entry 3 is 1000000, outside 0.." + std::to_string(h.n - 1));
    EXPECT_EQ(h.read_after([&](auto& f) { f.put_ints("/fclib_global/H/nz", {-3}); }),
              "/fclib_global/H/nz: must be >= 0 (triplets), -1 (CSC) or -2 (CSR), got -3");
    EXPECT_EQ(h.read_after([&](auto& f) { f.put_ints("/fclib_global/M/nzmax", {-1}); }),
              "/fclib_global/M/nzmax: must be in 0..2147483646, got -1");
    EXPECT_EQ(h.read_after([&](auto& f) { f.put_reals("/fclib_global/spacedim", {3.0}); }),
              "/fclib_global/spacedim: expected integers");
    EXPECT_EQ(h.read_after([&](auto& f) { f.put_ints("/fclib_global/spacedim", {2}); }),
              "/fclib_global/spacedim: must be 3, got 2");
    EXPECT_EQ(h.read_after([&](auto& f) {
        f.put_ints("/fclib_global/M/nz", {-2, -2}, {1, 2});
    }),
              "/fclib_global/M/nz: expected a 1-D array, found 2 dimensions");
    EXPECT_EQ(h.read_after([&](auto& f) { f.remove("/fclib_global/vectors/w"); }), "/fclib_global/vectors/w: missing");
    EXPECT_EQ(h.read_after([&](auto& f) { f.remove("/fclib_global/H"); }), "/fclib_global/H/nzmax: missing");
    EXPECT_EQ(h.read_after([&](auto& f) { f.put_ints("/guesses/number_of_guesses", {-7}); }),
              "/guesses/number_of_guesses: must be >= 0, got -7");
    EXPECT_EQ(h.read_after([&](auto& f) { f.remove("/guesses/1"); }), "/guesses/1/v: missing");
}

TEST(FclibHostile, FrictionHugeOrNanMuAndEqualityConstraintsAreRefused)
{
    Hostile h;
    const auto mu_of = [&](double value) {
        return h.read_after([&](auto& f) {
            std::vector<double> mu(size_t(h.m), 0.0);
            mu[1] = value;
            f.put_reals("/fclib_global/vectors/mu", mu);
        });
    };
    const std::string friction = " (friction is not supported: only mu = 0 maps onto the QP)";
    EXPECT_EQ(mu_of(0.3), "/fclib_global/vectors/mu: contact 1 has mu = 0.29999999999999999" + friction);
    EXPECT_EQ(mu_of(1e308), "/fclib_global/vectors/mu: contact 1 has mu = 1e+308" + friction);
    EXPECT_EQ(mu_of(std::nan("")), "/fclib_global/vectors/mu: contact 1 has mu = nan" + friction);
    EXPECT_EQ(h.read_after([&](auto& f) { f.put_ints("/fclib_global/G/n", {2}); }),
              "/fclib_global/G: equality constraints are not supported (2 columns)");
    // Free text in the description is not metadata, and a deeply nested one is no crash.
    EXPECT_EQ(h.read_after([&](auto& f) {
        f.put_text("/fclib_global/info/description", std::string(100000, '[') + std::string(100000, ']'));
    }),
              "no error");
}

TEST(FclibHostile, ExportRefusesNoContactsAndSpecialTargetsLeavingNothing)
{
    const fs::path dir = scratch("export");
    fs::create_directories(dir);
    cb::Qp qp = cb::make_synthetic("plane", {{"nx", 2}, {"ny", 2}, {"nz", 2}}, 3);
    cb::Qp unconstrained = qp;
    unconstrained.J.resize(0, qp.n());
    unconstrained.c.resize(0);
    const std::string target = (dir / "free.hdf5").string();
    std::string message = "no error";
    try {
        cb::write_fclib_global(target, unconstrained);
    } catch (const cb::InputError& e) {
        message = e.what();
    }
    EXPECT_EQ(message, target + ": J: the QP has no constraints (m = 0); FCLIB stores no problem without contacts "
                                "(write a .qpsnap or a Matrix Market folder instead)");
    const std::string fifo = (dir / "fifo.hdf5").string();
    ASSERT_EQ(::mkfifo(fifo.c_str(), 0644), 0);
    message = "no error";
    try {
        cb::write_fclib_global(fifo, qp);
    } catch (const cb::InputError& e) {
        message = e.what();
    }
    EXPECT_EQ(message, fifo + ": is a FIFO: not replaced (this output needs a regular file)");
    struct stat st {};
    ASSERT_EQ(::stat(fifo.c_str(), &st), 0);
    EXPECT_TRUE(S_ISFIFO(st.st_mode)) << "the FIFO was replaced";
    // A temporary of an interrupted export (its process is gone) is removed by the next one.
    const pid_t child = ::fork();
    ASSERT_GE(child, 0);
    if (child == 0) ::_exit(0);
    ASSERT_EQ(::waitpid(child, nullptr, 0), child);
    const fs::path stale = dir / ("plane.hdf5.tmp." + std::to_string(child));
    std::ofstream(stale) << "half an HDF5 file";
    fs::last_write_time(stale, fs::file_time_type::clock::now() - std::chrono::hours(1));  // left over, not young
    cb::write_fclib_global((dir / "plane.hdf5").string(), qp);
    EXPECT_FALSE(fs::exists(stale));
    std::vector<std::string> names;
    for (const auto& e : fs::directory_iterator(dir)) names.push_back(e.path().filename().string());
    std::sort(names.begin(), names.end());
    EXPECT_EQ(names, (std::vector<std::string>{"fifo.hdf5", "plane.hdf5"}));
    fs::remove_all(dir);
}
#endif

namespace {
/// The scratch folder of this process (the hostile tests leave their edited file in it).
class CleanUp : public ::testing::Environment {
public:
    void TearDown() override { fs::remove_all(scratch("x").parent_path()); }
};
const auto* const CLEAN_UP = ::testing::AddGlobalTestEnvironment(new CleanUp);
}  // namespace
