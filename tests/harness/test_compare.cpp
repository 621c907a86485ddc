// The regression judge: on records built by hand, on compact performance records (CSV), and end
// to end through the binary (an identical copy passes with exit 0, a worse run fails with exit 3
// and names the counter, bad input exits 2 naming the file).
#include "harness/compare.hpp"
#include "harness/perf_record.hpp"
#include "harness/results.hpp"
#include "solvers/core/types.hpp"

#include <gtest/gtest.h>

#include <sys/stat.h>

#include <cmath>

#include <functional>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <sys/wait.h>
#include <unistd.h>

namespace fs = std::filesystem;
using namespace cb;

namespace {

nlohmann::json compare_record(const std::string& snapshot, const std::string& label, long iterations, long a_products,
                              double accuracy, const std::string& status = "converged")
{
    return {
        {"label", label},
        {"solver", label},
        {"snapshot", {{"id", snapshot}}},
        {"status", status},
        {"iterations", iterations},
        {"tol", 1e-6},
        {"accuracy", {{"max", accuracy}}},
        {"counters", {{"a_products", a_products}, {"cholmod_factorizations", 0}, {"precond_applications", iterations}}},
        {"time", {{"total_s", 0.01}, {"repeat", 1}}}};
}

}  // namespace

TEST(Compare, IdenticalRunsAreEqual)
{
    const std::vector<nlohmann::json> runs = {compare_record("a", "mprgp", 10, 20, 5e-7),
                                              compare_record("b", "mprgp", 12, 25, 8e-7)};
    const CompareReport r = compare_runs(runs, runs);
    EXPECT_FALSE(r.failed());
    EXPECT_EQ(r.equal, 2);
    EXPECT_EQ(
        r.verdict(),
        "verdict: PASS (2 runs compared: 2 equal, 0 improved, 0 regressed, 0 status changed, 0 missing in NEW; 0 new)");
}

TEST(Compare, CountersKktStatusAndMissing)
{
    const std::vector<nlohmann::json> base = {
        compare_record("a", "mprgp", 10, 20, 5e-7), compare_record("b", "mprgp", 12, 25, 8e-7),
        compare_record("c", "mprgp", 12, 25, 8e-7), compare_record("d", "mprgp", 12, 25, 8e-7),
        compare_record("e", "mprgp", 12, 25, 8e-7)};
    const std::vector<nlohmann::json> next = {
        compare_record("a", "mprgp", 10, 21, 5e-7),                    // one more A-product: regressed
        compare_record("b", "mprgp", 11, 24, 8e-7),                    // fewer: improved
        compare_record("c", "mprgp", 12, 25, 8e-7, "max_iterations"),  // status change
        compare_record("e", "mprgp", 12, 25, 9.5e-7),                  // accuracy worse by 19% but below tol: fine
        compare_record("f", "mprgp", 1, 1, 1e-7)};                     // new
    const CompareReport r = compare_runs(base, next);
    EXPECT_TRUE(r.failed());
    EXPECT_EQ(r.regressed, 1);
    EXPECT_EQ(r.improved, 1);
    EXPECT_EQ(r.status_changed, 1);
    EXPECT_EQ(r.missing, 1);
    EXPECT_EQ(r.equal, 1);
    EXPECT_EQ(r.added, 1);
    ASSERT_EQ(r.rows[0].regressed, std::vector<std::string>{"a_products"});
    const std::string table = r.table();
    EXPECT_NE(table.find("20 -> 21 (+5%)"), std::string::npos) << table;
    EXPECT_NE(table.find("FAIL regressed: a_products"), std::string::npos) << table;
    EXPECT_NE(table.find("FAIL status changed"), std::string::npos) << table;
    EXPECT_NE(table.find("FAIL missing in NEW"), std::string::npos) << table;

    // accuracy above tol and more than 10% worse: regressed; within --accuracy-rtol: not.
    const std::vector<nlohmann::json> b2 = {compare_record("a", "ica", 10, 20, 1e-5)};
    EXPECT_EQ(compare_runs(b2, {compare_record("a", "ica", 10, 20, 1.2e-5)}).rows[0].regressed,
              std::vector<std::string>{"accuracy"});
    EXPECT_FALSE(compare_runs(b2, {compare_record("a", "ica", 10, 20, 1.05e-5)}).failed());
    CompareOptions loose;
    loose.accuracy_rtol = 0.5;
    EXPECT_FALSE(compare_runs(b2, {compare_record("a", "ica", 10, 20, 1.2e-5)}, loose).failed());
}

TEST(Compare, WorkUnitsAreACounter)
{
    // Same A-products, one more factorisation's worth of work (pgs, active-set, ichol): regressed
    // on "work" alone; less work: improved; a BASE without the counter: shown, not judged.
    std::vector<nlohmann::json> base = {compare_record("a", "pgs", 10, 1, 5e-7),
                                        compare_record("b", "pgs", 10, 1, 5e-7)};
    base[0]["counters"]["work"] = 224.5;
    base[1]["counters"]["work"] = 224.5;
    std::vector<nlohmann::json> next = base;
    next[0]["counters"]["work"] = 230.25;
    next[1]["counters"]["work"] = 200.0;
    const CompareReport r = compare_runs(base, next);
    ASSERT_EQ(r.rows.size(), 2u);
    EXPECT_EQ(r.rows[0].regressed, std::vector<std::string>{"work"});
    EXPECT_EQ(r.rows[1].improved, std::vector<std::string>{"work"});
    for (auto& run : base) run["counters"].erase("work");
    EXPECT_FALSE(compare_runs(base, next).failed());
}

TEST(Compare, BinaryExitCodesOnFolders)
{
    const char* b = std::getenv("CB_CONTACTBENCH");
    const std::string binary = b && *b ? b : std::string(CB_BINARY_DIR) + "/bin/contactbench";
    const fs::path dir = fs::temp_directory_path() / ("cb_test_compare_" + std::to_string(::getpid()));
    fs::remove_all(dir);
    const std::vector<nlohmann::json> runs = {compare_record("a", "mprgp", 10, 20, 5e-7),
                                              compare_record("b", "cg", 12, 25, 8e-7)};
    for (const auto& folder : {"base", "same", "worse"})
        for (const auto& r : runs)
            write_json_atomic((dir / folder / "runs" / run_file_name(r["snapshot"]["id"], r["label"])).string(), r);
    nlohmann::json worse = runs[1];
    worse["counters"]["a_products"] = 40;
    write_json_atomic((dir / "worse" / "runs" / "b__cg.json").string(), worse);
    auto judge = [&](const std::string& args, std::string& out) {
        const std::string file = (dir / "out.txt").string();
        const int raw = std::system(("'" + binary + "' compare " + args + " >'" + file + "' 2>&1").c_str());
        std::ifstream in(file);
        out.assign(std::istreambuf_iterator<char>(in), {});
        return WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
    };
    std::string out;
    EXPECT_EQ(judge("'" + (dir / "base").string() + "' '" + (dir / "same").string() + "'", out), 0) << out;
    EXPECT_NE(out.find("verdict: PASS"), std::string::npos) << out;
    const std::string json = (dir / "judge.json").string();
    EXPECT_EQ(judge("'" + (dir / "base").string() + "' '" + (dir / "worse").string() + "' --json '" + json + "'", out),
              3)
        << out;
    EXPECT_NE(out.find("25 -> 40 (+60%)"), std::string::npos) << out;
    EXPECT_NE(out.find("FAIL regressed: a_products"), std::string::npos) << out;
    EXPECT_NE(out.find("verdict: FAIL"), std::string::npos) << out;
    EXPECT_EQ(read_json_file(json)["regressed"], 1);
    EXPECT_EQ(judge("'" + (dir / "base").string() + "' '" + (dir / "nowhere").string() + "'", out), 2) << out;
    EXPECT_EQ(out, "contactbench compare: error: " + (dir / "nowhere").string() +
                       ": no such results folder or performance record (.csv)\n");
    fs::remove_all(dir);
}

namespace {

/// A compact record row (harness/perf_record.hpp): snapshot,label,status,iterations,a_products,
/// a_products_harness,accuracy,tol,instructions,time_min_s,time_noise,time_samples.
struct PerfRow {
    std::string snapshot, label, status = "converged";
    long iterations = 10, a_products = 20, a_products_harness = 18;
    double accuracy = 5e-7;
    long instructions = 1000000;
    double time_min_s = 0.01, time_noise = 0.05;
    long time_samples = 5;
};

const char* const PERF_HEADER =
    "snapshot,label,status,iterations,a_products,a_products_harness,accuracy,tol,instructions,time_min_s,time_noise,"
    "time_samples\n";

std::string perf_line(const PerfRow& r)
{
    std::ostringstream out;
    out << r.snapshot << "," << r.label << "," << r.status << "," << r.iterations << "," << r.a_products << ","
        << r.a_products_harness << "," << r.accuracy << ",1e-06," << r.instructions << "," << r.time_min_s << ","
        << r.time_noise << "," << r.time_samples << "\n";
    return out.str();
}

fs::path perf_dir()
{
    fs::path dir = fs::temp_directory_path() / ("cb_test_compare_csv_" + std::to_string(::getpid()));
    fs::create_directories(dir);
    return dir;
}

/// Writes NAME.csv (and NAME-machine.json when cpu is given) and returns the CSV path.
std::string write_perf(const std::string& name, const std::vector<PerfRow>& rows, const std::string& cpu = "")
{
    const fs::path csv = perf_dir() / (name + ".csv");
    std::string text = PERF_HEADER;
    for (const auto& r : rows) text += perf_line(r);
    write_file_atomic(csv.string(), text);
    if (!cpu.empty())
        write_json_atomic((perf_dir() / (name + "-machine.json")).string(),
                          {{"cpu", cpu},
                           {"blas", "/usr/lib/x86_64-linux-gnu/openblas-pthread/libblas.so.3"},
                           {"suitesparse", "5.12.0 (CHOLMOD 3.0.14)"},
                           {"compiler", "gcc 12.2.0"}});
    return csv.string();
}

PerfRow row(const std::string& snapshot, const std::string& label)
{
    PerfRow r;
    r.snapshot = snapshot;
    r.label = label;
    return r;
}

std::vector<std::string> regressed_of(const CompareReport& report, const std::string& snapshot)
{
    for (const auto& r : report.rows)
        if (r.snapshot == snapshot) return r.regressed;
    ADD_FAILURE() << "no row " << snapshot;
    return {};
}

}  // namespace

TEST(ComparePerfRecord, InstructionsAndHarnessCountedProductsOnOneMachine)
{
    const std::vector<PerfRow> base = {row("a", "mprgp"), row("b", "mprgp"), row("c", "mprgp"), row("d", "mprgp")};
    std::vector<PerfRow> next = base;
    next[0].instructions = 1020000;   // +2%: under the 3% threshold
    next[1].instructions = 1040000;   // +4%: regressed
    next[2].a_products_harness = 19;  // one product the solver did not count
    next[3].a_products = 21;          // counted by both
    next[3].a_products_harness = 19;
    const CompareInput b = read_compare_input(write_perf("base", base, "AMD EPYC"));
    const CompareInput n = read_compare_input(write_perf("next", next, "AMD EPYC"));
    EXPECT_EQ(b.machine["cpu"], "AMD EPYC");
    const CompareReport report = compare_inputs(b, n);
    EXPECT_FALSE(report.cross_machine);
    EXPECT_EQ(report.equal, 1);
    EXPECT_EQ(report.regressed, 3);
    EXPECT_TRUE(regressed_of(report, "a").empty());
    EXPECT_EQ(regressed_of(report, "b"), std::vector<std::string>{"instructions"});
    EXPECT_EQ(regressed_of(report, "c"), std::vector<std::string>{"a_products_harness"});
    EXPECT_EQ(regressed_of(report, "d"), (std::vector<std::string>{"a_products", "a_products_harness"}));
    const std::string table = report.table();
    EXPECT_NE(table.find("1.000M +2.000%"), std::string::npos) << table;
    EXPECT_NE(table.find("FAIL regressed: a_products_harness (uncounted by the solver)"), std::string::npos) << table;
    EXPECT_NE(table.find("FAIL regressed: a_products a_products_harness\n"), std::string::npos) << table;
    const std::string header = report.header();
    EXPECT_NE(header.find("measured on AMD EPYC, openblas-pthread, SuiteSparse 5.12.0 (CHOLMOD 3.0.14), gcc 12.2.0"),
              std::string::npos)
        << header;
    EXPECT_NE(header.find("NEW   " + n.source + "  measured on the same machine"), std::string::npos) << header;
    EXPECT_NE(header.find("instructions in the solve within +3%"), std::string::npos) << header;

    // An older BASE without the harness count: a results folder of an older binary is shown, not
    // judged; a compact record (a baseline) is refused, since NEW's count would go unjudged (issue 27).
    std::vector<nlohmann::json> old_runs = b.runs;
    for (auto& r : old_runs) r["counters"].erase("a_products_harness");
    CompareInput old = b;
    old.runs = old_runs;
    old.compact = false;
    EXPECT_TRUE(regressed_of(compare_inputs(old, n), "c").empty());
    old.compact = true;
    try {
        compare_inputs(old, n);
        ADD_FAILURE() << "a compact BASE without a judged counter was accepted";
    } catch (const InputError& e) {
        EXPECT_EQ(std::string(e.what()), b.source + ": a/mprgp: a_products_harness: not recorded in BASE but recorded "
                                                    "in NEW, so it would not be judged (a baseline must record every "
                                                    "judged quantity: regenerate it)");
    }
}

TEST(ComparePerfRecord, WallTimeIsJudgedOnlyBeyondTheRatioTimesTheNoiseBand)
{
    const std::vector<PerfRow> base = {row("a", "cg"), row("b", "cg"), row("c", "cg"), row("d", "cg")};
    std::vector<PerfRow> next = base;
    next[0].time_min_s = 0.018;  // 1.8x, band 0.10: beyond 1.5 x 1.10, regressed
    next[1].time_min_s = 0.018;  // 1.8x but noisy (band 0.05 + 0.60): within 1.5 x 1.65, not judged a regression
    next[1].time_noise = 0.6;
    next[2].time_min_s = 0.016;  // 1.6x, band 0.10: within 1.5 x 1.10 = 1.65x
    next[3].time_min_s = 0.03;   // 3x from a single sample: never judged
    next[3].time_samples = 1;
    const CompareReport report =
        compare_inputs(read_compare_input(write_perf("tb", base)), read_compare_input(write_perf("tn", next)));
    EXPECT_EQ(regressed_of(report, "a"), std::vector<std::string>{"time"});
    EXPECT_TRUE(regressed_of(report, "b").empty());
    EXPECT_TRUE(regressed_of(report, "c").empty());
    EXPECT_TRUE(regressed_of(report, "d").empty());
    EXPECT_NEAR(report.rows[0].time_ratio, 1.8, 1e-12);
    EXPECT_NEAR(report.rows[0].time_band, 0.1, 1e-12);
    EXPECT_NE(report.table().find("1.80x ±0.10"), std::string::npos) << report.table();
    CompareOptions never;
    never.time_ratio_max = 0.0;
    EXPECT_FALSE(
        compare_inputs(read_compare_input(write_perf("tb", base)), read_compare_input(write_perf("tn", next)), never)
            .failed());
}

TEST(ComparePerfRecord, AcrossMachinesCountersGetTolerancesAndInstructionsAreNotJudged)
{
    const std::vector<PerfRow> base = {row("a", "active-set"), row("b", "active-set"), row("c", "active-set")};
    std::vector<PerfRow> next = base;
    next[0].a_products = 21;  // one more product (rounding on another CPU): within 25% + 2
    next[0].a_products_harness = 19;
    next[0].instructions = 1500000;  // another CPU's BLAS kernels: not judged
    next[1].iterations = 16;         // 10 -> 16: beyond 10 * 1.25 + 2 = 14.5
    next[2].status = "max_iterations";
    const CompareReport report = compare_inputs(read_compare_input(write_perf("xb", base, "AMD EPYC")),
                                                read_compare_input(write_perf("xn", next, "Intel Xeon")));
    EXPECT_TRUE(report.cross_machine);
    EXPECT_TRUE(regressed_of(report, "a").empty());
    EXPECT_EQ(regressed_of(report, "b"), std::vector<std::string>{"iterations"});
    EXPECT_EQ(report.status_changed, 1);
    const std::string header = report.header();
    EXPECT_NE(header.find("machines DIFFER"), std::string::npos) << header;
    EXPECT_NE(header.find("measured on AMD EPYC"), std::string::npos) << header;
    EXPECT_NE(header.find("measured on Intel Xeon"), std::string::npos) << header;
    EXPECT_NE(header.find("work counters within +25% + 2"), std::string::npos) << header;

    // Asked for on one machine (the gate's fallback against the committed record): said so.
    CompareOptions across;
    across.cross_machine = true;
    const CompareReport asked = compare_inputs(read_compare_input(write_perf("xb", base, "AMD EPYC")),
                                               read_compare_input(write_perf("xs", base, "AMD EPYC")), across);
    EXPECT_TRUE(asked.cross_machine);
    EXPECT_NE(asked.header().find("\nacross-machines rules (asked for"), std::string::npos) << asked.header();
}

TEST(ComparePerfRecord, MalformedRecordsNameTheFileLineAndColumn)
{
    const fs::path dir = perf_dir();
    auto error_of = [&](const std::string& name, const std::string& text) -> std::string {
        const std::string path = (dir / name).string();
        write_file_atomic(path, text);
        try {
            read_perf_record(path);
        } catch (const InputError& e) {
            return e.what();
        }
        return "no error";
    };
    const std::string p1 = (dir / "unknown.csv").string();
    EXPECT_EQ(error_of("unknown.csv", "snapshot,label,status,speed\na,cg,converged,1\n"),
              p1 + ": line 1: unknown column 'speed'");
    const std::string p2 = (dir / "count.csv").string();
    EXPECT_EQ(error_of("count.csv", "snapshot,label,status,a_products\na,cg,converged,1\nb,cg,converged,x\n"),
              p2 + ": line 3: column a_products: expected a count (integer >= 0), got 'x'");
    const std::string p3 = (dir / "cells.csv").string();
    EXPECT_EQ(error_of("cells.csv", "snapshot,label,status\na,cg\n"), p3 + ": line 2: expected 3 cells, got 2");
    const std::string p4 = (dir / "twice.csv").string();
    EXPECT_EQ(error_of("twice.csv", "snapshot,label,status\na,cg,converged\na,cg,converged\n"),
              p4 + ": line 3: run a/cg appears twice");
    const std::string p5 = (dir / "nostatus.csv").string();
    EXPECT_EQ(error_of("nostatus.csv", "snapshot,label\na,cg\n"), p5 + ": line 1: missing column 'status'");
}

// Issue 27: compare passed NaN counters and a BASE lacking a judged column; a 1e6-row CSV took 3.7 GB.
TEST(ComparePerfRecord, NanCountersMissingJudgedColumnsAndHugeRecordsAreRefused)
{
    const fs::path dir = perf_dir();
    auto error_of = [&](const std::function<void()>& f) -> std::string {
        try {
            f();
        } catch (const InputError& e) {
            return e.what();
        }
        return "no error";
    };
    auto compare_record = [&](const std::string& name, const std::string& text) {
        std::string path = (dir / name).string();
        write_file_atomic(path, text);
        return path;
    };
    const std::string nan_csv =
        compare_record("nan.csv", "snapshot,label,status,work,accuracy\na,cg,converged,nan,1e-9\n");
    EXPECT_EQ(error_of([&] { read_perf_record(nan_csv); }),
              nan_csv + ": line 2: column work: expected a finite number, got 'nan'");
    const std::string inf_csv = compare_record("inf.csv", "snapshot,label,status,accuracy\na,cg,converged,-inf\n");
    EXPECT_EQ(error_of([&] { read_perf_record(inf_csv); }),
              inf_csv + ": line 2: column accuracy: expected a finite number, got '-inf'");
    // NaN through the API (a record built in memory): NaN > x and NaN < x are both false.
    nlohmann::json run = {
        {"snapshot", {{"id", "a"}}}, {"label", "cg"}, {"status", "converged"}, {"counters", {{"work", 10.0}}}};
    nlohmann::json bad = run;
    bad["counters"]["work"] = std::nan("");
    CompareInput base, next;
    base.source = "BASE";
    next.source = "NEW";
    base.runs = {run};
    next.runs = {bad};
    EXPECT_EQ(error_of([&] { compare_inputs(base, next); }),
              "NEW: a/cg: work: not a finite number (NaN or infinite): it cannot be judged");
    // A baseline (CSV) whose column or cell is empty where NEW records the quantity.
    const std::string no_column =
        compare_record("no_column.csv", "snapshot,label,status,iterations\na,cg,converged,5\n");
    const std::string with_column =
        compare_record("with_column.csv", "snapshot,label,status,iterations,a_products\na,cg,converged,5,7\n");
    EXPECT_EQ(error_of([&] { compare_inputs(read_compare_input(no_column), read_compare_input(with_column)); }),
              no_column + ": a/cg: a_products: not recorded in BASE but recorded in NEW, so it would not be judged "
                          "(a baseline must record every judged quantity: regenerate it)");
    const std::string empty_cell =
        compare_record("empty_cell.csv", "snapshot,label,status,iterations,accuracy\na,cg,converged,5,\n");
    const std::string accuracy =
        compare_record("accuracy.csv", "snapshot,label,status,iterations,accuracy\na,cg,converged,5,1e-3\n");
    EXPECT_EQ(error_of([&] { compare_inputs(read_compare_input(empty_cell), read_compare_input(accuracy)); }),
              empty_cell + ": a/cg: accuracy: not recorded in BASE but recorded in NEW, so it would not be judged "
                           "(a baseline must record every judged quantity: regenerate it)");
    // Bounded memory: at most 100000 runs and 4096 characters a line; a FIFO is not waited on.
    std::string huge = "snapshot,label,status\n";
    for (int i = 0; i <= 100000; ++i) huge += "s" + std::to_string(i) + ",cg,converged\n";
    const std::string huge_csv = compare_record("huge.csv", huge);
    EXPECT_EQ(error_of([&] { read_perf_record(huge_csv); }),
              huge_csv +
                  ": line 100002: more than 100000 runs: not a performance record of a suite (memory is bounded)");
    const std::string long_csv =
        compare_record("long.csv", "snapshot,label,status\n" + std::string(5000, 'a') + ",cg,x\n");
    EXPECT_EQ(error_of([&] { read_perf_record(long_csv); }), long_csv + ": line 2: longer than 4096 characters");
    const fs::path fifo = dir / "fifo.csv";
    ASSERT_EQ(::mkfifo(fifo.c_str(), 0644), 0);
    EXPECT_EQ(error_of([&] { read_perf_record(fifo.string()); }), fifo.string() + ": not a regular file (a FIFO)");
}

TEST(ComparePerfRecord, BinaryOnlyChangesFilterAndExitCodes)
{
    const char* b = std::getenv("CB_CONTACTBENCH");
    const std::string binary = b && *b ? b : std::string(CB_BINARY_DIR) + "/bin/contactbench";
    const std::vector<PerfRow> base = {row("a", "mprgp"), row("a", "cg"), row("b", "mprgp")};
    std::vector<PerfRow> next = base;
    next[1].instructions = 1100000;  // a/cg: +10%
    const std::string base_csv = write_perf("bb", base, "AMD EPYC"), next_csv = write_perf("bn", next, "AMD EPYC");
    const std::string out_file = (perf_dir() / "out.txt").string();
    auto judge = [&](const std::string& args, std::string& out) {
        const int raw = std::system(("'" + binary + "' compare " + args + " >'" + out_file + "' 2>&1").c_str());
        std::ifstream in(out_file);
        out.assign(std::istreambuf_iterator<char>(in), {});
        return WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
    };
    std::string out;
    EXPECT_EQ(judge("'" + base_csv + "' '" + next_csv + "' --only-changes", out), 3) << out;
    EXPECT_NE(out.find("a         cg     converged"), std::string::npos) << out;
    EXPECT_EQ(out.find("mprgp"), std::string::npos) << out;  // unchanged rows left out
    EXPECT_NE(out.find("FAIL regressed: instructions"), std::string::npos) << out;
    EXPECT_EQ(judge("'" + base_csv + "' '" + next_csv + "' --filter '/mprgp$'", out), 0) << out;
    EXPECT_NE(out.find("verdict: PASS (2 runs compared: 2 equal"), std::string::npos) << out;
    EXPECT_EQ(judge("'" + base_csv + "' '" + next_csv + "' --instructions-rtol 0.2", out), 0) << out;
    EXPECT_EQ(judge("'" + base_csv + "' '" + next_csv + "' --filter '('", out), 2) << out;
    EXPECT_NE(out.find("contactbench compare: error: compare: --filter: not a regular expression: '('"),
              std::string::npos)
        << out;
    fs::remove_all(perf_dir());
}
