// Qp::a_symmetric, the readers' word that A equals A' to the bit (the block products then skip their
// own check of A's mirror): every reader sets it on what it returns, and each returned A is
// checked here again, independently; QPs no reader made keep it false; select_rows copies it.
#include "problems/fclib_io.hpp"
#include "problems/matrix_market.hpp"
#include "problems/qpsnap.hpp"
#include "problems/siconos_dat.hpp"
#include "problems/synthetic.hpp"
#include "solvers/mprgp/decouple.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <unistd.h>

namespace cb {
namespace a_symmetric_flag_test {

namespace fs = std::filesystem;

/// Whether A(i, j) == A(j, i) for every i, j (absent entries are 0), found without the readers'
/// or the block build's code: each entry against the transpose's.
bool equals_its_transpose(const SpMat& A)
{
    if (A.rows() != A.cols()) return false;
    const SpMat At = A.transpose();
    for (Eigen::Index i = 0; i < A.outerSize(); ++i) {
        for (SpMat::InnerIterator it(A, i); it; ++it)
            if (At.coeff(i, it.col()) != it.value()) return false;
        for (SpMat::InnerIterator it(At, i); it; ++it)
            if (A.coeff(i, it.col()) != it.value()) return false;
    }
    return true;
}

fs::path scratch(const std::string& name)
{
    const fs::path dir = fs::temp_directory_path() / ("cb_test_a_symmetric_" + std::to_string(::getpid()));
    fs::create_directories(dir);
    return dir / name;
}

/// A synthetic QP whose A is off its mirror by rounding only: one upper entry one ulp up, and a
/// tiny one-sided entry (1e-14 of the largest) with no mirror.
Qp nearly_symmetric_qp(bool one_sided)
{
    Qp qp = make_synthetic("plane", {{"nx", 3}, {"ny", 3}, {"nz", 3}}, 5);
    Eigen::MatrixXd dense(qp.A);
    dense(0, 1) = std::nextafter(dense(0, 1), 1e300);
    if (one_sided) dense(0, qp.n() - 1) = 1e-14 * dense.cwiseAbs().maxCoeff();
    qp.A = dense.sparseView(0.0, 0.0);
    qp.A.makeCompressed();
    return qp;
}

void expect_flag_holds(const Qp& qp, const std::string& what)
{
    EXPECT_TRUE(qp.a_symmetric) << what;
    EXPECT_TRUE(equals_its_transpose(qp.A)) << what << ": a reader set a_symmetric on an A that differs from A'";
    EXPECT_TRUE(qp.view().a_symmetric) << what;
}

}  // namespace a_symmetric_flag_test

using namespace a_symmetric_flag_test;

// The independent check can fail: it is what would catch a reader setting the flag wrongly.
TEST(ASymmetricFlag, TheIndependentCheckSeesOneBitOff)
{
    const Qp off = nearly_symmetric_qp(false);
    EXPECT_FALSE(equals_its_transpose(off.A));
    EXPECT_FALSE(equals_its_transpose(nearly_symmetric_qp(true).A));
    EXPECT_FALSE(off.a_symmetric);  // no reader made it
}

TEST(ASymmetricFlag, QpsnapReaderSetsItOnWhatItSymmetrised)
{
    for (const bool one_sided : {false, true}) {
        const std::string path = scratch(one_sided ? "one_sided.qpsnap" : "one_ulp.qpsnap").string();
        write_qpsnap(path, nearly_symmetric_qp(one_sided));
        expect_flag_holds(read_qpsnap(path), path);
    }
    for (const char* name : {"plane_2x2x2.qpsnap", "lmgc_perio_normal.qpsnap"}) {
        const std::string path = (fs::path(CB_TEST_DATA_DIR) / name).string();
        expect_flag_holds(read_qpsnap(path), path);
    }
}

TEST(ASymmetricFlag, MatrixMarketReaderSetsItOnWhatItSymmetrised)
{
    for (const bool one_sided : {false, true}) {
        const fs::path dir = scratch(one_sided ? "mtx_one_sided" : "mtx_one_ulp");
        write_matrix_market_folder(dir.string(), nearly_symmetric_qp(one_sided));
        expect_flag_holds(read_matrix_market_folder(dir.string()), dir.string());
    }
}

TEST(ASymmetricFlag, FclibReaderSetsItOnRealFiles)
{
    // Two global problems (A = M) and two local ones (A = W_NN, Capsules' averaged with its mirror).
    FclibReadOptions drop, drop_and_average;
    drop.drop_friction = drop_and_average.drop_friction = true;
    drop_and_average.symmetrise = true;
    const std::pair<const char*, const FclibReadOptions*> files[] = {
        {"LMGC_GlobalFrictionContactProblem00046.hdf5", &drop},
        {"CubeH8.hdf5", &drop},
        {"Capsules-i125-1213.hdf5", &drop_and_average},
        {"LMGC_100_PR_PerioBox-i00361-60-03000.hdf5", &drop}};
    for (const auto& [name, options] : files) {
        const std::string path = (fs::path(CB_TEST_DATA_DIR) / "fclib" / name).string();
        expect_flag_holds(read_fclib(path, nullptr, *options), path);
    }
}

TEST(ASymmetricFlag, SiconosDatReaderSetsItOnASymmetrisedLcp)
{
    // An LCP whose M is off its mirror beyond rounding: averaged when asked (options.symmetrise).
    const std::string path = scratch("lcp.dat").string();
    std::ofstream(path) << "3\n0\n3\n3\n3\t3\n4 1 0\n1.5 5 2\n0 2 6\n-1 -2 -3\n";  // column-major
    FclibReadOptions symmetrise;
    symmetrise.symmetrise = true;
    const Qp qp = read_siconos_dat_qp(path, symmetrise);
    EXPECT_EQ(qp.A.coeff(0, 1), 1.25);
    expect_flag_holds(qp, path);
}

TEST(ASymmetricFlag, GeneratedQpsLeaveItUnsetAndSelectRowsCopiesIt)
{
    Qp qp = make_synthetic("plane", {{"nx", 3}, {"ny", 3}, {"nz", 3}}, 5);
    EXPECT_FALSE(qp.a_symmetric);  // symmetric by construction, but no reader checked it
    EXPECT_FALSE(qp.view().a_symmetric);
    ASSERT_GE(qp.m(), 2);
    EXPECT_FALSE(select_rows(qp, {0, 1}).a_symmetric);
    const std::string path = scratch("plane.qpsnap").string();
    write_qpsnap(path, qp);
    const Qp read = read_qpsnap(path);
    ASSERT_TRUE(read.a_symmetric);
    const Qp rows = select_rows(read, {1});
    EXPECT_TRUE(rows.a_symmetric);  // the same A
    EXPECT_TRUE(equals_its_transpose(rows.A));
}

}  // namespace cb
