// .qpsnap v1 and v2 (friction): round trip, symmetrisation, and one test per corruption with the exact message.
// Corrupt files are written by an independent raw writer below, so that the structure checks
// are reached with valid CRCs.
#include "problems/qpsnap.hpp"
#include "problems/synthetic.hpp"
#include "tests/problems/file_bytes.hpp"

#include <gtest/gtest.h>
#include <zlib.h>

#include <chrono>
#include <cmath>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <limits>
#include <unistd.h>

namespace cb {
namespace {

std::string qpsnap_temp_path(const std::string& name)
{
    const auto dir = std::filesystem::temp_directory_path() / ("cb_test_qpsnap_" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir);
    return (dir / name).string();
}

void put_bytes(const std::string& path, const std::string& bytes)
{
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(bytes.data(), std::streamsize(bytes.size()));
}

/// A raw array for the independent writer.
struct Raw {
    std::string dtype;
    std::vector<std::uint64_t> shape;
    std::vector<std::int64_t> i;
    std::vector<double> f;
};

Raw ints(const std::vector<std::int64_t>& v) { return Raw{"int64", {v.size()}, v, {}}; }
Raw reals(const std::vector<double>& v) { return Raw{"float64", {v.size()}, {}, v}; }

/// The valid 3 x 3 / 2-row problem every corruption starts from:
/// A = [4 1 0; 1 5 2; 0 2 6], J = [1 0 0; 0 -1 1].
std::map<std::string, Raw> tiny_arrays()
{
    return {
        {"A.indptr", ints({0, 2, 5, 7})},
        {"A.indices", ints({0, 1, 0, 1, 2, 1, 2})},
        {"A.data", reals({4, 1, 1, 5, 2, 2, 6})},
        {"b", reals({1, 2, 3})},
        {"x0", reals({0, 0, 0})},
        {"J.indptr", ints({0, 1, 3})},
        {"J.indices", ints({0, 1, 2})},
        {"J.data", reals({1, -1, 1})},
        {"c", reals({0.5, -1})},
    };
}

/// Writes arrays in map order; `edit` may change the header before it is serialised.
std::string write_raw(const std::string& name, const std::map<std::string, Raw>& arrays, std::int64_t n = 3,
                      std::int64_t m = 2, const std::function<void(nlohmann::json&)>& edit = nullptr)
{
    nlohmann::json header = {{"format", "qpsnap"}, {"version", 1}, {"n", n}, {"m", m}, {"meta", {{"scene", "tiny"}}}};
    std::string data;
    for (const auto& kv : arrays) {
        std::string bytes;
        if (kv.second.dtype == "int64")
            bytes.assign(reinterpret_cast<const char*>(kv.second.i.data()), 8 * kv.second.i.size());
        else
            bytes.assign(reinterpret_cast<const char*>(kv.second.f.data()), 8 * kv.second.f.size());
        const auto crc = crc32(0L, reinterpret_cast<const Bytef*>(bytes.data()), uInt(bytes.size()));
        header["arrays"][kv.first] = {{"dtype", kv.second.dtype},
                                      {"shape", kv.second.shape},
                                      {"offset", data.size()},
                                      {"nbytes", bytes.size()},
                                      {"crc32", crc}};
        data += bytes;
    }
    if (edit) edit(header);
    const std::string text = header.dump();
    std::string file(8, '\0');
    const std::uint64_t len = text.size();
    std::memcpy(&file[0], &len, 8);
    std::string path = qpsnap_temp_path(name);
    put_bytes(path, file + text + data);
    return path;
}

/// Expects read_qpsnap(path) to throw InputError with exactly "path: tail".
void expect_qpsnap_error(const std::string& path, const std::string& tail)
{
    try {
        read_qpsnap(path);
        ADD_FAILURE() << "no error for " << tail;
    } catch (const InputError& e) {
        EXPECT_EQ(std::string(e.what()), path + ": " + tail);
    }
}

TEST(Qpsnap, TinyRawFileReads)
{
    const std::string path = write_raw("tiny.qpsnap", tiny_arrays());
    const Qp qp = read_qpsnap(path);
    ASSERT_EQ(qp.n(), 3);
    ASSERT_EQ(qp.m(), 2);
    EXPECT_EQ(qp.A.coeff(1, 2), 2.0);
    EXPECT_EQ(qp.A.coeff(0, 2), 0.0);
    EXPECT_EQ(qp.J.coeff(1, 1), -1.0);
    EXPECT_EQ(qp.c[0], 0.5);
    EXPECT_EQ(qp.meta["scene"], "tiny");
    EXPECT_TRUE(qp.contacts.empty());
    EXPECT_EQ(read_qpsnap_header(path)["n"], 3);
}

TEST(Qpsnap, RoundTripIsBitExact)
{
    Qp qp = make_synthetic("coupled", {{"nx", 3}, {"ny", 2}, {"nz", 3}}, 5);
    qp.b[0] = 1.0 / 3.0;  // a value without a short decimal form
    SnapshotExtras extras;
    extras.x_ref = qp.x0 * 0.5;
    extras.lambda_ref = Vec::LinSpaced(qp.m(), 0.0, 1.0);
    const std::string p1 = qpsnap_temp_path("round1.qpsnap"), p2 = qpsnap_temp_path("round2.qpsnap");
    write_qpsnap(p1, qp, &extras);
    SnapshotExtras back_extras;
    const Qp back = read_qpsnap(p1, &back_extras);
    ASSERT_EQ(back.A.nonZeros(), qp.A.nonZeros());
    EXPECT_EQ(std::memcmp(back.A.valuePtr(), qp.A.valuePtr(), 8 * qp.A.nonZeros()), 0);
    EXPECT_EQ(std::memcmp(back.A.innerIndexPtr(), qp.A.innerIndexPtr(), 4 * qp.A.nonZeros()), 0);
    EXPECT_EQ(std::memcmp(back.J.valuePtr(), qp.J.valuePtr(), 8 * qp.J.nonZeros()), 0);
    EXPECT_TRUE(back.b == qp.b);
    EXPECT_TRUE(back.x0 == qp.x0);
    EXPECT_TRUE(back.c == qp.c);
    EXPECT_EQ(back.contacts.kind, qp.contacts.kind);
    EXPECT_EQ(back.contacts.depth, qp.contacts.depth);
    EXPECT_EQ(back.contacts.vertex, qp.contacts.vertex);
    EXPECT_EQ(back.meta, qp.meta);
    EXPECT_TRUE(back_extras.x_ref == extras.x_ref);
    EXPECT_TRUE(back_extras.lambda_ref == extras.lambda_ref);
    write_qpsnap(p2, back, &back_extras);
    EXPECT_EQ(test::file_bytes(p1), test::file_bytes(p2));
    // The data buffer starts 8-byte aligned in the file.
    std::uint64_t len = 0;
    std::memcpy(&len, test::file_bytes(p1).data(), 8);
    EXPECT_EQ((8 + len) % 8, 0u);
    // No temporary left beside the file.
    int entries = 0;
    for (const auto& e : std::filesystem::directory_iterator(std::filesystem::path(p1).parent_path()))
        entries += e.path().string().find(".tmp.") != std::string::npos;
    EXPECT_EQ(entries, 0);
}

TEST(Qpsnap, EmptyJRoundTrip)
{
    const Qp qp = make_synthetic("unconstrained", {{"nx", 1}, {"ny", 1}, {"nz", 1}}, 1);
    const std::string path = qpsnap_temp_path("empty_j.qpsnap");
    write_qpsnap(path, qp);
    const Qp back = read_qpsnap(path);
    EXPECT_EQ(back.m(), 0);
    EXPECT_EQ(back.J.cols(), qp.n());
}

TEST(Qpsnap, ContentHashIsFnv1a)
{
    const std::string path = qpsnap_temp_path("hash.bin");
    put_bytes(path, "a");
    EXPECT_EQ(qpsnap_content_hash(path), "af63dc4c8601ec8c");  // FNV-1a 64 of "a"
    put_bytes(path, "");
    EXPECT_EQ(qpsnap_content_hash(path), "cbf29ce484222325");  // the offset basis
}

TEST(Qpsnap, SmallAsymmetryIsSymmetrisedExactly)
{
    auto a = tiny_arrays();
    a["A.data"] = reals({4, 1, 1 + 1e-15, 5, 2, 2 - 2e-15, 6});
    const Qp qp = read_qpsnap(write_raw("asym_small.qpsnap", a));
    EXPECT_EQ(qp.A.coeff(0, 1), qp.A.coeff(1, 0));
    EXPECT_EQ(qp.A.coeff(0, 1), 0.5 * 1 + 0.5 * (1 + 1e-15));
    EXPECT_EQ(qp.A.coeff(1, 2), qp.A.coeff(2, 1));
}

TEST(Qpsnap, TinyOneSidedEntryIsMirrored)
{
    auto a = tiny_arrays();
    // A(0, 2) = 1e-13 stored, A(2, 0) absent: within 1e-12 * 6, mirrored at half.
    a["A.indptr"] = ints({0, 3, 6, 8});
    a["A.indices"] = ints({0, 1, 2, 0, 1, 2, 1, 2});
    a["A.data"] = reals({4, 1, 1e-13, 1, 5, 2, 2, 6});
    const Qp qp = read_qpsnap(write_raw("one_sided.qpsnap", a));
    EXPECT_EQ(qp.A.coeff(0, 2), 0.5e-13);
    EXPECT_EQ(qp.A.coeff(2, 0), 0.5e-13);
}

// ---- one test per corruption ---------------------------------------------------------------

TEST(QpsnapCorrupt, FileTooShort)
{
    const std::string path = qpsnap_temp_path("short.qpsnap");
    put_bytes(path, "abcde");
    expect_qpsnap_error(path, "header: file too short: 5 bytes, a .qpsnap starts with an 8-byte header length");
}

TEST(QpsnapCorrupt, HeaderLengthBeyondFile)
{
    const std::string path = write_raw("hlen.qpsnap", tiny_arrays());
    std::string bytes = test::file_bytes(path);
    const std::uint64_t huge = 1000000;
    std::memcpy(&bytes[0], &huge, 8);
    put_bytes(path, bytes);
    expect_qpsnap_error(path, "header: header length 1000000 exceeds the file (" + std::to_string(bytes.size() - 8) +
                                  " bytes after the length field)");
}

TEST(QpsnapCorrupt, HeaderNotJson)
{
    const std::string path = write_raw("notjson.qpsnap", tiny_arrays());
    std::string bytes = test::file_bytes(path);
    bytes[8] = '[';  // "{" -> "[": an array with a key in it
    put_bytes(path, bytes);
    expect_qpsnap_error(path, "header: not valid UTF-8 JSON (parse error at header byte 10)");
}

TEST(QpsnapCorrupt, HeaderNotUtf8)
{
    const std::string path = write_raw("utf8.qpsnap", tiny_arrays());
    std::string bytes = test::file_bytes(path);
    const size_t at = bytes.find("tiny");
    bytes[at] = char(0xff);
    put_bytes(path, bytes);
    try {
        read_qpsnap(path);
        FAIL();
    } catch (const InputError& e) {
        EXPECT_EQ(std::string(e.what()).rfind(path + ": header: not valid UTF-8 JSON (parse error at header byte ", 0),
                  0u)
            << e.what();
    }
}

TEST(QpsnapCorrupt, FormatWrong)
{
    expect_qpsnap_error(write_raw("format.qpsnap", tiny_arrays(), 3, 2, [](nlohmann::json& h) { h["format"] = "npz"; }),
                        "format: expected \"qpsnap\", got \"npz\"");
}

TEST(QpsnapCorrupt, VersionUnsupported)
{
    expect_qpsnap_error(write_raw("version.qpsnap", tiny_arrays(), 3, 2, [](nlohmann::json& h) { h["version"] = 3; }),
                        "version: unsupported version 3 (this reader knows versions 1 and 2)");
}

TEST(QpsnapCorrupt, NMissingOrNegative)
{
    expect_qpsnap_error(write_raw("nmissing.qpsnap", tiny_arrays(), 3, 2, [](nlohmann::json& h) { h.erase("n"); }),
                        "n: missing");
    expect_qpsnap_error(write_raw("mneg.qpsnap", tiny_arrays(), 3, -1), "m: expected a non-negative integer, got -1");
}

TEST(QpsnapCorrupt, RequiredArrayMissing)
{
    auto a = tiny_arrays();
    a.erase("J.data");
    expect_qpsnap_error(write_raw("missing.qpsnap", a), "J.data: required array missing");
}

TEST(QpsnapCorrupt, UnknownArray)
{
    auto a = tiny_arrays();
    a["extra"] = reals({1});
    expect_qpsnap_error(write_raw("unknown.qpsnap", a), "arrays.extra: unknown array name");
}

TEST(QpsnapCorrupt, WrongDtype)
{
    auto a = tiny_arrays();
    a["b"].dtype = "int64";
    a["b"].i = {1, 2, 3};
    a["b"].f.clear();
    expect_qpsnap_error(write_raw("dtype.qpsnap", a), "b.dtype: expected \"float64\", got \"int64\"");
}

TEST(QpsnapCorrupt, WrongShape)
{
    auto a = tiny_arrays();
    a["x0"] = reals({0, 0, 0, 0});
    expect_qpsnap_error(write_raw("shape.qpsnap", a), "x0.shape: expected [3] (n = 3), got [4]");
    auto b = tiny_arrays();
    b["J.data"] = reals({1, -1});
    expect_qpsnap_error(write_raw("shape2.qpsnap", b), "J.data.shape: expected [3] (the length of J.indices), got [2]");
}

TEST(QpsnapCorrupt, OffsetMisaligned)
{
    expect_qpsnap_error(
        write_raw("align.qpsnap", tiny_arrays(), 3, 2,
                  [](nlohmann::json& h) { h["arrays"]["b"]["offset"] = h["arrays"]["b"]["offset"].get<int>() + 4; }),
        "b.offset: 220 is not 8-byte aligned");
}

TEST(QpsnapCorrupt, OffsetOutsideBuffer)
{
    expect_qpsnap_error(
        write_raw("outside.qpsnap", tiny_arrays(), 3, 2, [](nlohmann::json& h) { h["arrays"]["c"]["offset"] = 400; }),
        "c.offset: bytes [400, 416) lie outside the data buffer of 280 bytes");
}

TEST(QpsnapCorrupt, NbytesMismatch)
{
    expect_qpsnap_error(
        write_raw("nbytes.qpsnap", tiny_arrays(), 3, 2, [](nlohmann::json& h) { h["arrays"]["b"]["nbytes"] = 16; }),
        "b.nbytes: 16 does not match shape [3] (expected 24)");
}

TEST(QpsnapCorrupt, CrcMismatch)
{
    const std::string path = write_raw("crc.qpsnap", tiny_arrays());
    std::string bytes = test::file_bytes(path);
    bytes[bytes.size() - 1] ^= 0x01;  // last byte of x0 (arrays are written in name order)
    put_bytes(path, bytes);
    const auto h = read_qpsnap_header(path);
    const std::string expected = std::to_string(h["arrays"]["x0"]["crc32"].get<std::uint64_t>());
    try {
        read_qpsnap(path);
        FAIL();
    } catch (const InputError& e) {
        EXPECT_EQ(
            std::string(e.what()).rfind(path + ": x0.crc32: mismatch: header says " + expected + ", data has ", 0), 0u)
            << e.what();
    }
}

TEST(QpsnapCorrupt, IndptrNotStartingAtZero)
{
    auto a = tiny_arrays();
    a["J.indptr"] = ints({1, 1, 3});
    expect_qpsnap_error(write_raw("indptr0.qpsnap", a), "J.indptr: must start at 0, starts at 1");
}

TEST(QpsnapCorrupt, IndptrDecreasing)
{
    auto a = tiny_arrays();
    a["A.indptr"] = ints({0, 5, 2, 7});
    expect_qpsnap_error(write_raw("indptrdec.qpsnap", a), "A.indptr: decreases at row 1 (5 then 2)");
}

TEST(QpsnapCorrupt, IndptrEndNotNnz)
{
    auto a = tiny_arrays();
    a["A.indptr"] = ints({0, 2, 5, 6});
    expect_qpsnap_error(write_raw("indptrend.qpsnap", a),
                        "A.indptr: ends at 6, expected nnz = 7 (the length of A.indices)");
}

TEST(QpsnapCorrupt, IndexOutOfRange)
{
    auto a = tiny_arrays();
    a["A.indices"] = ints({0, 1, 0, 1, 2, 1, 7});
    expect_qpsnap_error(write_raw("range.qpsnap", a), "A.indices: column 7 out of range [0, 3) in row 2");
    auto j = tiny_arrays();
    j["J.indices"] = ints({-1, 1, 2});
    expect_qpsnap_error(write_raw("range2.qpsnap", j), "J.indices: column -1 out of range [0, 3) in row 0");
}

TEST(QpsnapCorrupt, IndicesNotIncreasing)
{
    auto a = tiny_arrays();
    a["J.indices"] = ints({0, 2, 1});
    expect_qpsnap_error(write_raw("sorted.qpsnap", a),
                        "J.indices: columns not strictly increasing in row 1 (2 then 1)");
}

TEST(QpsnapCorrupt, NonFiniteValues)
{
    auto a = tiny_arrays();
    a["b"] = reals({1, std::numeric_limits<double>::quiet_NaN(), 3});
    expect_qpsnap_error(write_raw("nan.qpsnap", a), "b: non-finite value nan at index 1");
    auto j = tiny_arrays();
    j["J.data"] = reals({1, -1, std::numeric_limits<double>::infinity()});
    expect_qpsnap_error(write_raw("inf.qpsnap", j), "J.data: non-finite value inf at index 2");
    auto d = tiny_arrays();
    d["A.data"] = reals({4, 1, 1, -std::numeric_limits<double>::infinity(), 2, 2, 6});
    expect_qpsnap_error(write_raw("infa.qpsnap", d), "A.data: non-finite value -inf at index 3");
}

TEST(QpsnapCorrupt, AsymmetricNamesWorstEntry)
{
    auto a = tiny_arrays();
    a["A.data"] = reals({4, 1, 1.5, 5, 2, 2.25, 6});
    expect_qpsnap_error(write_raw("asym.qpsnap", a),
                        "A: not symmetric: A(0, 1) = 1 but A(1, 0) = 1.5 (difference 0.5 > 1e-12 * max|A_ij| = "
                        "6.0000000000000003e-12)");
}

TEST(QpsnapCorrupt, OneSidedEntryTooLarge)
{
    auto a = tiny_arrays();
    a["A.indptr"] = ints({0, 3, 6, 8});
    a["A.indices"] = ints({0, 1, 2, 0, 1, 2, 1, 2});
    a["A.data"] = reals({4, 1, 0.5, 1, 5, 2, 2, 6});
    expect_qpsnap_error(write_raw("onesided.qpsnap", a),
                        "A: not symmetric: A(0, 2) = 0.5 but A(2, 0) = 0 (difference 0.5 > 1e-12 * max|A_ij| = "
                        "6.0000000000000003e-12)");
}

TEST(QpsnapCorrupt, DiagonalMissingOrNotPositive)
{
    auto a = tiny_arrays();
    a["A.indptr"] = ints({0, 2, 4, 6});
    a["A.indices"] = ints({0, 1, 0, 2, 1, 2});
    a["A.data"] = reals({4, 1, 1, 2, 2, 6});
    expect_qpsnap_error(write_raw("diagmissing.qpsnap", a), "A: diagonal entry A(1, 1) is missing (A must be SPD)");
    auto b = tiny_arrays();
    b["A.data"] = reals({4, 1, 1, 5, 2, 2, -6});
    expect_qpsnap_error(write_raw("diagneg.qpsnap", b),
                        "A: diagonal entry A(2, 2) = -6 is not positive (A must be SPD)");
}

TEST(QpsnapCorrupt, ContactArraysNeedMRows)
{
    auto a = tiny_arrays();
    a["contact.kind"] = ints({0, 2, 2});
    expect_qpsnap_error(write_raw("kind.qpsnap", a), "contact.kind.shape: expected [2] (m = 2), got [3]");
    auto v = tiny_arrays();
    v["contact.vertex"] = ints({0, -1, -1, -1, 1, 2, -1, -1});
    expect_qpsnap_error(write_raw("vertex.qpsnap", v),
                        "contact.vertex.shape: expected [2, 4] (m = 2, 4 vertices per row), got [8]");
    auto k = tiny_arrays();
    k["contact.kind"] = ints({0, 9});
    expect_qpsnap_error(write_raw("kind9.qpsnap", k), "contact.kind: value 9 at row 1 is not a contact kind (0..4)");
}

TEST(QpsnapCorrupt, MissingFile)
{
    const std::string path = qpsnap_temp_path("does_not_exist.qpsnap");
    expect_qpsnap_error(path, "cannot open: No such file or directory");
}

/// Load time of a ~107k-DOF FEM-like snapshot (printed, not asserted: machines differ).
TEST(QpsnapPerf, LoadTimeOf107kDofSnapshot)
{
    Qp qp;
    qp.A = fem_like_matrix(FemGridParams{32, 32, 32, 0.1, 1e6, 0.4, 1000.0, 0.01});
    qp.b = Vec::Ones(qp.A.rows());
    qp.x0 = Vec::Zero(qp.A.rows());
    qp.J.resize(0, qp.A.rows());
    const std::string path = qpsnap_temp_path("big.qpsnap");
    write_qpsnap(path, qp);
    read_qpsnap(path);  // warm the page cache
    const auto t0 = std::chrono::steady_clock::now();
    const std::clock_t c0 = std::clock();
    const Qp back = read_qpsnap(path);
    const double cpu = double(std::clock() - c0) / CLOCKS_PER_SEC;
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::printf("[ perf ] read_qpsnap: n = %ld, nnz(A) = %ld, %.3f s wall, %.3f s cpu\n", long(back.n()),
                long(back.A.nonZeros()), s, cpu);
    EXPECT_EQ(back.A.nonZeros(), qp.A.nonZeros());
    std::filesystem::remove(path);
}

}  // namespace
}  // namespace cb

namespace cb {
namespace {

/// The committed fixture (written by `contactbench generate plane --param nx=2 --param ny=2
/// --param nz=2 --seed 1`) stays readable: a format change that breaks old files fails here.
TEST(QpsnapFixture, CommittedFileReads)
{
    const std::string path = std::string(CB_TEST_DATA_DIR) + "/plane_2x2x2.qpsnap";
    const Qp qp = read_qpsnap(path);
    EXPECT_EQ(qp.n(), 81);
    EXPECT_EQ(qp.m(), 18);
    EXPECT_EQ(qp.contacts.kind.size(), 18u);
    EXPECT_EQ(qp.meta["generator"]["family"], "plane");
    EXPECT_EQ(qpsnap_content_hash(path).size(), 16u);
}

}  // namespace
}  // namespace cb

// Regression (found by tests/fuzz): a header number too large for a double made nlohmann::json
// throw out_of_range, which escaped read_qpsnap instead of becoming an InputError.
TEST(QpsnapFuzzRegression, JsonNumberOverflowIsAnInputError)
{
    const std::string path = std::string(CB_TEST_DATA_DIR) + "/../fuzz/regressions/json-number-overflow.qpsnap";
    try {
        (void)cb::read_qpsnap(path);
        FAIL() << "expected an InputError";
    } catch (const cb::InputError& e) {
        const std::string message = e.what();
        EXPECT_EQ(message.rfind(path + ": header: not a valid JSON header:", 0), 0u) << message;
    }
    EXPECT_THROW((void)cb::read_qpsnap_header(path), cb::InputError);
}

// ---- version 2: Coulomb friction (issue 48) ----

namespace cb {
namespace {

/// tiny_arrays() with friction: mu per row, T = [0 1 0; 0 0 1; 1 0 0; 0 1 1] (2m x n), in version 2.
std::map<std::string, Raw> tiny_friction_arrays()
{
    auto a = tiny_arrays();
    a["mu"] = reals({0.3, 0.0});
    a["T.indptr"] = ints({0, 1, 2, 3, 5});
    a["T.indices"] = ints({1, 2, 0, 1, 2});
    a["T.data"] = reals({1, 1, 1, 1, 1});
    return a;
}

void version2(nlohmann::json& h) { h["version"] = 2; }

/// A synthetic QP with every friction field set.
Qp frictional_synthetic_3x2x3()
{
    Qp qp = make_synthetic("coupled", {{"nx", 3}, {"ny", 2}, {"nz", 3}}, 5);
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

TEST(QpsnapFriction, RoundTripIsBitExactAndVersion2)
{
    const Qp qp = frictional_synthetic_3x2x3();
    ASSERT_TRUE(qp.frictional());
    ASSERT_TRUE(qp.view().frictional());
    const std::string p1 = qpsnap_temp_path("fric1.qpsnap"), p2 = qpsnap_temp_path("fric2.qpsnap");
    write_qpsnap(p1, qp);
    EXPECT_EQ(read_qpsnap_header(p1)["version"], 2);
    EXPECT_EQ(read_qpsnap_header(p1)["h"], 1.0 / 60.0);
    const Qp back = read_qpsnap(p1);
    EXPECT_TRUE(back.friction.mu == qp.friction.mu);
    ASSERT_EQ(back.friction.T.rows(), 2 * qp.m());
    ASSERT_EQ(back.friction.T.nonZeros(), qp.friction.T.nonZeros());
    EXPECT_EQ(std::memcmp(back.friction.T.valuePtr(), qp.friction.T.valuePtr(), 8 * qp.friction.T.nonZeros()), 0);
    EXPECT_EQ(std::memcmp(back.friction.T.innerIndexPtr(), qp.friction.T.innerIndexPtr(), 4 * qp.friction.T.nonZeros()),
              0);
    EXPECT_TRUE(back.friction.cT == qp.friction.cT);
    EXPECT_EQ(back.friction.h, qp.friction.h);
    EXPECT_TRUE(back.friction.v0 == qp.friction.v0);
    EXPECT_TRUE(back.frictional());
    write_qpsnap(p2, back);
    EXPECT_EQ(test::file_bytes(p1), test::file_bytes(p2));
}

TEST(QpsnapFriction, FrictionlessQpIsWrittenAsVersion1Unchanged)
{
    // A QP without friction fields is the file it was before version 2, byte for byte.
    Qp qp = frictional_synthetic_3x2x3();
    qp.friction = Friction{};
    const std::string p = qpsnap_temp_path("nofric.qpsnap");
    write_qpsnap(p, qp);
    EXPECT_EQ(read_qpsnap_header(p)["version"], 1);
    EXPECT_FALSE(read_qpsnap_header(p).contains("h"));
    const Qp back = read_qpsnap(p);
    EXPECT_TRUE(back.friction.empty());
    EXPECT_FALSE(back.frictional());
    EXPECT_FALSE(back.view().frictional());
    // mu = 0 everywhere: written (version 2), but not frictional.
    qp = frictional_synthetic_3x2x3();
    qp.friction.mu.setZero();
    write_qpsnap(p, qp);
    EXPECT_EQ(read_qpsnap_header(p)["version"], 2);
    EXPECT_FALSE(read_qpsnap(p).frictional());
}

TEST(QpsnapFriction, Version1FileReadsAsFrictionless)
{
    const Qp qp = read_qpsnap(write_raw("v1.qpsnap", tiny_arrays()));
    EXPECT_TRUE(qp.friction.empty());
    EXPECT_FALSE(qp.frictional());
    const Qp fr = read_qpsnap(write_raw("v2.qpsnap", tiny_friction_arrays(), 3, 2, version2));
    EXPECT_TRUE(fr.frictional());
    EXPECT_EQ(fr.friction.mu[0], 0.3);
    EXPECT_EQ(fr.friction.T.coeff(3, 2), 1.0);
    EXPECT_EQ(fr.friction.cT.size(), 0);
    EXPECT_EQ(fr.friction.h, 0.0);
}

TEST(QpsnapFrictionCorrupt, MuNegativeOrNaN)
{
    auto a = tiny_friction_arrays();
    a["mu"] = reals({0.3, -0.5});
    expect_qpsnap_error(write_raw("mu_neg.qpsnap", a, 3, 2, version2),
                        "mu: negative friction coefficient -0.5 at contact 1");
    a["mu"] = reals({std::nan(""), 0.1});
    expect_qpsnap_error(write_raw("mu_nan.qpsnap", a, 3, 2, version2), "mu: non-finite value nan at index 0");
    a["mu"] = reals({0.3});
    expect_qpsnap_error(write_raw("mu_size.qpsnap", a, 3, 2, version2),
                        "mu.shape: expected [2] (m = 2, one per contact row), got [1]");
}

TEST(QpsnapFrictionCorrupt, MuWithoutTangentsAndTangentsWithoutMu)
{
    auto a = tiny_friction_arrays();
    for (const char* t : {"T.indptr", "T.indices", "T.data"}) a.erase(t);
    expect_qpsnap_error(write_raw("mu_no_t.qpsnap", a, 3, 2, version2),
                        "T: missing: mu needs the two tangent rows per contact (T, 2m x n)");
    a = tiny_friction_arrays();
    a.erase("mu");
    expect_qpsnap_error(write_raw("t_no_mu.qpsnap", a, 3, 2, version2),
                        "mu: missing: T is given without friction coefficients");
    a = tiny_friction_arrays();
    a.erase("T.data");
    expect_qpsnap_error(write_raw("t_part.qpsnap", a, 3, 2, version2),
                        "T.data: missing (T is given as T.indptr, T.indices, T.data)");
}

TEST(QpsnapFrictionCorrupt, TangentRowsOfTheWrongSize)
{
    auto a = tiny_friction_arrays();
    a["T.indptr"] = ints({0, 1, 2, 3});  // 3 rows, not 2m = 4
    a["T.indices"] = ints({1, 2, 0});
    a["T.data"] = reals({1, 1, 1});
    expect_qpsnap_error(write_raw("t_rows.qpsnap", a, 3, 2, version2),
                        "T.indptr.shape: expected [5] (m = 2, two tangent rows per contact, 2m + 1 entries), got [4]");
    a = tiny_friction_arrays();
    a["T.indices"] = ints({1, 2, 0, 1, 3});  // column 3 of n = 3
    expect_qpsnap_error(write_raw("t_cols.qpsnap", a, 3, 2, version2),
                        "T.indices: column 3 out of range [0, 3) in row 3");
    a = tiny_friction_arrays();
    a["T.data"] = reals({1, 1, 1, std::numeric_limits<double>::infinity(), 1});
    expect_qpsnap_error(write_raw("t_inf.qpsnap", a, 3, 2, version2), "T.data: non-finite value inf at index 3");
    a = tiny_friction_arrays();
    a["cT"] = reals({0, 0, 0});
    expect_qpsnap_error(write_raw("ct_size.qpsnap", a, 3, 2, version2),
                        "cT.shape: expected [4] (m = 2, two per contact), got [3]");
}

TEST(QpsnapFrictionCorrupt, StepAndStartVelocities)
{
    auto a = tiny_friction_arrays();
    a["v0"] = reals({0, 1, 2});
    expect_qpsnap_error(write_raw("v0_no_h.qpsnap", a, 3, 2, version2), "h: missing: v0 is given without the step h");
    expect_qpsnap_error(write_raw("h_neg.qpsnap", a, 3, 2, [](nlohmann::json& h) { h["version"] = 2, h["h"] = -0.01; }),
                        "h: expected a positive finite time step, got -0.01");
    expect_qpsnap_error(
        write_raw("h_str.qpsnap", a, 3, 2, [](nlohmann::json& h) { h["version"] = 2, h["h"] = "0.01"; }),
        "h: expected a positive finite time step, got \"0.01\"");
    a["v0"] = reals({0, 1});
    expect_qpsnap_error(
        write_raw("v0_size.qpsnap", a, 3, 2, [](nlohmann::json& h) { h["version"] = 2, h["h"] = 0.01; }),
        "v0.shape: expected [3] (n = 3), got [2]");
}

TEST(QpsnapFrictionCorrupt, Version2FieldsInAVersion1File)
{
    expect_qpsnap_error(write_raw("v1_mu.qpsnap", tiny_friction_arrays()),
                        "arrays.T.data: a version 2 array in a version 1 snapshot");
    expect_qpsnap_error(write_raw("v1_h.qpsnap", tiny_arrays(), 3, 2, [](nlohmann::json& h) { h["h"] = 0.01; }),
                        "h: a version 2 field in a version 1 snapshot");
}

TEST(QpsnapFrictionCorrupt, WriterRefusesWhatTheReaderRefuses)
{
    const std::string p = qpsnap_temp_path("w_bad.qpsnap");
    auto expect_write_error = [&](const Qp& qp, const std::string& tail) {
        try {
            write_qpsnap(p, qp);
            ADD_FAILURE() << "no error for " << tail;
        } catch (const InputError& e) {
            EXPECT_EQ(std::string(e.what()), p + " (writing): " + tail);
        }
        EXPECT_FALSE(std::filesystem::exists(p));
    };
    Qp qp = frictional_synthetic_3x2x3();
    qp.friction.mu[2] = -1.0;
    expect_write_error(qp, "mu: negative friction coefficient -1 at contact 2");
    qp = frictional_synthetic_3x2x3();
    qp.friction.mu[0] = std::nan("");
    expect_write_error(qp, "mu: non-finite value nan at index 0");
    qp = frictional_synthetic_3x2x3();
    qp.friction.T.resize(qp.m(), qp.n());
    expect_write_error(qp, "T: expected 2m x n = " + std::to_string(2 * qp.m()) + " x " + std::to_string(qp.n()) +
                               " (two tangent rows per contact), got " + std::to_string(qp.m()) + " x " +
                               std::to_string(qp.n()));
    qp = frictional_synthetic_3x2x3();
    qp.friction.T = SpMat();
    expect_write_error(qp, "T: missing: mu needs the two tangent rows per contact (T, 2m x n)");
    qp = frictional_synthetic_3x2x3();
    qp.friction.h = 0.0;
    expect_write_error(qp, "h: missing: v0 is given without the step h");
}

}  // namespace
}  // namespace cb
