// Format recognition by content (problems/format_sniff.*, issue 41): every command names the
// format of a file it cannot take and says how to convert it. Before, `info`, `solve` and `judge`
// on an HDF5, .dat or .npy file printed a qpsnap "header length" read from its signature.
#include "problems/fclib_io.hpp"
#include "problems/format_sniff.hpp"
#include "problems/synthetic.hpp"
#include "tests/harness/cli_test_util.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <sys/stat.h>

namespace {

namespace fs = std::filesystem;
using cb::FileFormat;

const fs::path TEST_DATA = fs::path(CB_TEST_DATA_DIR);

std::string sniff_error_of(const std::function<void()>& f)
{
    try {
        f();
    } catch (const cb::InputError& e) {
        return e.what();
    }
    return "no error";
}

TEST(FormatSniff, EachFormatByItsContent)
{
    const fs::path work = cb::test::make_test_work_dir("format_sniff");
    EXPECT_EQ(cb::sniff_format((TEST_DATA / "plane_2x2x2.qpsnap").string()), FileFormat::QPSNAP);
    EXPECT_EQ(cb::sniff_format((TEST_DATA / "fclib/GFC3D_OneContact.dat").string()), FileFormat::SICONOS_DAT);
    EXPECT_EQ(cb::sniff_format((TEST_DATA / "fclib/GFC3D_TwoRods1.dat").string()), FileFormat::SICONOS_DAT);
    if (!cb::fclib_version().empty()) {
        EXPECT_EQ(cb::sniff_format((TEST_DATA / "fclib/CubeH8.hdf5").string()), FileFormat::FCLIB_GLOBAL);
        EXPECT_EQ(cb::sniff_format((TEST_DATA / "fclib/Capsules-i125-1213.hdf5").string()), FileFormat::FCLIB_LOCAL);
    }
    // The name does not decide: an FCLIB file named .qpsnap, a snapshot named .hdf5.
    fs::copy_file(TEST_DATA / "fclib/CubeH8.hdf5", work / "cube.qpsnap");
    fs::copy_file(TEST_DATA / "plane_2x2x2.qpsnap", work / "plane.hdf5");
    EXPECT_EQ(cb::sniff_format((work / "plane.hdf5").string()), FileFormat::QPSNAP);
    EXPECT_EQ(cb::sniff_format((work / "cube.qpsnap").string()),
              cb::fclib_version().empty() ? FileFormat::HDF5 : FileFormat::FCLIB_GLOBAL);
    std::ofstream(work / "x.npy") << "\x93NUMPY\x01\x00v\x00{'descr': '<f8', 'fortran_order': False, 'shape': (3,), }";
    EXPECT_EQ(cb::sniff_format((work / "x.npy").string()), FileFormat::NPY);
    std::ofstream(work / "b.mtx") << "%%MatrixMarket matrix array real general\n1 1\n2\n";
    EXPECT_EQ(cb::sniff_format((work / "b.mtx").string()), FileFormat::MATRIX_MARKET_FILE);
    fs::create_directories(work / "mm");
    std::ofstream(work / "mm" / "A.mtx") << "%%MatrixMarket matrix coordinate real general\n";
    EXPECT_EQ(cb::sniff_format((work / "mm").string()), FileFormat::MATRIX_MARKET_FOLDER);
    std::ofstream(work / "text.txt") << "hello";
    EXPECT_EQ(cb::sniff_format((work / "text.txt").string()), FileFormat::UNKNOWN);
    // A FIFO is refused by name, never opened for reading (which would block).
    const std::string fifo = (work / "fifo.qpsnap").string();
    ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
    EXPECT_EQ(sniff_error_of([&] { cb::sniff_format(fifo); }), fifo + ": not a regular file (a FIFO)");
    fs::remove_all(work);
}

TEST(FormatSniff, CommandsNameTheFormatAndSuggestConvert)
{
    const fs::path work = cb::test::make_test_work_dir("format_commands");
    const std::string bin = cb::test::contactbench_binary();
    const std::string dat = (TEST_DATA / "fclib/GFC3D_OneContact.dat").string();
    auto run = [&](const std::string& args) { return cb::test::run_captured(bin + " " + args, work); };

    // A Siconos .dat is summarised by info (this global one named, not imported: problems/siconos_dat.hpp);
    // solve suggests convert or friction-solve.
    const auto info_dat = run("info '" + dat + "' --json");
    ASSERT_EQ(info_dat.status, 0) << info_dat.err;
    EXPECT_EQ(nlohmann::json::parse(info_dat.out).at("format"), "siconos_dat");
    EXPECT_EQ(nlohmann::json::parse(info_dat.out).at("imported"), false);
    const auto solve_dat = run("solve '" + dat + "' --solver pgs");
    EXPECT_EQ(solve_dat.status, 2);
    EXPECT_EQ(solve_dat.err, "contactbench solve: error: " + dat +
                                 ": format: a Siconos numerics text dump (.dat), not a .qpsnap snapshot (solve reads "
                                 ".qpsnap snapshots); convert a local problem first: contactbench convert " +
                                 dat +
                                 " OUT.qpsnap --drop-friction (its normal part), or solve it with its friction: "
                                 "contactbench friction-solve " +
                                 dat + "\n");
    std::ofstream(work / "x.npy") << "\x93NUMPY\x01\x00v\x00{'descr': '<f8', 'fortran_order': False, 'shape': (3,), }";
    const auto judge_npy = run("judge '" + (work / "x.npy").string() + "' '" + (work / "x.npy").string() + "'");
    EXPECT_EQ(judge_npy.status, 2);
    EXPECT_NE(judge_npy.err.find("x.npy: format: a NumPy array (.npy), not a .qpsnap snapshot (judge reads .qpsnap "
                                 "snapshots); a snapshot holds a whole QP: write one from numpy/scipy arrays with "
                                 "plots/qpsnap.py's write_qpsnap"),
              std::string::npos)
        << judge_npy.err;
    if (cb::fclib_version().empty()) return;
    const std::string cube = (TEST_DATA / "fclib/CubeH8.hdf5").string();
    const auto solve = run("solve '" + cube + "' --solver active-set");
    EXPECT_EQ(solve.status, 2);
    EXPECT_EQ(solve.err, "contactbench solve: error: " + cube +
                             ": format: an FCLIB fclib_global problem (HDF5), not a .qpsnap snapshot (solve reads "
                             ".qpsnap snapshots); convert it first: contactbench convert " +
                             cube +
                             " OUT.qpsnap (a frictional problem keeps its friction; --drop-friction keeps only its "
                             "normal part), or solve it with its friction: contactbench friction-solve " +
                             cube + "\n");
    const auto info = run("info '" + cube + "' --json");
    ASSERT_EQ(info.status, 0) << info.err;
    const nlohmann::json summary = nlohmann::json::parse(info.out);
    EXPECT_EQ(summary.at("format"), "fclib_global");
    EXPECT_EQ(summary.at("contacts"), 1);
    EXPECT_EQ(summary.at("unknowns"), 162);
    EXPECT_EQ(summary.at("mu_max"), 0.3);
    // CubeH8 (3-D, mu 0.3) converts with its friction: no --drop-friction in the suggestion.
    EXPECT_EQ(summary.at("convert"), "contactbench convert " + cube + " OUT.qpsnap");
    EXPECT_EQ(summary.at("friction_solve"), "contactbench friction-solve " + cube);
    // A local file (no A) converts only its normal part: --drop-friction is part of the suggestion.
    const std::string local = (TEST_DATA / "fclib/Capsules-i125-1213.hdf5").string();
    const auto solve_local = run("solve '" + local + "' --solver pgs");
    EXPECT_EQ(solve_local.status, 2);
    EXPECT_EQ(solve_local.err, "contactbench solve: error: " + local +
                                   ": format: an FCLIB fclib_local problem (HDF5), not a .qpsnap snapshot (solve "
                                   "reads .qpsnap snapshots); convert it first: contactbench convert " +
                                   local +
                                   " OUT.qpsnap (a frictional problem needs --drop-friction: its normal part), or "
                                   "solve it with its friction: contactbench friction-solve " +
                                   local + "\n");
    const auto info_local = run("info '" + local + "' --json");
    ASSERT_EQ(info_local.status, 0) << info_local.err;
    const nlohmann::json local_summary = nlohmann::json::parse(info_local.out);
    EXPECT_EQ(local_summary.at("convert"), "contactbench convert " + local + " OUT.qpsnap --drop-friction");
    EXPECT_EQ(local_summary.at("friction_solve"), "contactbench friction-solve " + local);
    fs::remove_all(work);
}

}  // namespace
