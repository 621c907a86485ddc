// Siconos numerics .dat import (problems/siconos_dat.*, issue 41's remainder): the real local
// problems of tests/data/siconos_dat (dense and sparse-block W) are read, solved with their
// friction by our NSGS and Siconos' NSN, converted with --drop-friction and described by info;
// the storage layouts are checked on hand-written files; hostile files end in exit 2 naming the
// file and the field, under a memory limit. The comparison with Siconos' own reader is in
// test_siconos_dat_reference.cpp (it links Siconos).
#include "problems/format_sniff.hpp"
#include "problems/qpsnap.hpp"
#include "problems/siconos_dat.hpp"
#include "solvers/friction/friction_nsgs.hpp"
#include "solvers/measure/friction_error.hpp"
#include "solvers/peers/siconos_fc3d.hpp"
#include "tests/harness/cli_test_util.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <regex>

namespace {

namespace fs = std::filesystem;
using cb::test::run_captured;

const fs::path DAT_FILES = fs::path(CB_TEST_DATA_DIR) / "siconos_dat";
const fs::path ROVER = DAT_FILES / "Rover4396.dat";                         // dense, 2 contacts
const fs::path SPHERES = DAT_FILES / "NESpheres_10_1.dat";                  // dense, 9 contacts
const fs::path CONFETI = DAT_FILES / "Confeti-ex13-4contact-Fc3D-SBM.dat";  // sparse block, 4 contacts
const fs::path CAPSULES = DAT_FILES / "Capsules-i101-404.dat";              // sparse block, 225 contacts
const std::vector<fs::path> REAL = {ROVER, SPHERES, CONFETI, CAPSULES};

void write(const fs::path& file, const std::string& text) { std::ofstream(file, std::ios::binary) << text; }

std::string dat_error_of(const std::function<void()>& f)
{
    try {
        f();
    } catch (const cb::InputError& e) {
        return e.what();
    }
    return "no error";
}

TEST(SiconosDat, EachRealFileIsRecognisedAndImported)
{
    struct Expected {
        fs::path file;
        long contacts;
        double mu;
        std::string storage;
    };
    for (const Expected& e :
         {Expected{ROVER, 2, 0.7, "dense"}, Expected{SPHERES, 9, 0.8, "dense"},
          Expected{CONFETI, 4, 0.04, "sparse block"}, Expected{CAPSULES, 225, 0.7, "sparse block"}}) {
        EXPECT_EQ(cb::sniff_format(e.file.string()), cb::FileFormat::SICONOS_DAT) << e.file;
        const cb::FrictionLocal p = cb::read_siconos_dat_friction(e.file.string());
        EXPECT_EQ(p.contacts(), e.contacts) << e.file;
        EXPECT_EQ(p.W.rows(), 3 * e.contacts) << e.file;
        EXPECT_EQ(p.W.cols(), 3 * e.contacts) << e.file;
        EXPECT_EQ(p.q.size(), 3 * e.contacts) << e.file;
        EXPECT_EQ(p.mu.minCoeff(), e.mu) << e.file;
        EXPECT_EQ(p.mu.maxCoeff(), e.mu) << e.file;
        EXPECT_TRUE(p.W.toDense().allFinite()) << e.file;
        const nlohmann::json d = cb::describe_siconos_dat(e.file.string());
        EXPECT_EQ(d.at("storage"), e.storage) << e.file;
        EXPECT_EQ(d.at("imported"), true) << e.file;
    }
    // Values as printed (%32.24e), read to the nearest double: Rover's first column starts
    // 1.2062...e-02, -1.5433...e-04 (column-major: W(1,0), not W(0,1) = -1.5159...e-04).
    const cb::FrictionLocal rover = cb::read_siconos_dat_friction(ROVER.string());
    EXPECT_EQ(rover.W.coeff(0, 0), 1.206265440170792811735989e-02);
    EXPECT_EQ(rover.W.coeff(1, 0), -1.515988037597431909581092e-04);
    EXPECT_EQ(rover.W.coeff(0, 1), -1.543351006400240027841009e-04);
    EXPECT_EQ(rover.q[5], -2.339750149624925779079376e+00);
}

TEST(SiconosDat, DenseIsColumnMajorAndSparseBlocksLandWhereTheirIndicesSay)
{
    const fs::path dir = cb::test::make_test_work_dir("siconos_dat_layout");
    // One contact, dense 3 x 3 written column by column; spacing as Siconos' oldest files have it.
    write(dir / "dense.dat", "3\n1\n\n0\n3\n3\n\n3\n3\n\n11 21 31\n12 22 32\n13 23 33\n\n-1 2 3\n\n0.25\n");
    const cb::FrictionLocal d = cb::read_siconos_dat_friction((dir / "dense.dat").string());
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) EXPECT_EQ(d.W.coeff(i, j), 10.0 * (i + 1) + (j + 1)) << i << " " << j;
    EXPECT_EQ(d.q, (cb::Vec(3) << -1, 2, 3).finished());
    EXPECT_EQ(d.mu[0], 0.25);
    // Two contacts, three blocks: (0,0), (0,1), (1,1); block values column-major, numbered in order.
    std::string sbm = "3\n2\n1\n6\n6\n3\n2\n2\n3\t6\t\n3\t6\t\n3\n3\n0\t2\t3\t\n0\t1\t1\t\n";
    for (int b = 0; b < 3; ++b) {
        sbm += std::to_string(b) + "\n";
        for (int k = 0; k < 9; ++k) sbm += std::to_string(100 * (b + 1) + k) + "\n";
    }
    sbm += "1 0 0 1 0 0\n0.5 0.6\n";
    write(dir / "sbm.dat", sbm);
    const cb::FrictionLocal s = cb::read_siconos_dat_friction((dir / "sbm.dat").string());
    EXPECT_EQ(s.W.nonZeros(), 27);
    EXPECT_EQ(s.W.coeff(0, 0), 100.0);
    EXPECT_EQ(s.W.coeff(1, 0), 101.0);  // column-major inside a block
    EXPECT_EQ(s.W.coeff(0, 1), 103.0);
    EXPECT_EQ(s.W.coeff(0, 3), 200.0);  // block (0,1)
    EXPECT_EQ(s.W.coeff(2, 5), 208.0);
    EXPECT_EQ(s.W.coeff(3, 0), 0.0);  // block (1,0) absent
    EXPECT_EQ(s.W.coeff(5, 5), 308.0);
    EXPECT_EQ(s.mu[1], 0.6);
    // The same numbers with every separator a newline (fscanf's rule: any white space).
    std::string one_per_line = cb::test::slurp(ROVER);
    one_per_line = std::regex_replace(one_per_line, std::regex("[ \t\n]+"), "\n");
    write(dir / "rover_lines.dat", one_per_line);
    const cb::FrictionLocal a = cb::read_siconos_dat_friction(ROVER.string());
    const cb::FrictionLocal b = cb::read_siconos_dat_friction((dir / "rover_lines.dat").string());
    EXPECT_EQ(Eigen::MatrixXd(a.W), Eigen::MatrixXd(b.W));
    EXPECT_EQ(a.q, b.q);
    EXPECT_EQ(a.mu, b.mu);
    fs::remove_all(dir);
}

TEST(SiconosDat, OurNsgsAndSiconosNsnReachTheirTolerance)
{
    // nsgs at 1e-8 on the small files; Capsules at 1e-6 (measured: 8322 sweeps, 10.7 s to 1e-8).
    for (const fs::path& file : REAL) {
        const cb::FrictionLocal p = cb::read_siconos_dat_friction(file.string());
        cb::FrictionNsgsSettings s;
        s.tol = file == CAPSULES ? 1e-6 : 1e-8;
        const cb::FrictionRun run = cb::friction_nsgs(p, s);
        EXPECT_EQ(run.status, "converged") << file;
        EXPECT_LE(run.error, s.tol) << file;
        EXPECT_EQ(run.error, cb::fclib_relative_error(p, run.r)) << file;
    }
    if (!cb::siconos_fc3d_built()) GTEST_SKIP() << "Siconos numerics is not built (libsiconos-numerics-dev)";
    for (const fs::path& file : REAL) {
        const cb::FrictionLocal p = cb::read_siconos_dat_friction(file.string());
        const cb::FrictionRun nsn = cb::siconos_fc3d_solve(p, "nsn", 500, 1e-8, 120.0);
        EXPECT_EQ(nsn.status, "converged") << file << " " << nsn.note;
        EXPECT_LE(nsn.error, 1e-8) << file;  // the harness's FCLIB error, not NSN's own
    }
}

TEST(SiconosDat, ConvertKeepsTheNormalBlockAsFclibLocalDoes)
{
    const fs::path dir = cb::test::make_test_work_dir("siconos_dat_convert");
    const std::string bin = cb::test::contactbench_binary();
    const std::string in = CAPSULES.string(), out = (dir / "capsules.qpsnap").string();
    // Friction is refused unless dropped; W_NN is not symmetric (Siconos' W is assembled, not
    // symmetrised), so --symmetrise is needed too. Nothing is written before both are given.
    cb::test::Output o = run_captured(bin + " convert '" + in + "' '" + out + "'", dir);
    EXPECT_EQ(o.status, 2);
    EXPECT_EQ(o.err, "contactbench convert: error: " + in +
                         ": mu[0]: contact 0 has mu = 0.69999999999999996: this Siconos local problem has friction, "
                         "which a snapshot cannot hold (it has no A); `convert --drop-friction` keeps its normal part "
                         "(recorded in the snapshot), `friction-solve` solves a 3-D one with its friction\n");
    o = run_captured(bin + " convert '" + in + "' '" + out + "' --drop-friction", dir);
    EXPECT_EQ(o.status, 2);
    EXPECT_EQ(o.err, "contactbench convert: error: " + in +
                         ": M: the normal block W_NN (indexed by contact) is not symmetric: (146, 216) = "
                         "0.018958977152198325 but (216, 146) = 0.017250599635300901 (beyond 1e-12 of its largest "
                         "entry); `convert --symmetrise` averages it with its transpose\n");
    EXPECT_FALSE(fs::exists(out));
    o = run_captured(bin + " convert '" + in + "' '" + out + "' --drop-friction --symmetrise", dir);
    ASSERT_EQ(o.status, 0) << o.err;
    const cb::Qp qp = cb::read_qpsnap(out);
    const cb::FrictionLocal p = cb::read_siconos_dat_friction(in);
    ASSERT_EQ(qp.n(), 225);
    ASSERT_EQ(qp.m(), 225);
    for (int i = 0; i < 225; ++i) {
        EXPECT_EQ(qp.b[i], -p.q[3 * i]);
        for (int j = 0; j < 225; ++j)
            ASSERT_EQ(qp.A.coeff(i, j), 0.5 * (p.W.coeff(3 * i, 3 * j) + p.W.coeff(3 * j, 3 * i))) << i << " " << j;
    }
    EXPECT_EQ(Eigen::MatrixXd(qp.J), Eigen::MatrixXd::Identity(225, 225));
    EXPECT_EQ(qp.c, cb::Vec::Zero(225));
    const nlohmann::json prov = qp.meta.at("provenance");
    EXPECT_EQ(prov.at("format"), "siconos_dat");
    EXPECT_EQ(prov.at("storage"), "sparse block");
    EXPECT_EQ(prov.at("dropped_friction").at("mu_max"), 0.7);
    EXPECT_EQ(prov.at("mapping"), "A = W_NN, b = -q_N, J = I, c = 0 (x = r_N, lambda = u_N)");
    // The QP solves: active-set's verdict (its KKT error) on the converted file.
    o = run_captured(bin + " solve '" + out + "' --solver active-set", dir);
    ASSERT_EQ(o.status, 0) << o.err;
    EXPECT_NE(o.out.find("active-set: converged"), std::string::npos) << o.out;
    // A 2-D problem converts (the normal is each contact's first component); Confeti's W_NN is
    // symmetric to rounding, so it needs no --symmetrise.
    write(dir / "two_d.dat", "2\n2\n0\n4\n4\n4 4\n2 0 0.5 0  0 1 0 0  0.5 0 3 0  0 0 0 1\n-1 0 -2 0\n0.3 0.3\n");
    o = run_captured(bin + " convert '" + (dir / "two_d.dat").string() + "' '" + (dir / "two_d.qpsnap").string() +
                         "' --drop-friction",
                     dir);
    ASSERT_EQ(o.status, 0) << o.err;
    const cb::Qp two = cb::read_qpsnap((dir / "two_d.qpsnap").string());
    EXPECT_EQ(Eigen::MatrixXd(two.A), (Eigen::MatrixXd(2, 2) << 2, 0.5, 0.5, 3).finished());
    EXPECT_EQ(two.b, (cb::Vec(2) << 1, 2).finished());
    o = run_captured(
        bin + " convert '" + CONFETI.string() + "' '" + (dir / "confeti.qpsnap").string() + "' --drop-friction", dir);
    EXPECT_EQ(o.status, 0) << o.err;
    fs::remove_all(dir);
}

TEST(SiconosDat, FrictionSolveAndInfoTakeDatFiles)
{
    const fs::path dir = cb::test::make_test_work_dir("siconos_dat_cli");
    const std::string bin = cb::test::contactbench_binary();
    cb::test::Output o = run_captured(bin + " friction-solve '" + SPHERES.string() + "' --solver nsgs --json '" +
                                          (dir / "r.json").string() + "'",
                                      dir);
    ASSERT_EQ(o.status, 0) << o.err;
    const nlohmann::json j = nlohmann::json::parse(cb::test::slurp(dir / "r.json"));
    EXPECT_EQ(j.at("contacts"), 9);
    EXPECT_EQ(j.at("runs").at(0).at("status"), "converged");
    EXPECT_LE(j.at("runs").at(0).at("fclib_error").get<double>(), 1e-8);
    o = run_captured(bin + " info '" + CONFETI.string() + "' --json", dir);
    ASSERT_EQ(o.status, 0) << o.err;
    const nlohmann::json info = nlohmann::json::parse(o.out);
    EXPECT_EQ(info.at("format"), "siconos_dat");
    EXPECT_EQ(info.at("contacts"), 4);
    EXPECT_EQ(info.at("rows"), 12);
    EXPECT_EQ(info.at("nnz_W"), 144);
    EXPECT_EQ(info.at("storage"), "sparse block");
    EXPECT_EQ(info.at("mu_max"), 0.04);
    EXPECT_EQ(info.at("convert"), "contactbench convert " + CONFETI.string() + " OUT.qpsnap --drop-friction");
    // A global problem is described and named, not imported.
    const std::string global = (fs::path(CB_TEST_DATA_DIR) / "fclib" / "GFC3D_TwoRods1.dat").string();
    o = run_captured(bin + " info '" + global + "' --json", dir);
    ASSERT_EQ(o.status, 0) << o.err;
    const nlohmann::json g = nlohmann::json::parse(o.out);
    EXPECT_EQ(g.at("imported"), false);
    EXPECT_EQ(g.at("contacts"), 3);
    o = run_captured(bin + " friction-solve '" + global + "'", dir);
    EXPECT_EQ(o.status, 2);
    EXPECT_EQ(o.err, "contactbench friction-solve: error: " + global +
                         ": H: a global friction-contact problem (Siconos GlobalFrictionContactProblem: M, H, q, b, "
                         "mu), not a local one (W, q, mu); contactbench imports local .dat problems only (write it "
                         "as FCLIB fclib_global with Siconos, then `contactbench convert` it)\n");
    fs::remove_all(dir);
}

TEST(SiconosDat, AnLcpConvertsAsAQpAndIsNotAFrictionProblem)
{
    const fs::path dir = cb::test::make_test_work_dir("siconos_dat_lcp");
    const std::string bin = cb::test::contactbench_binary();
    // Siconos' linearComplementarity_printInFile layout: n, M (dense here), q; text after q ignored.
    const std::string lcp = (dir / "lcp.dat").string();
    write(lcp, "2\n0\n2\n2\n2\t2\n2 1\n1 2\n-5 -6\n\nRemark: z ⊥ w, z = (4/3, 7/3)\n");  // UTF-8 text after q
    EXPECT_EQ(cb::sniff_format(lcp), cb::FileFormat::SICONOS_DAT);
    const nlohmann::json d = cb::describe_siconos_dat(lcp);
    EXPECT_EQ(d.at("size"), 2);
    EXPECT_EQ(d.at("ignored_after_q"), 8);
    const cb::Qp qp = cb::read_siconos_dat_qp(lcp);
    EXPECT_EQ(Eigen::MatrixXd(qp.A), (Eigen::MatrixXd(2, 2) << 2, 1, 1, 2).finished());
    EXPECT_EQ(qp.b, (cb::Vec(2) << 5, 6).finished());
    EXPECT_EQ(qp.meta.at("provenance").at("mapping"), "A = M, b = -q, J = I, c = 0 (x = z, lambda = w = M z + q)");
    cb::test::Output o = run_captured(bin + " convert '" + lcp + "' '" + (dir / "lcp.qpsnap").string() + "'", dir);
    ASSERT_EQ(o.status, 0) << o.err;
    o = run_captured(bin + " solve '" + (dir / "lcp.qpsnap").string() + "' --solver active-set", dir);
    ASSERT_EQ(o.status, 0) << o.err;
    EXPECT_NE(o.out.find("objective   -10.33333333,"), std::string::npos) << o.out;  // -1/2 q'z = -31/3
    o = run_captured(bin + " friction-solve '" + lcp + "'", dir);
    EXPECT_EQ(o.status, 2);
    EXPECT_EQ(o.err, "contactbench friction-solve: error: " + lcp +
                         ": size: a linear complementarity problem (Siconos LinearComplementarityProblem: n, M, q), "
                         "not a friction-contact one; `contactbench convert` takes it as a QP (A = M, b = -q, J = I, "
                         "c = 0)\n");
    // A non-symmetric M is not a QP: refused naming the pair (column-major: M(1,0) = 2).
    write(dir / "asym.dat", "3\n0\n3\n3\n3\t3\n1 2 2\n0 1 2\n0 0 1\n-1 -1 -1\n");
    EXPECT_EQ(dat_error_of([&] { cb::read_siconos_dat_qp((dir / "asym.dat").string()); }),
              (dir / "asym.dat").string() +
                  ": M: the LCP matrix M is not symmetric: (0, 1) = 0 but (1, 0) = 2 (beyond 1e-12 of its largest "
                  "entry); `convert --symmetrise` averages it with its transpose");
    fs::remove_all(dir);
}

/// A mutant of a real file (or a written one), run through friction-solve under a 600 MB address
/// space limit: every refusal happens before anything of a declared size is made.
struct Hostile {
    fs::path dir = cb::test::make_test_work_dir("siconos_dat_hostile");
    std::string bin = cb::test::contactbench_binary();
    cb::test::Output solve(const std::string& name, const std::string& text)
    {
        write(dir / name, text);
        return run_captured(
            "ulimit -v 600000; " + bin + " friction-solve '" + (dir / name).string() + "' --solver nsgs", dir);
    }
    std::string expected(const std::string& name, const std::string& rest) const
    {
        return "contactbench friction-solve: error: " + (dir / name).string() + ": " + rest + "\n";
    }
};

/// `text` with its `line`-th line (1-based) replaced.
std::string with_line(const std::string& text, int line, const std::string& replacement)
{
    size_t start = 0;
    for (int k = 1; k < line; ++k) start = text.find('\n', start) + 1;
    const size_t end = text.find('\n', start);
    return text.substr(0, start) + replacement + text.substr(end);
}

TEST(SiconosDat, HostileFilesEndInExitTwoNamingFileAndField)
{
    Hostile h;
    const std::string rover = cb::test::slurp(ROVER), confeti = cb::test::slurp(CONFETI),
                      capsules = cb::test::slurp(CAPSULES);
    const std::string first = "1.206265440170792811735989e-02";
    const std::vector<std::pair<std::string, std::string>> cases = {
        {capsules.substr(0, 150000), "M.block[478][2]: missing: the file ends here (truncated) (line 4797)"},
        {rover.substr(0, rover.size() / 2), "M.matrix0[22]: missing: the file ends here (truncated) (line 10)"},
        {with_line(rover, 4, "-6"), "M.size0: is -6, must be >= 1 (line 4)"},
        {with_line(rover, 2, "1000000000000"), "numberOfContacts: is 1000000000000, more than the rest of the file "
                                               "can hold (1473 bytes: a wrong count or a truncated file) (line 2)"},
        {with_line(with_line(with_line(rover, 4, "700"), 5, "700"), 6, "700\t700"),
         "M.matrix0: declares 490000 values, more than the rest of the file can hold (1460 bytes: a wrong count or a "
         "truncated file) (line 7)"},
        {with_line(confeti, 6, "100000000000"), "M.nbblocks: is 100000000000, more than the rest of the file can hold "
                                                "(5398 bytes: a wrong count or a truncated file) (line 6)"},
        {std::regex_replace(rover, std::regex(first), "nan"), "M.matrix0[0]: is nan (values must be finite) (line 7)"},
        {std::regex_replace(rover, std::regex(first), "1e999"),
         "M.matrix0[0]: is 1e999 (values must be finite) (line 7)"},
        {std::regex_replace(rover, std::regex(first), "1.2x6"), "M.matrix0[0]: '1.2x6' is not a number (line 7)"},
        {with_line(rover, 14, "  6.999999999999999555910790e-01  -6.999999999999999555910790e-01"),
         "mu[1]: contact 1 has mu = -0.69999999999999996 (a friction coefficient is finite and >= 0)"},
        {with_line(rover, 1, "5"), "dimension: is 5, must be in [2, 3] (line 1)"},
        {"2\n1\n0\n2\n2\n2 2\n2 0 0 1\n-1 0\n0.5\n",
         "dimension: is 2: only 3-D frictional problems (dimension 3) are solved"},
        {with_line(rover, 2, "0"), "numberOfContacts: is 0: the problem has no contacts (line 2)"},
        {with_line(rover, 2, "3"), "M: is 6 x 6, must be 9 x 9 (dimension 3 times 3 contacts) (line 12)"},
        {with_line(rover, 3, "2"),
         "M.storageType: is 2 (NM_SPARSE: CSparse's text print, values with 6 significant digits), which does not "
         "hold the problem to double precision; write it dense or sparse-block (NM_SPARSE_BLOCK), or as FCLIB "
         "(HDF5) (line 3)"},
        {with_line(rover, 6, "6\t5"), "M.size0 (dense): the dense block is 6 x 5, the header says 6 x 6 (line 6)"},
        {with_line(confeti, 9, "4\t3\t9\t12\t"),
         "M.blocksize0[1]: is 3, not above the previous bound 4 (cumulative block sizes increase) (line 9)"},
        {with_line(confeti, 9, "3\t6\t9\t11\t"),
         "M.blocksize0[3]: is 11, but the matrix has 12 (M.blocksize0 ends at the matrix's size) (line 9)"},
        {with_line(confeti, 14, "0\t1\t2\t7\t0\t1\t2\t3\t0\t1\t2\t3\t0\t1\t2\t3\t"),
         "M.index2_data[3]: is 7, must be in [0, 3] (line 14)"},
        {with_line(confeti, 14, "0\t1\t1\t3\t0\t1\t2\t3\t0\t1\t2\t3\t0\t1\t2\t3\t"),
         "M.index2_data[2]: block column 1 appears twice in block row 0 (line 34)"},
        {with_line(confeti, 13, "0\t4\t8\t17\t16\t"), "M.index1_data[3]: is 17, must be in [8, 16] (line 13)"},
        {with_line(confeti, 25, "5"),
         "M.block[1] number: is 5, the blocks are numbered in order (expected 1) (line 25)"},
    };
    for (size_t k = 0; k < cases.size(); ++k) {
        const std::string name = "mutant" + std::to_string(k) + ".dat";
        const cb::test::Output o = h.solve(name, cases[k].first);
        EXPECT_EQ(o.status, 2) << k;
        EXPECT_EQ(o.err, h.expected(name, cases[k].second)) << k;
        EXPECT_EQ(o.out, "") << k;
    }
    fs::remove_all(h.dir);
}

TEST(SiconosDat, ConvertOfAHostileFileWritesNothing)
{
    const fs::path dir = cb::test::make_test_work_dir("siconos_dat_no_output");
    const std::string text = cb::test::slurp(ROVER);
    write(dir / "bad.dat", with_line(text, 14, "  6.999999999999999555910790e-01  -1"));
    const cb::test::Output o =
        run_captured(cb::test::contactbench_binary() + " convert '" + (dir / "bad.dat").string() + "' '" +
                         (dir / "out.qpsnap").string() + "' --drop-friction --symmetrise",
                     dir);
    EXPECT_EQ(o.status, 2);
    EXPECT_EQ(o.err, "contactbench convert: error: " + (dir / "bad.dat").string() +
                         ": mu[1]: contact 1 has mu = -1 (a friction coefficient is finite and >= 0)\n");
    EXPECT_FALSE(fs::exists(dir / "out.qpsnap"));
    EXPECT_EQ(dat_error_of([&] { cb::read_siconos_dat_qp((dir / "missing.dat").string()); }),
              (dir / "missing.dat").string() + ": cannot open: No such file or directory");
    fs::remove_all(dir);
}

}  // namespace
