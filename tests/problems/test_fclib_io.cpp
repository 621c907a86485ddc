// FCLIB export (problems/fclib_io.*): a write/read round trip keeps every array bit for bit, and
// problems outside the frictionless mapping are refused with a message naming the field.
#include "problems/fclib_io.hpp"
#include "problems/synthetic.hpp"
#include "solvers/core/registry.hpp"

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
    // Issue 41: i and x holding just the p[n] entries used (nzmax larger) is how other writers write.
    EXPECT_EQ(h.read_after([&](auto& f) { f.put_ints("/fclib_global/M/nzmax", {h.nnz_a + 1000}); }), "no error");
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
              "/fclib_global/M/p: entry 1 is -5: pointers must be non-decreasing within 0..nzmax (" +
                  std::to_string(h.nnz_a) + ")");
    EXPECT_EQ(h.read_after([&](auto& f) {
        std::vector<long long> i = iota(h.nnz_a);
        for (auto& v : i) v = 0;
        i[3] = 1000000;
        f.put_ints("/fclib_global/M/i", i);
    }),
              "/fclib_global/M/i: entry 3 is 1000000, outside 0.." + std::to_string(h.n - 1) + " (column indices)");
    EXPECT_EQ(h.read_after([&](auto& f) { f.put_ints("/fclib_global/H/nz", {-3}); }),
              "/fclib_global/H/nz: must be >= 0 (triplets), -1 (CSC) or -2 (CSR), got -3");
    EXPECT_EQ(h.read_after([&](auto& f) { f.put_ints("/fclib_global/M/nzmax", {-1}); }),
              "/fclib_global/M/nzmax: must be in 0..2147483646, got -1");
    EXPECT_EQ(h.read_after([&](auto& f) { f.put_reals("/fclib_global/spacedim", {3.0}); }),
              "/fclib_global/spacedim: expected integers");
    EXPECT_EQ(h.read_after([&](auto& f) { f.put_ints("/fclib_global/spacedim", {4}); }),
              "/fclib_global/spacedim: must be 2 or 3, got 4");
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
    const std::string friction = ": this fclib_global problem has friction: read it with keep_friction (as "
                                 "`convert` does: a snapshot of version 2) or drop_friction (its normal part)";
    EXPECT_EQ(mu_of(0.3), "/fclib_global/vectors/mu: contact 1 has mu = 0.29999999999999999" + friction);
    EXPECT_EQ(mu_of(1e308), "/fclib_global/vectors/mu: contact 1 has mu = 1e+308" + friction);
    EXPECT_EQ(mu_of(std::nan("")),
              "/fclib_global/vectors/mu: contact 1 has mu = nan (a friction coefficient is finite and >= 0)");
    EXPECT_EQ(mu_of(-0.5),
              "/fclib_global/vectors/mu: contact 1 has mu = -0.5 (a friction coefficient is finite and >= 0)");
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

// Issue 41: FCLIB as real writers write it. A global problem built from scratch the way Siconos
// and LMGC90 write one: triplets in CSparse's convention (p = columns, i = rows), M as its upper
// triangle, x with nzmax values, H with tangential columns and w with tangential entries.
namespace {

void write_global_triplets(cb::test::Hdf5Edit& f, std::vector<double> mu)
{
    f.put_ints("/fclib_global/spacedim", {3}, {1});
    // M = [4 1 0; 1 4 1; 0 1 4] as its upper triangle: (row, col) = (0,0) (0,1) (1,1) (1,2) (2,2).
    f.put_ints("/fclib_global/M/nzmax", {7}, {1});
    f.put_ints("/fclib_global/M/m", {3}, {1});
    f.put_ints("/fclib_global/M/n", {3}, {1});
    f.put_ints("/fclib_global/M/nz", {5}, {1});
    f.put_ints("/fclib_global/M/p", {0, 1, 1, 2, 2});
    f.put_ints("/fclib_global/M/i", {0, 0, 1, 1, 2});
    f.put_reals("/fclib_global/M/x", {4.0, 1.0, 4.0, 1.0, 4.0, 99.0, 99.0});  // nzmax values, the last 2 unused
    // H (3 x 6): contact 0's normal is e0 and a tangent 0.5 e0; contact 1's normal e2.
    f.put_ints("/fclib_global/H/nzmax", {3}, {1});
    f.put_ints("/fclib_global/H/m", {3}, {1});
    f.put_ints("/fclib_global/H/n", {6}, {1});
    f.put_ints("/fclib_global/H/nz", {3}, {1});
    f.put_ints("/fclib_global/H/p", {0, 1, 3});
    f.put_ints("/fclib_global/H/i", {0, 0, 2});
    f.put_reals("/fclib_global/H/x", {1.0, 0.5, 1.0});
    f.put_reals("/fclib_global/vectors/f", {1.0, 2.0, 3.0});
    f.put_reals("/fclib_global/vectors/w", {0.1, 0.7, 0.0, -0.2, 0.0, 0.0});
    f.put_reals("/fclib_global/vectors/mu", mu);
    f.put_text("/fclib_global/info/title", "written like LMGC90");
}

/// A local problem of 2 contacts: W (6 x 6, CSR) with W_NN = [2 -1; -1 3] at rows/columns 0 and 3.
void write_local(cb::test::Hdf5Edit& f, std::vector<double> mu, double w03 = -1.0)
{
    f.put_ints("/fclib_local/spacedim", {3}, {1});
    f.put_ints("/fclib_local/W/nzmax", {8}, {1});
    f.put_ints("/fclib_local/W/m", {6}, {1});
    f.put_ints("/fclib_local/W/n", {6}, {1});
    f.put_ints("/fclib_local/W/nz", {-2}, {1});
    f.put_ints("/fclib_local/W/p", {0, 2, 3, 4, 6, 7, 8});
    f.put_ints("/fclib_local/W/i", {0, 3, 1, 2, 0, 3, 4, 5});
    f.put_reals("/fclib_local/W/x", {2.0, w03, 1.0, 1.0, -1.0, 3.0, 1.0, 1.0});
    f.put_reals("/fclib_local/vectors/q", {-1.0, 0.3, 0.4, 2.0, 0.0, 0.0});
    f.put_reals("/fclib_local/vectors/mu", mu);
    f.put_reals("/solution/r", {0.5, 0.0, 0.0, 0.0, 0.0, 0.0});
    f.put_reals("/solution/u", {0.0, 0.0, 0.0, 1.5, 0.0, 0.0});
}

std::string error_of(const std::function<void()>& read, const std::string& path)
{
    try {
        read();
    } catch (const cb::InputError& e) {
        const std::string what = e.what();
        return what.rfind(path + ": ", 0) == 0 ? what.substr(path.size() + 2) : "(no file named) " + what;
    }
    return "no error";
}

}  // namespace

TEST(FclibWriters, TripletsInCSparseConventionAndOneTriangleMirrored)
{
    const std::string path = scratch("triplets.hdf5").string();
    {
        cb::test::Hdf5Edit f(path, true);
        write_global_triplets(f, {0.0, 0.0});
    }
    cb::SnapshotExtras extras;
    const cb::Qp qp = cb::read_fclib(path, &extras);
    Eigen::MatrixXd A(3, 3);
    A << 4, 1, 0, 1, 4, 1, 0, 1, 4;
    EXPECT_EQ(Eigen::MatrixXd(qp.A), A);
    Eigen::MatrixXd J(2, 3);
    J << 1, 0, 0, 0, 0, 1;  // mu = 0: the tangent carries no force, exactly
    EXPECT_EQ(Eigen::MatrixXd(qp.J), J);
    EXPECT_EQ(qp.b, cb::Vec::LinSpaced(3, 1.0, 3.0));
    EXPECT_EQ(qp.c, (cb::Vec(2) << -0.1, 0.2).finished());
    EXPECT_EQ(qp.x0, cb::Vec::Zero(3));  // no /guesses: optional groups may be absent
    EXPECT_EQ(extras.x_ref.size(), 0);
    const nlohmann::json& provenance = qp.meta.at("provenance");
    EXPECT_EQ(provenance.at("format"), "fclib_global");
    EXPECT_EQ(provenance.at("title"), "written like LMGC90");
    EXPECT_EQ(provenance.at("matrices").at("/fclib_global/M"), "stored as its upper triangle: mirrored");
    EXPECT_FALSE(provenance.contains("dropped_friction"));
    // Before issue 41 the triplets were read the other way round and x had to hold nzmax values.
    {
        cb::test::Hdf5Edit f(path, false);
        f.put_reals("/fclib_global/M/x", {4.0, 1.0, 4.0, 1.0, 4.0});  // nz values: accepted too
        f.put_ints("/fclib_global/M/p", {0, 1, 1, 2, 3});             // column 3 of a 3 x 3 matrix
    }
    EXPECT_EQ(error_of([&] { cb::read_fclib(path); }, path),
              "/fclib_global/M/p: entry 4 is 3, outside 0..2 (column indices)");
}

TEST(FclibWriters, FrictionIsDroppedOnlyWhenAskedAndRecorded)
{
    const std::string path = scratch("friction.hdf5").string();
    {
        cb::test::Hdf5Edit f(path, true);
        write_global_triplets(f, {0.0, 0.4});
    }
    EXPECT_EQ(error_of([&] { cb::read_fclib(path); }, path),
              "/fclib_global/vectors/mu: contact 1 has mu = 0.40000000000000002: this fclib_global problem has "
              "friction: read it with keep_friction (as `convert` does: a snapshot of version 2) or drop_friction "
              "(its normal part)");
    cb::FclibReadOptions drop;
    drop.drop_friction = true;
    const cb::Qp qp = cb::read_fclib(path, nullptr, drop);
    EXPECT_EQ(qp.m(), 2);
    const nlohmann::json& dropped = qp.meta.at("provenance").at("dropped_friction");
    EXPECT_EQ(dropped.at("mu_min"), 0.0);
    EXPECT_EQ(dropped.at("mu_max"), 0.4);
}

TEST(FclibWriters, LocalProblemIsItsNormalBlock)
{
    const std::string path = scratch("local.hdf5").string();
    {
        cb::test::Hdf5Edit f(path, true);
        write_local(f, {0.0, 0.0});
    }
    cb::SnapshotExtras extras;
    const cb::Qp qp = cb::read_fclib(path, &extras);
    Eigen::MatrixXd A(2, 2);
    A << 2, -1, -1, 3;
    EXPECT_EQ(Eigen::MatrixXd(qp.A), A);
    EXPECT_EQ(Eigen::MatrixXd(qp.J), Eigen::MatrixXd::Identity(2, 2));
    EXPECT_EQ(qp.b, (cb::Vec(2) << 1.0, -2.0).finished());
    EXPECT_EQ(qp.c, cb::Vec::Zero(2));
    // mu = 0: the file's solution is the QP's (x = r_N, lambda = u_N).
    EXPECT_EQ(extras.x_ref, (cb::Vec(2) << 0.5, 0.0).finished());
    EXPECT_EQ(extras.lambda_ref, (cb::Vec(2) << 0.0, 1.5).finished());
    EXPECT_EQ(qp.meta.at("provenance").at("mapping"), "A = W_NN, b = -q_N, J = I, c = 0 (x = r_N, lambda = u_N)");
    EXPECT_EQ(cb::fclib_kind(path), "fclib_local");
    EXPECT_EQ(error_of([&] { cb::read_fclib_global(path); }, path),
              "/fclib_global: missing: this is an fclib_local problem, not an fclib_global one");
    {
        cb::test::Hdf5Edit f(path, true);
        write_local(f, {0.0, 0.25});
    }
    EXPECT_EQ(error_of([&] { cb::read_fclib(path); }, path),
              "/fclib_local/vectors/mu: contact 1 has mu = 0.25: this fclib_local problem has friction, which a "
              "snapshot cannot hold (it has no A); `convert --drop-friction` keeps its normal part (recorded in the "
              "snapshot), `friction-solve` solves a 3-D one with its friction");
    cb::FclibReadOptions drop;
    drop.drop_friction = true;
    const cb::Qp dropped = cb::read_fclib(path, &extras, drop);
    EXPECT_EQ(Eigen::MatrixXd(dropped.A), A);
    EXPECT_EQ(extras.x_ref.size(), 0) << "a frictional file's solution is not the QP's";
}

TEST(FclibWriters, AsymmetricMatrixRefusedOrSymmetrisedWhenAsked)
{
    const std::string path = scratch("asymmetric.hdf5").string();
    {
        cb::test::Hdf5Edit f(path, true);
        write_local(f, {0.0, 0.0}, -1.25);
    }
    EXPECT_EQ(error_of([&] { cb::read_fclib(path); }, path),
              "/fclib_local/W: the normal block W_NN (indexed by contact) is not symmetric: (0, 1) = -1.25 but (1, 0) "
              "= -1 (difference 0.25 > 1e-12 max|entry| = 3.0000000000000001e-12; one triangle alone is mirrored; "
              "`convert --symmetrise` takes (A + A')/2)");
    cb::FclibReadOptions symmetrise;
    symmetrise.symmetrise = true;
    const cb::Qp qp = cb::read_fclib(path, nullptr, symmetrise);
    EXPECT_EQ(qp.A.coeff(0, 1), -1.125);
    EXPECT_EQ(qp.A.coeff(1, 0), -1.125);
    EXPECT_EQ(qp.meta.at("provenance").at("matrices").at("/fclib_local/W").at("max_asymmetry"), 0.25);
}

// Issue 42 F4: an empty problem passed the reader and crashed three solvers.
TEST(FclibHostile, EmptyProblemIsRefused)
{
    Hostile h;
    EXPECT_EQ(h.read_after([&](auto& f) {
        for (const char* group : {"/fclib_global/M", "/fclib_global/H"}) {
            for (const char* size : {"/m", "/n", "/nzmax"}) f.put_ints(std::string(group) + size, {0}, {1});
            f.put_ints(std::string(group) + "/nz", {-1}, {1});
            f.put_ints(std::string(group) + "/p", {0}, {1});
            f.put_ints(std::string(group) + "/i", {}, {0});
            f.put_reals(std::string(group) + "/x", {}, {0});
        }
        for (const char* v : {"f", "w", "mu"}) f.put_reals(std::string("/fclib_global/vectors/") + v, {}, {0});
        f.remove("/guesses");
    }),
              "/fclib_global/M/n: the problem has no unknowns (n = 0)");
}

// Issue 40 F1/F2 and issue 42 F3: external links and external storage read other files (a FIFO
// blocks, /dev/zero fills memory, a local secret is copied into the snapshot). Refused, never opened.
TEST(FclibHostile, ExternalLinksAndExternalStorageAreRefused)
{
    Hostile h;
    const std::string other = scratch("other.h5").string();
    cb::write_fclib_global(other, h.qp);
    const std::string fifo = scratch("fifo.h5").string();
    ::unlink(fifo.c_str());
    ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
    const std::string link = ": is an external link to another file (not followed: the file must hold its own data)";
    EXPECT_EQ(h.read_after([&](auto& f) { f.put_external_link("/fclib_global/M", other, "/fclib_global/M"); }),
              "/fclib_global/M" + link);
    EXPECT_EQ(h.read_after([&](auto& f) { f.put_external_link("/fclib_global/M", fifo, "/M"); }),
              "/fclib_global/M" + link);
    EXPECT_EQ(h.read_after([&](auto& f) { f.put_external_link("/fclib_global/vectors/f", other, "/x"); }),
              "/fclib_global/vectors/f" + link);
    const std::string secret = scratch("secret.txt").string();
    std::ofstream(secret) << std::string(size_t(8 * h.n), 's');
    const std::string storage =
        ": stored in an external file (external storage is not read: the file must hold its own data)";
    for (const std::string& target : {secret, fifo, std::string("/dev/zero")})
        EXPECT_EQ(
            h.read_after([&](auto& f) { f.put_external_storage("/fclib_global/vectors/f", hsize_t(h.n), target); }),
            "/fclib_global/vectors/f" + storage)
            << target;
    EXPECT_EQ(
        h.read_after([&](auto& f) { f.put_external_storage("/fclib_global/M/x", hsize_t(h.nnz_a), "/dev/zero"); }),
        "/fclib_global/M/x" + storage);
    ::unlink(fifo.c_str());
}

// Hostile mutants of the real files (tests/data/fclib): each ends in an InputError naming the field.
TEST(FclibHostile, MutantsOfRealFilesNameTheField)
{
    const fs::path data = fs::path(CB_TEST_DATA_DIR) / "fclib";
    const std::string path = scratch("mutant.hdf5").string();
    cb::FclibReadOptions drop;
    drop.drop_friction = true;
    auto mutant = [&](const char* name, const std::function<void(cb::test::Hdf5Edit&)>& edit) {
        fs::copy_file(data / name, path, fs::copy_options::overwrite_existing);
        fs::permissions(path, fs::perms::owner_read | fs::perms::owner_write);
        {
            cb::test::Hdf5Edit f(path, false);
            edit(f);
        }
        return error_of([&] { cb::read_fclib(path, nullptr, drop); }, path);
    };
    EXPECT_EQ(mutant("CubeH8.hdf5", [](auto&) {}), "no error");
    EXPECT_EQ(mutant("CubeH8.hdf5",
                     [](auto& f) {
                         std::vector<long long> p(3168, 0);
                         p[7] = 500;
                         f.put_ints("/fclib_global/M/p", p);
                     }),
              "/fclib_global/M/p: entry 7 is 500, outside 0..161 (column indices)");
    EXPECT_EQ(mutant("LMGC_GlobalFrictionContactProblem00046.hdf5",
                     [](auto& f) { f.put_ints("/fclib_global/H/i", std::vector<long long>(10, 60)); }),
              "/fclib_global/H/i: holds 10 values, /fclib_global/H/nz declares 405");
    EXPECT_EQ(mutant("LMGC_GlobalFrictionContactProblem00046.hdf5",
                     [](auto& f) { f.put_ints("/fclib_global/M/m", {161}, {1}); }),
              "/fclib_global/M: not square: m = 161, n = 162");
    EXPECT_EQ(mutant("Capsules-i125-1213.hdf5",
                     [](auto& f) {
                         std::vector<double> q(858, 0.5);
                         q[5] = std::nan("");
                         f.put_reals("/fclib_local/vectors/q", q);
                     }),
              "/fclib_local/vectors/q: entry 5 is nan (values must be finite)");
    EXPECT_EQ(mutant("LMGC_100_PR_PerioBox-i00361-60-03000.hdf5",
                     [](auto& f) { f.put_ints("/fclib_local/W/m", {179}, {1}); }),
              "/fclib_local/W: not square: m = 179, n = 180");
    EXPECT_EQ(mutant("LMGC_100_PR_PerioBox-i00361-60-03000.hdf5",
                     [](auto& f) { f.put_ints("/fclib_local/W/nz", {-7}, {1}); }),
              "/fclib_local/W/nz: must be >= 0 (triplets), -1 (CSC) or -2 (CSR), got -7");
    // CubeH8's M is an upper triangle; one entry moved below the diagonal makes it neither.
    const std::string moved = mutant("CubeH8.hdf5", [](auto& f) {
        std::vector<long long> p(3168), i(3168);
        for (int k = 0; k < 3168; ++k) p[size_t(k)] = i[size_t(k)] = k % 162;  // the diagonal ...
        p[1] = 5;                                                              // ... and (1, 5) ...
        i[2] = 7;                                                              // ... and (7, 2)
        f.put_ints("/fclib_global/M/p", p);
        f.put_ints("/fclib_global/M/i", i);
    });
    EXPECT_EQ(moved, "/fclib_global/M: M is not symmetric: (2, 7) = 0 but (7, 2) = 5.1654369212962976 (difference "
                     "5.1654369212962976 > 1e-12 max|entry| = 0.00051225275878276453; one triangle alone is mirrored; "
                     "`convert --symmetrise` takes (A + A')/2)");
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
