// Matrix Market: bit-exact .qpsnap -> folder -> .qpsnap, what other writers produce (symmetric,
// integer, array), and exact messages for bad files.
#include "problems/matrix_market.hpp"
#include "problems/synthetic.hpp"
#include "tests/problems/file_bytes.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <unistd.h>
#include <vector>

namespace cb {
namespace {

namespace fs = std::filesystem;

std::string temp_dir(const std::string& name)
{
    const auto dir = fs::temp_directory_path() / ("cb_test_mm_" + std::to_string(::getpid())) / name;
    fs::create_directories(dir);
    return dir.string();
}

void put(const std::string& path, const std::string& text)
{
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out << text;
}

/// A valid folder for A = [4 1; 1 3], J = [1 -1], with one file replaced by `override`.
std::string tiny_folder(const std::string& name, const std::string& file = "", const std::string& text = "")
{
    std::string d = temp_dir(name);
    put(d + "/A.mtx",
        "%%MatrixMarket matrix coordinate real symmetric\n% lower triangle\n2 2 3\n1 1 4\n2 1 1\n2 2 3\n");
    put(d + "/b.mtx", "%%MatrixMarket matrix array real general\n2 1\n1\n2\n");
    put(d + "/x0.mtx", "%%MatrixMarket matrix array real general\n2 1\n0\n0\n");
    put(d + "/J.mtx", "%%MatrixMarket matrix coordinate integer general\n1 2 2\n1 1 1\n1 2 -1\n");
    put(d + "/c.mtx", "%%MatrixMarket matrix coordinate real general\n1 1 1\n1 1 0.25\n");
    if (!file.empty()) put(d + "/" + file, text);
    return d;
}

void expect_mm_folder_error(const std::string& dir, const std::string& message)
{
    try {
        read_matrix_market_folder(dir);
        ADD_FAILURE() << "no error, expected " << message;
    } catch (const InputError& e) {
        EXPECT_EQ(std::string(e.what()), message);
    }
}

TEST(MatrixMarket, ReadsSymmetricIntegerAndCoordinateVectors)
{
    const Qp qp = read_matrix_market_folder(tiny_folder("ok"));
    ASSERT_EQ(qp.n(), 2);
    ASSERT_EQ(qp.m(), 1);
    EXPECT_EQ(qp.A.coeff(0, 1), 1.0);
    EXPECT_EQ(qp.A.coeff(1, 0), 1.0);
    EXPECT_EQ(qp.A.nonZeros(), 4);
    EXPECT_EQ(qp.J.coeff(0, 1), -1.0);
    EXPECT_EQ(qp.c[0], 0.25);
    EXPECT_EQ(qp.b[1], 2.0);
}

TEST(MatrixMarket, EmptyJ)
{
    const std::string d = tiny_folder("emptyj", "J.mtx", "%%MatrixMarket matrix coordinate real general\n0 2 0\n");
    put(d + "/c.mtx", "%%MatrixMarket matrix array real general\n0 1\n");
    const Qp qp = read_matrix_market_folder(d);
    EXPECT_EQ(qp.m(), 0);
    EXPECT_EQ(qp.J.cols(), 2);
}

TEST(MatrixMarket, RoundTripThroughFolderIsBitExact)
{
    Qp qp = make_synthetic("coupled", {{"nx", 2}, {"ny", 2}, {"nz", 2}}, 3);
    qp.b[1] = 1.0 / 3.0;
    qp.x0[0] = -0.0;
    SnapshotExtras extras;
    extras.lambda_ref = Vec::LinSpaced(qp.m(), 0.1, 0.7);
    const std::string base = temp_dir("round");
    const std::string s1 = base + "/a.qpsnap", s2 = base + "/b.qpsnap", folder = base + "/folder";
    write_qpsnap(s1, qp, &extras);
    SnapshotExtras e1;
    const Qp q1 = read_qpsnap(s1, &e1);
    write_matrix_market_folder(folder, q1, &e1);
    EXPECT_FALSE(fs::exists(folder + ".tmp." + std::to_string(::getpid())));
    SnapshotExtras e2;
    const Qp q2 = read_matrix_market_folder(folder, &e2);
    write_qpsnap(s2, q2, &e2);
    EXPECT_EQ(test::file_bytes(s1), test::file_bytes(s2));  // every array, the meta and the contacts, bit for bit
    EXPECT_TRUE(std::signbit(q2.x0[0]));
    // Writing again over our own folder replaces it.
    write_matrix_market_folder(folder, q2, &e2);
    EXPECT_TRUE(fs::exists(folder + "/contact.json"));
}

TEST(MatrixMarket, RefusesToReplaceAForeignFolder)
{
    const std::string d = temp_dir("foreign");
    put(d + "/notes.txt", "mine");
    try {
        write_matrix_market_folder(d, make_synthetic("box", {{"nx", 1}, {"ny", 1}, {"nz", 1}}, 1));
        FAIL();
    } catch (const InputError& e) {
        EXPECT_EQ(std::string(e.what()), d + ": exists and is not a snapshot folder (no A.mtx); not replacing it");
    }
    EXPECT_TRUE(fs::exists(d + "/notes.txt"));
}

TEST(MatrixMarketErrors, BadBanner)
{
    const std::string d = tiny_folder("banner", "b.mtx", "%%MatrixMarket vector array real general\n2 1\n1\n2\n");
    expect_mm_folder_error(d, d + "/b.mtx: line 1: expected '%%MatrixMarket matrix FORMAT FIELD SYMMETRY', got "
                                  "'%%MatrixMarket vector array real general'");
}

TEST(MatrixMarketErrors, UnsupportedField)
{
    const std::string d = tiny_folder("complex", "A.mtx", "%%MatrixMarket matrix coordinate complex general\n2 2 0\n");
    expect_mm_folder_error(d, d + "/A.mtx: line 1: field 'complex' not supported (real or integer)");
}

TEST(MatrixMarketErrors, BadEntryLine)
{
    const std::string d =
        tiny_folder("entry", "J.mtx", "%%MatrixMarket matrix coordinate real general\n%c\n1 2 2\n1 1 1\n1 x -1\n");
    expect_mm_folder_error(d, d + "/J.mtx: line 5: expected 'row col value', got '1 x -1'");
}

TEST(MatrixMarketErrors, EntryOutOfRange)
{
    const std::string d =
        tiny_folder("range", "J.mtx", "%%MatrixMarket matrix coordinate real general\n1 2 2\n1 1 1\n1 3 -1\n");
    expect_mm_folder_error(d, d + "/J.mtx: line 4: entry (1 3 -1) outside [1, 1] x [1, 2]");
}

TEST(MatrixMarketErrors, TooFewEntries)
{
    const std::string d =
        tiny_folder("few", "J.mtx", "%%MatrixMarket matrix coordinate real general\n1 2 3\n1 1 1\n1 2 -1\n");
    expect_mm_folder_error(d, d + "/J.mtx: entries: expected 3 entries, the file ends after 2");
}

TEST(MatrixMarketErrors, DuplicateEntry)
{
    const std::string d =
        tiny_folder("dup", "J.mtx", "%%MatrixMarket matrix coordinate real general\n1 2 2\n1 1 1\n1 1 2\n");
    expect_mm_folder_error(d, d + "/J.mtx: line 4: duplicate entry (1, 1)");
}

TEST(MatrixMarketErrors, WrongVectorSize)
{
    const std::string d = tiny_folder("size", "x0.mtx", "%%MatrixMarket matrix array real general\n3 1\n0\n0\n0\n");
    expect_mm_folder_error(d, d + "/x0.mtx: size: expected n (from A.mtx) = 2 entries, got 3");
}

TEST(MatrixMarketErrors, MissingFile)
{
    const std::string d = tiny_folder("missing");
    fs::remove(d + "/c.mtx");
    expect_mm_folder_error(d, d + ": c.mtx: missing");
}

TEST(MatrixMarketErrors, AsymmetricGeneralA)
{
    const std::string d = tiny_folder(
        "asym", "A.mtx", "%%MatrixMarket matrix coordinate real general\n2 2 4\n1 1 4\n1 2 1\n2 1 2\n2 2 3\n");
    expect_mm_folder_error(d, d + ": A: not symmetric: A(0, 1) = 1 but A(1, 0) = 2 (difference 1 > 1e-12 * max|A_ij| = "
                                  "3.9999999999999999e-12)");
}

TEST(MatrixMarketErrors, ContactJsonWrongLength)
{
    const std::string d = tiny_folder("contact", "contact.json", "{\"kind\": [0, 0]}");
    expect_mm_folder_error(d, d + "/contact.json: kind: expected an array of m = 1 entries");
}

TEST(MatrixMarketErrors, DeclaredSizesBeyondTheBytesPresent)
{
    // Issue 15: the size line is checked against what the files can hold before allocating.
    const std::string a =
        tiny_folder("huge_a", "A.mtx", "%%MatrixMarket matrix coordinate real general\n200000000 200000000 1\n1 1 4\n");
    expect_mm_folder_error(
        a, a + "/A.mtx: line 2: declares 200000000 rows but only 1 entries (every row needs its diagonal entry)");
    const std::string j =
        tiny_folder("huge_j", "J.mtx", "%%MatrixMarket matrix coordinate real general\n200000000 2 1\n1 1 1\n");
    const auto c_bytes = fs::file_size(fs::path(j) / "c.mtx");
    expect_mm_folder_error(j, j + "/J.mtx: line 2: declares 200000000 rows, at most " +
                                  std::to_string(c_bytes / 2 + 1) + " possible (c.mtx holds " +
                                  std::to_string(c_bytes) + " bytes, this file declares 1 entries)");
    const std::string b = tiny_folder("huge_b", "b.mtx", "%%MatrixMarket matrix array real general\n200000000 1\n1\n");
    expect_mm_folder_error(b, b + "/b.mtx: size: expected n (from A.mtx) = 2 entries, got 200000000");
    // A lone file: the reserve follows the bytes present, the error is the missing entries.
    const std::string v = temp_dir("huge_v") + "/v.mtx";
    put(v, "%%MatrixMarket matrix array real general\n200000000 1\n1\n");
    try {
        read_mtx_vector(v);
        ADD_FAILURE() << "no error";
    } catch (const InputError& e) {
        EXPECT_EQ(std::string(e.what()), v + ": entries: expected 200000000 entries, the file ends after 1");
    }
}

// ---- Coulomb friction in files of its own (issue 48: a folder used to drop it without a word) ----

/// A synthetic QP with every friction field set (mu, T, cT, h, v0).
Qp frictional_synthetic_2x2x2()
{
    Qp qp = make_synthetic("coupled", {{"nx", 2}, {"ny", 2}, {"nz", 2}}, 3);
    const Eigen::Index m = qp.m(), n = qp.n();
    Friction& f = qp.friction;
    f.mu = Vec::LinSpaced(m, 0.0, 0.9);
    std::vector<Eigen::Triplet<double>> t;
    for (Eigen::Index i = 0; i < 2 * m; ++i) t.emplace_back(int(i), int((3 * i + 1) % n), 1.0 / double(i + 3));
    f.T.resize(2 * m, n);
    f.T.setFromTriplets(t.begin(), t.end());
    f.T.makeCompressed();
    f.cT = Vec::LinSpaced(2 * m, -1.0, 1.0 / 7.0);
    f.h = 1.0 / 60.0;
    f.v0 = Vec::LinSpaced(n, 0.25, -2.0 / 3.0);
    return qp;
}

TEST(MatrixMarketFriction, RoundTripKeepsEveryFrictionFieldBitForBit)
{
    const Qp qp = frictional_synthetic_2x2x2();
    const std::string base = temp_dir("friction_round");
    const std::string s1 = base + "/a.qpsnap", s2 = base + "/b.qpsnap", folder = base + "/folder";
    write_qpsnap(s1, qp);
    write_matrix_market_folder(folder, read_qpsnap(s1));
    for (const char* file : {"mu.mtx", "T.mtx", "cT.mtx", "h.mtx", "v0.mtx"})
        EXPECT_TRUE(fs::exists(folder + "/" + file)) << file;
    const Qp back = read_matrix_market_folder(folder);
    ASSERT_TRUE(back.frictional());
    EXPECT_EQ(back.friction.h, qp.friction.h);
    write_qpsnap(s2, back);
    EXPECT_EQ(test::file_bytes(s1), test::file_bytes(s2));  // version 2, every friction array bit for bit
    // A frictionless QP's folder has no friction file.
    write_matrix_market_folder(folder, make_synthetic("coupled", {{"nx", 2}, {"ny", 2}, {"nz", 2}}, 3));
    EXPECT_FALSE(fs::exists(folder + "/mu.mtx"));
    EXPECT_TRUE(read_matrix_market_folder(folder).friction.empty());
}

TEST(MatrixMarketFriction, BadFrictionFilesNameTheFileAndField)
{
    const std::string mu = "%%MatrixMarket matrix array real general\n1 1\n0.5\n";
    const std::string t = "%%MatrixMarket matrix coordinate real general\n2 2 2\n1 1 1\n2 2 1\n";
    std::string d = tiny_folder("fric_no_t", "mu.mtx", mu);
    expect_mm_folder_error(d, d + ": T: missing: mu needs the two tangent rows per contact (T, 2m x n)");
    d = tiny_folder("fric_no_mu", "T.mtx", t);
    expect_mm_folder_error(d, d + ": mu: missing: T is given without friction coefficients");
    d = tiny_folder("fric_negative", "mu.mtx", "%%MatrixMarket matrix array real general\n1 1\n-0.5\n");
    put(d + "/T.mtx", t);
    expect_mm_folder_error(d, d + ": mu: negative friction coefficient -0.5 at contact 0");
    d = tiny_folder("fric_t_rows", "mu.mtx", mu);
    put(d + "/T.mtx", "%%MatrixMarket matrix coordinate real general\n5 2 1\n1 1 1\n");
    expect_mm_folder_error(
        d, d + "/T.mtx: line 2: declares 5 rows, at most 2 possible (2m = 2, two tangent rows per row of "
               "J.mtx)");
    d = tiny_folder("fric_v0", "v0.mtx", "%%MatrixMarket matrix array real general\n2 1\n1\n2\n");
    expect_mm_folder_error(d, d + ": h: missing: v0 is given without the step h");
}

}  // namespace
}  // namespace cb
