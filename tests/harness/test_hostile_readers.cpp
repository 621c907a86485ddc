// Issue 42 through the contactbench binary (env CB_CONTACTBENCH): readers bound what they
// allocate by the bytes present (or the snapshot's n), a QP with no unknowns is refused in one
// place, numbers from files and the command line are finite and in range, results folders are
// read only when whole, and every refusal is exit 2 naming the file and the field.
#include "harness/results.hpp"
#include "problems/qpsnap.hpp"
#include "problems/synthetic.hpp"
#include "tests/harness/shell_quoted.hpp"

#include "tests/harness/cli_test_util.hpp"
#include "tests/harness/remove_at_end.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <fcntl.h>
#include <filesystem>
#include <fstream>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

namespace fs = std::filesystem;
using namespace cb;
using cb::test::Output;

namespace {

const fs::path& readers_work_dir()
{
    static const fs::path dir = test::make_test_work_dir("hostile_readers");
    return dir;
}

/// Runs `[PREFIX;] timeout 120 contactbench ARGS` in bash; a hang ends as 124.
Output run_reader(const std::string& args, const std::string& prefix = "")
{
    test::CliCall call;
    call.prefix = prefix;
    return test::run_contactbench(args, readers_work_dir(), call);
}

fs::path fresh_readers_dir(const std::string& name)
{
    fs::path d = readers_work_dir() / name;
    fs::remove_all(d);
    fs::create_directories(d);
    return d;
}

void write_bytes(const fs::path& p, const std::string& bytes) { std::ofstream(p, std::ios::binary) << bytes; }

/// The plane snapshot (2 x 2 x 2 cells) judge and solve read; returns its n.
long plane(const fs::path& p)
{
    const Qp qp = make_synthetic("plane", {{"nx", 2}, {"ny", 2}, {"nz", 2}}, 1);
    write_qpsnap(p.string(), qp);
    return qp.n();
}

/// A .npy file: the magic, version 1.0, the header dict padded to 64 bytes, then `data`.
std::string npy(const std::string& dict, const std::string& data)
{
    std::string header = dict;
    while ((10 + header.size() + 1) % 64 != 0) header += ' ';
    header += '\n';
    std::string out = "\x93NUMPY\x01";
    out += '\0';
    out += char(header.size() & 0xff);
    out += char(header.size() >> 8);
    return out + header + data;
}

std::string doubles(long n, double v)
{
    std::string s(size_t(n) * 8, '\0');
    for (long i = 0; i < n; ++i) std::memcpy(&s[size_t(i) * 8], &v, 8);
    return s;
}

const auto* const READERS_CLEAN_UP = ::testing::AddGlobalTestEnvironment(new test::RemoveAtEnd(readers_work_dir));

/// 600 MB of address space: the binary and its libraries, far from what a declared size once cost.
const std::string LIMIT = "ulimit -v 600000";

}  // namespace

// ---- F4: an empty QP -------------------------------------------------------------------------

TEST(HostileReaders, QpWithNoUnknownsIsRefusedByEveryReader)
{
    const fs::path dir = fresh_readers_dir("empty_qp");
    // A .qpsnap of n = 0, m = 0, as the writer lays it out (the FCLIB reader's empty problem
    // converted gave the same file).
    Qp empty;
    empty.A = SpMat(0, 0);
    empty.J = SpMat(0, 0);
    write_qpsnap((dir / "empty.qpsnap").string(), empty);
    const std::string refusal =
        (dir / "empty.qpsnap").string() + ": n: no unknowns (n = 0): an empty problem has nothing to solve\n";
    for (const char* solver : {"active-set", "pgs", "mprgp-coupled"}) {
        const Output o = run_reader("solve " + test::shell_quoted(dir / "empty.qpsnap") + " --solver " + solver);
        EXPECT_EQ(o.status, 2) << solver << ": " << o.err;  // was SIGSEGV (139)
        EXPECT_EQ(o.err, "contactbench solve: error: " + refusal) << solver;
    }
    // The Matrix Market folder reader goes through validate_qp: the same rule, the same words.
    fs::create_directories(dir / "mm");
    write_bytes(dir / "mm" / "A.mtx", "%%MatrixMarket matrix coordinate real general\n0 0 0\n");
    for (const char* v : {"b", "x0", "c"})
        write_bytes(dir / "mm" / (std::string(v) + ".mtx"), "%%MatrixMarket matrix array real general\n0 1\n");
    write_bytes(dir / "mm" / "J.mtx", "%%MatrixMarket matrix coordinate real general\n0 0 0\n");
    const Output mm =
        run_reader("convert " + test::shell_quoted(dir / "mm") + " " + test::shell_quoted(dir / "mm.qpsnap"));
    EXPECT_EQ(mm.status, 2) << mm.err;
    EXPECT_EQ(mm.err, "contactbench convert: error: " + (dir / "mm").string() +
                          ": n: no unknowns (n = 0): an empty problem has nothing to solve\n");
    EXPECT_FALSE(fs::exists(dir / "mm.qpsnap"));
}

// ---- judge's solution readers ------------------------------------------------------------------

TEST(HostileReaders, TextVectorWithANulByteEndsAtOnce)
{
    const fs::path dir = fresh_readers_dir("nul");
    plane(dir / "plane.qpsnap");
    write_bytes(dir / "nul.txt", std::string(1, '\0'));
    const Output o = run_reader(
        "judge " + test::shell_quoted(dir / "plane.qpsnap") + " " + test::shell_quoted(dir / "nul.txt"), LIMIT);
    EXPECT_EQ(o.status, 2) << o.err;  // was an endless loop growing to bad_alloc
    EXPECT_EQ(o.err, "contactbench judge: error: " + (dir / "nul.txt").string() +
                         ": line 1: expected a number of x, got '\\x00'\n");
    write_bytes(dir / "nul2.txt", std::string("1 2\0003", 5));
    const Output o2 = run_reader(
        "judge " + test::shell_quoted(dir / "plane.qpsnap") + " " + test::shell_quoted(dir / "nul2.txt"), LIMIT);
    EXPECT_EQ(o2.status, 2) << o2.err;
    EXPECT_EQ(o2.err, "contactbench judge: error: " + (dir / "nul2.txt").string() +
                          ": line 1: expected a number of x, got '2\\x003'\n");
}

TEST(HostileReaders, SolutionReadersAllocateByTheSnapshotNotTheFile)
{
    const fs::path dir = fresh_readers_dir("declared");
    const long n = plane(dir / "plane.qpsnap");
    const std::string judge = "judge " + test::shell_quoted(dir / "plane.qpsnap") + " ";
    const std::string error = "contactbench judge: error: ";
    // J2: 60 bytes declaring 3e8 rows (2.4 GB once allocated before n was checked).
    write_bytes(dir / "decl.mtx", "%%MatrixMarket matrix coordinate real general\n300000000 1 0\n");
    Output o = run_reader(judge + test::shell_quoted(dir / "decl.mtx"), LIMIT);
    EXPECT_EQ(o.status, 2) << o.err;
    EXPECT_EQ(o.err, error + (dir / "decl.mtx").string() + ": size: expected " + std::to_string(n) +
                         " entries (n of the snapshot), got 300000000\n");
    // More entries declared than positions: duplicates certain, refused before they are stored.
    write_bytes(dir / "many.mtx", "%%MatrixMarket matrix coordinate real general\n3 1 100000000\n");
    o = run_reader(judge + test::shell_quoted(dir / "many.mtx"), LIMIT);
    EXPECT_EQ(o.status, 2) << o.err;
    EXPECT_EQ(o.err, error + (dir / "many.mtx").string() +
                         ": line 2: declares 100000000 entries, more than the 3 x 1 matrix holds\n");
    // J3: a shape of 2^61 entries: count * 8 wrapped to 0 bytes and passed the size check.
    write_bytes(dir / "wrap.npy",
                npy("{'descr': '<f8', 'fortran_order': False, 'shape': (2305843009213693952,), }", ""));
    o = run_reader(judge + test::shell_quoted(dir / "wrap.npy"), LIMIT);
    EXPECT_EQ(o.status, 2) << o.err;
    EXPECT_EQ(o.err, error + (dir / "wrap.npy").string() +
                         ": x: shape (2305843009213693952,) declares 2305843009213693952 entries, the file holds 0 "
                         "bytes of data (0 entries of 8 bytes)\n");
    // J4: 50 M entries of text (100 MB): counted, refused before a value is stored (was ~9x the file).
    {
        std::ofstream big(dir / "big.txt");
        std::string zeros;
        for (int i = 0; i < (1 << 19); ++i) zeros += "0\n";
        for (int k = 0; k < 100; ++k) big << zeros;
    }
    o = run_reader(judge + test::shell_quoted(dir / "big.txt"), LIMIT);
    EXPECT_EQ(o.status, 2) << o.err;
    EXPECT_EQ(o.err, error + (dir / "big.txt").string() + ": x: expected " + std::to_string(n) +
                         " entries (n of the snapshot), got 52428800\n");
    fs::remove(dir / "big.txt");
}

TEST(HostileReaders, NpyHeaderIsParsedAsADict)
{
    const fs::path dir = fresh_readers_dir("npy");
    const long n = plane(dir / "plane.qpsnap");
    const std::string judge = "judge " + test::shell_quoted(dir / "plane.qpsnap") + " ";
    // J5: a decoy 'descr' inside another value; the real dtype is int64 (once read as float64).
    write_bytes(dir / "decoy.npy", npy("{'shape': (" + std::to_string(n) +
                                           ",), 'fortran_order': False, 'note': \"'descr': '<f8', \", "
                                           "'descr': '<i8', }",
                                       doubles(n, 0.0)));
    Output o = run_reader(judge + test::shell_quoted(dir / "decoy.npy"));
    EXPECT_EQ(o.status, 2) << o.err;
    EXPECT_EQ(o.err, "contactbench judge: error: " + (dir / "decoy.npy").string() +
                         ": note: unknown key in the .npy header (descr, fortran_order, shape)\n");
    write_bytes(dir / "i8.npy", npy("{'descr': '<i8', 'fortran_order': False, 'shape': (" + std::to_string(n) + ",), }",
                                    doubles(n, 0.0)));
    o = run_reader(judge + test::shell_quoted(dir / "i8.npy"));
    EXPECT_EQ(o.status, 2) << o.err;
    EXPECT_EQ(o.err, "contactbench judge: error: " + (dir / "i8.npy").string() +
                         ": x: dtype '<i8' not supported; write float64 (numpy: x.astype(float))\n");
    write_bytes(dir / "twice.npy",
                npy("{'descr': '<i8', 'descr': '<f8', 'fortran_order': False, 'shape': (" + std::to_string(n) + ",), }",
                    doubles(n, 0.0)));
    o = run_reader(judge + test::shell_quoted(dir / "twice.npy"));
    EXPECT_EQ(o.status, 2) << o.err;
    EXPECT_EQ(o.err, "contactbench judge: error: " + (dir / "twice.npy").string() +
                         ": descr: given twice in the .npy header\n");
    // A well-formed one still reads.
    write_bytes(
        dir / "good.npy",
        npy("{'descr': '<f8', 'fortran_order': False, 'shape': (" + std::to_string(n) + ",), }", doubles(n, 0.0)));
    o = run_reader(judge + test::shell_quoted(dir / "good.npy"));
    EXPECT_EQ(o.status, 0) << o.err;
}

TEST(HostileReaders, JudgeCommandLineAndRecordChecks)
{
    const fs::path dir = fresh_readers_dir("judge_checks");
    plane(dir / "plane.qpsnap");
    const std::string snap = test::shell_quoted(dir / "plane.qpsnap");
    ASSERT_EQ(run_reader("solve " + snap + " --solver pgs --json " + test::shell_quoted(dir / "rec.json") +
                         " --save-solution " + test::shell_quoted(dir / "sol"))
                  .status,
              0);
    const std::string judge = "judge " + snap + " " + test::shell_quoted(dir / "sol");
    // J9: --tol inf and 1e999 (once "converged at tol inf").
    for (const char* tol : {"inf", "1e999", "nan"}) {
        const Output o = run_reader(judge + " --tol " + tol);
        EXPECT_EQ(o.status, 2) << tol;
        EXPECT_EQ(o.err, std::string("contactbench judge: error: judge: --tol: expected a finite number, got '") + tol +
                             "'\n");
    }
    // J8 / J7: the record must name this snapshot by a hash string.
    nlohmann::json rec = read_json_file((dir / "rec.json").string());
    nlohmann::json no_snapshot = rec;
    no_snapshot.erase("snapshot");
    write_json_atomic((dir / "no_snap.json").string(), no_snapshot);
    Output o = run_reader(judge + " --record " + test::shell_quoted(dir / "no_snap.json"));
    EXPECT_EQ(o.status, 2) << o.err;  // was judged with no snapshot check at all
    EXPECT_EQ(o.err, "contactbench judge: error: " + (dir / "no_snap.json").string() +
                         ": /snapshot: missing or not an object: is this a run record (solve --json, a suite's "
                         "runs/*.json)?\n");
    nlohmann::json hash_num = rec;
    hash_num["snapshot"]["hash"] = 5;
    write_json_atomic((dir / "hash_num.json").string(), hash_num);
    o = run_reader(judge + " --record " + test::shell_quoted(dir / "hash_num.json"));
    EXPECT_EQ(o.status, 2) << o.err;  // was a raw type_error, exit 1
    EXPECT_EQ(o.err, "contactbench judge: error: " + (dir / "hash_num.json").string() +
                         ": /snapshot/hash: missing or not a non-empty string: the record does not say which snapshot "
                         "it ran on\n");
    // J6: a symlink loop as the solution.
    fs::create_symlink("loop", dir / "loop");
    o = run_reader("judge " + snap + " " + test::shell_quoted(dir / "loop"));
    EXPECT_EQ(o.status, 2) << o.err;  // was "internal error: filesystem error", exit 1
    EXPECT_EQ(o.err, "contactbench judge: error: " + (dir / "loop").string() +
                         ": x: cannot open: Too many levels of symbolic links\n");
}

// ---- suites, scenes and meshes -----------------------------------------------------------------

TEST(HostileReaders, SuiteDuplicateKeysAndHugeTimeLimitAreRefused)
{
    const fs::path dir = fresh_readers_dir("suite_checks");
    plane(dir / "plane.qpsnap");
    write_bytes(dir / "dup.json",
                R"({"name": "d", "snapshots": ["plane.qpsnap"], "solvers": ["pgs"], "solvers": ["cg"]})");
    Output o = run_reader("run " + test::shell_quoted(dir / "dup.json") + " --out " + test::shell_quoted(dir / "out"));
    EXPECT_EQ(o.status, 2) << o.err;  // was accepted, the last "solvers" silently winning
    EXPECT_EQ(o.err, "contactbench run: error: " + (dir / "dup.json").string() +
                         ": /solvers: key given twice in one object (each key once)\n");
    write_bytes(dir / "nested.json",
                R"({"name": "d", "snapshots": ["plane.qpsnap"], "solvers": [{"solver": "pgs", "solver": "cg"}]})");
    o = run_reader("run " + test::shell_quoted(dir / "nested.json") + " --out " + test::shell_quoted(dir / "out"));
    EXPECT_EQ(o.status, 2) << o.err;
    EXPECT_EQ(o.err, "contactbench run: error: " + (dir / "nested.json").string() +
                         ": /solvers/0/solver: key given twice in one object (each key once)\n");
    write_bytes(dir / "tl.json",
                R"({"name": "t", "snapshots": ["plane.qpsnap"], "solvers": ["pgs"], "time_limit_s": 1e308})");
    o = run_reader("run " + test::shell_quoted(dir / "tl.json") + " --out " + test::shell_quoted(dir / "out"));
    EXPECT_EQ(o.status, 2) << o.err;  // was accepted, and every run failed
    EXPECT_EQ(o.err, "contactbench run: error: " + (dir / "tl.json").string() +
                         ": /time_limit_s: must be <= 1e6 seconds (11.6 days; 0 disables), got 1e+308\n");
    // S3: a FIFO named as a snapshot is named as one (was "no such file").
    ASSERT_EQ(::mkfifo((dir / "fifo.qpsnap").c_str(), 0644), 0);
    write_bytes(dir / "fifo.json", R"({"name": "f", "snapshots": ["fifo.qpsnap"], "solvers": ["pgs"]})");
    o = run_reader("run " + test::shell_quoted(dir / "fifo.json") + " --out " + test::shell_quoted(dir / "out"));
    EXPECT_EQ(o.status, 2) << o.err;
    EXPECT_EQ(o.err, "contactbench run: error: " + (dir / "fifo.json").string() + ": /snapshots/0: '" +
                         (dir / "fifo.qpsnap").string() + "': not a regular file (a FIFO)\n");
    EXPECT_FALSE(fs::exists(dir / "out" / "runs"));
    // A link loop in a snapshot folder fails its own run by name (was "internal error: filesystem error").
    fs::create_directories(dir / "loops");
    fs::create_symlink("self.qpsnap", dir / "loops" / "self.qpsnap");
    fs::copy_file(dir / "plane.qpsnap", dir / "loops" / "a.qpsnap");
    write_bytes(dir / "loops.json", R"({"name": "l", "snapshots": ["loops"], "solvers": ["pgs"]})");
    o = run_reader("run " + test::shell_quoted(dir / "loops.json") + " --out " + test::shell_quoted(dir / "lo"));
    EXPECT_EQ(o.status, 0) << o.err;
    EXPECT_NE(o.err.find("self x pgs: invalid_input: " + (dir / "loops" / "self.qpsnap").string() +
                         ": cannot open: Too many levels of symbolic links"),
              std::string::npos)
        << o.err;
}

TEST(HostileReaders, MeshSizesAreBoundedBeforeAllocation)
{
    const fs::path dir = fresh_readers_dir("meshes");
    // S2: an OFF file declaring 2e9 vertices (reserved in full once).
    write_bytes(dir / "h.off", "OFF\n2000000000 1 0\n0 0 0\n");
    write_bytes(dir / "o.json", R"({"name": "o", "frames": 1, "bodies": [{"mesh": "h.off"}]})");
    Output o = run_reader("simulate " + test::shell_quoted(dir / "o.json") + " --frames 0 --no-snapshots --out " +
                              test::shell_quoted(dir / "o"),
                          LIMIT);
    EXPECT_EQ(o.status, 2) << o.err;
    EXPECT_NE(o.err.find((dir / "h.off").string() + ": "), std::string::npos) << o.err;
    EXPECT_NE(o.err.find("expected 2000000000 vertices, got 1"), std::string::npos) << o.err;
    // S1: a tetrahedron at resolution 512: 805M grid tets were built before the 6M-tet limit.
    write_bytes(dir / "tet.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n");
    write_bytes(dir / "r.json", R"({"name": "r", "frames": 1, "bodies": [{"mesh": )"
                                R"({"path": "tet.obj", "resolution": 512, "fit_size": 0.2}}]})");
    o = run_reader("simulate " + test::shell_quoted(dir / "r.json") + " --frames 0 --no-snapshots --out " +
                       test::shell_quoted(dir / "r"),
                   "ulimit -v 1500000");
    EXPECT_EQ(o.status, 2) << o.err;
    EXPECT_EQ(o.err, "contactbench simulate: error: " + (dir / "tet.obj").string() +
                         ": resolution: 512 puts more than 6000000 tets inside the surface (the limit); use a lower "
                         "resolution\n");
    // S7: a box whose cells are too small: the scene file and field named.
    write_bytes(dir / "tiny.json", R"({"name": "t", "frames": 1, "bodies": [{"box": {"cells": [2, 2, 2], )"
                                   R"("size": [1e-300, 1e-300, 1e-300]}}]})");
    o = run_reader("simulate " + test::shell_quoted(dir / "tiny.json") + " --frames 0 --no-snapshots --out " +
                   test::shell_quoted(dir / "t"));
    EXPECT_EQ(o.status, 2) << o.err;
    EXPECT_EQ(
        o.err.rfind("contactbench simulate: error: " + (dir / "tiny.json").string() + ": /bodies/0/box/size: ", 0), 0u)
        << o.err;
}

// ---- results folders judged whole --------------------------------------------------------------

TEST(HostileReaders, ResultsFoldersAreReadOnlyWhenWhole)
{
    const fs::path dir = fresh_readers_dir("whole");
    plane(dir / "plane.qpsnap");
    write_bytes(dir / "s.json", R"({"name": "s", "snapshots": ["plane.qpsnap"], "solvers": ["pgs"]})");
    const fs::path base = dir / "b";
    ASSERT_EQ(run_reader("run " + test::shell_quoted(dir / "s.json") + " --out " + test::shell_quoted(base)).status, 0);
    auto copy_of_base = [&](const std::string& name) {
        const fs::path to = dir / name;
        fs::remove_all(to);
        fs::copy(base, to, fs::copy_options::recursive);
        return to;
    };
    // R4: NEW regressed, and a stale copy of BASE's record beside it once shadowed the regression.
    const fs::path next = copy_of_base("n");
    nlohmann::json regressed = read_json_file((next / "runs" / "plane__pgs.json").string());
    regressed["status"] = "diverged";
    write_json_atomic((next / "runs" / "plane__pgs.json").string(), regressed);
    fs::copy_file(base / "runs" / "plane__pgs.json", next / "runs" / "zz_stale.json");
    Output o = run_reader("compare " + test::shell_quoted(base) + " " + test::shell_quoted(next));
    EXPECT_EQ(o.status, 2) << o.out << o.err;  // was PASS
    EXPECT_EQ(o.err, "contactbench compare: error: " + (next / "runs" / "zz_stale.json").string() + ": not a job of " +
                         (next / "jobs.json").string() + ": a stray or stale file (remove it, or run again)\n");
    // R5: a killed run (suite.pending.json, no jobs.json) read as a BASE.
    const fs::path killed = copy_of_base("k");
    fs::rename(killed / "suite.json", killed / "suite.pending.json");
    fs::remove(killed / "jobs.json");
    o = run_reader("compare " + test::shell_quoted(killed) + " " + test::shell_quoted(base));
    EXPECT_EQ(o.status, 2) << o.out << o.err;
    EXPECT_EQ(o.err, "contactbench compare: error: " + killed.string() +
                         ": suite.pending.json: present: the folder's `contactbench run` was interrupted or is still "
                         "running, so its results are incomplete (run it again to finish)\n");
    // R6: merge of a run marked final: false, and of a file holding another job's record.
    const fs::path retry = copy_of_base("f");
    nlohmann::json not_final = read_json_file((retry / "runs" / "plane__pgs.json").string());
    not_final["final"] = false;
    write_json_atomic((retry / "runs" / "plane__pgs.json").string(), not_final);
    o = run_reader("merge " + test::shell_quoted(dir / "m") + " " + test::shell_quoted(retry));
    EXPECT_EQ(o.status, 2) << o.err;
    EXPECT_EQ(o.err, "contactbench merge: error: " + (retry / "runs" / "plane__pgs.json").string() +
                         ": /final: false: the run ended in an error to be retried, not a result (run the suite "
                         "again)\n");
    const fs::path other = copy_of_base("o");
    nlohmann::json foreign = read_json_file((other / "runs" / "plane__pgs.json").string());
    foreign["label"] = "cg";
    write_json_atomic((other / "runs" / "plane__pgs.json").string(), foreign);
    o = run_reader("merge " + test::shell_quoted(dir / "m") + " " + test::shell_quoted(other));
    EXPECT_EQ(o.status, 2) << o.err;
    EXPECT_EQ(o.err, "contactbench merge: error: " + (other / "runs" / "plane__pgs.json").string() +
                         ": /snapshot/id, /label: the record is of job plane__cg.json, not of this file: a copy or "
                         "another job's record (remove it, or run again)\n");
    // merge read a string counter as it came (compare refused it): now both check the types.
    const fs::path stringly = copy_of_base("str");
    nlohmann::json counted = read_json_file((stringly / "runs" / "plane__pgs.json").string());
    ASSERT_TRUE(counted["counters"].contains("a_products"));
    counted["counters"]["a_products"] = "12";
    write_json_atomic((stringly / "runs" / "plane__pgs.json").string(), counted);
    o = run_reader("merge " + test::shell_quoted(dir / "m") + " " + test::shell_quoted(stringly));
    EXPECT_EQ(o.status, 2) << o.err;
    EXPECT_EQ(o.err, "contactbench merge: error: " + (stringly / "runs" / "plane__pgs.json").string() +
                         ": /counters/a_products: expected a number, got \"12\"\n");
    EXPECT_FALSE(fs::exists(dir / "m"));
    // R3: merge into a folder a run is writing (the run holds OUT/.lock); compare of it too.
    const fs::path busy = copy_of_base("busy");
    const int fd = ::open((busy / ".lock").c_str(), O_RDWR | O_CREAT, 0644);
    ASSERT_GE(fd, 0);
    ASSERT_EQ(::flock(fd, LOCK_EX), 0);
    const std::string me = std::to_string(::getpid());
    const std::string holder = me + " run\n";  // as `run` writes it: "<pid> <command>"
    ASSERT_EQ(::ftruncate(fd, 0), 0);
    ASSERT_EQ(::pwrite(fd, holder.data(), holder.size(), 0), ssize_t(holder.size()));
    o = run_reader("merge " + test::shell_quoted(busy) + " " + test::shell_quoted(base));
    EXPECT_EQ(o.status, 2) << o.err;
    EXPECT_EQ(o.err, "contactbench merge: error: " + busy.string() + ": another `contactbench run` (pid " + me +
                         ") is writing to this folder; wait for it to finish or use another --out\n");
    o = run_reader("compare " + test::shell_quoted(base) + " " + test::shell_quoted(busy));
    EXPECT_EQ(o.status, 2) << o.err;
    EXPECT_EQ(o.err, "contactbench compare: error: " + busy.string() + ": being written by `contactbench run` (pid " +
                         me + ", holding .lock): not a finished result; wait for it to finish\n");
    ::close(fd);
    // A FIFO among the run files is named, never opened.
    const fs::path fifo = copy_of_base("fifo");
    ASSERT_EQ(::mkfifo((fifo / "runs" / "zz__pgs.json").c_str(), 0644), 0);
    o = run_reader("compare " + test::shell_quoted(base) + " " + test::shell_quoted(fifo));
    EXPECT_EQ(o.status, 2) << o.err;
    EXPECT_EQ(o.err, "contactbench compare: error: " + (fifo / "runs" / "zz__pgs.json").string() + ": not a job of " +
                         (fifo / "jobs.json").string() + ": a stray or stale file (remove it, or run again)\n");
    // R7: a type confused in a record is named with its file and field (was a raw type_error).
    const fs::path typed = copy_of_base("typed");
    nlohmann::json strings = read_json_file((typed / "runs" / "plane__pgs.json").string());
    strings["time"]["samples_total_s"] = {"a", "b"};
    write_json_atomic((typed / "runs" / "plane__pgs.json").string(), strings);
    o = run_reader("compare " + test::shell_quoted(base) + " " + test::shell_quoted(typed));
    EXPECT_EQ(o.status, 2) << o.err;
    EXPECT_EQ(o.err, "contactbench compare: error: " + (typed / "runs" / "plane__pgs.json").string() +
                         ": /time/samples_total_s: expected numbers (seconds), got \"a\"\n");
    // R7: every field compare reads is type-checked in one place: a string counter (once skipped
    // as "not recorded"), an object where a number is expected, a number where a string is.
    auto confused = [&](const std::string& name, const nlohmann::json::json_pointer& field, const nlohmann::json& v) {
        const fs::path to = copy_of_base(name);
        nlohmann::json record = read_json_file((to / "runs" / "plane__pgs.json").string());
        record[field] = v;
        write_json_atomic((to / "runs" / "plane__pgs.json").string(), record);
        return run_reader("compare " + test::shell_quoted(base) + " " + test::shell_quoted(to));
    };
    o = confused("t1", nlohmann::json::json_pointer("/counters/iterations"), "12");
    EXPECT_EQ(o.status, 2) << o.out << o.err;
    EXPECT_EQ(o.err, "contactbench compare: error: " + (dir / "t1" / "runs" / "plane__pgs.json").string() +
                         ": /counters/iterations: expected a number, got \"12\"\n");
    o = confused("t2", nlohmann::json::json_pointer("/accuracy/max"), {{"v", 1}});
    EXPECT_EQ(o.status, 2) << o.out << o.err;
    EXPECT_EQ(o.err, "contactbench compare: error: " + (dir / "t2" / "runs" / "plane__pgs.json").string() +
                         ": /accuracy/max: expected a number or null, got {\"v\":1}\n");
    o = confused("t3", nlohmann::json::json_pointer("/snapshot/hash"), 7);
    EXPECT_EQ(o.status, 2) << o.out << o.err;
    EXPECT_EQ(o.err, "contactbench compare: error: " + (dir / "t3" / "runs" / "plane__pgs.json").string() +
                         ": /snapshot/hash: expected a string, got 7\n");
    o = confused("t4", nlohmann::json::json_pointer("/status"), 0);
    EXPECT_EQ(o.status, 2) << o.out << o.err;
    EXPECT_EQ(o.err, "contactbench compare: error: " + (dir / "t4" / "runs" / "plane__pgs.json").string() +
                         ": /status: expected a string, got 0\n");
    o = confused("t5", nlohmann::json::json_pointer("/counters/a_products"), nullptr);  // null: work_counted is true
    EXPECT_EQ(o.status, 2) << o.out << o.err;
    EXPECT_EQ(o.err, "contactbench compare: error: " + (dir / "t5" / "runs" / "plane__pgs.json").string() +
                         ": /counters/a_products: expected a number, got null\n");
    // The whole folders still compare.
    o = run_reader("compare " + test::shell_quoted(base) + " " + test::shell_quoted(copy_of_base("same")));
    EXPECT_EQ(o.status, 0) << o.out << o.err;
}
