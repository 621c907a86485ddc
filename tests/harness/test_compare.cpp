// The regression judge: on records built by hand, and end to end through the binary (an
// identical copy passes, a worse run fails with exit 1 and names the counter).
#include "harness/compare.hpp"
#include "harness/results.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sys/wait.h>
#include <unistd.h>

namespace fs = std::filesystem;
using namespace cb;

namespace {

nlohmann::json record(const std::string& snapshot, const std::string& label, long iterations, long a_products,
                      double kkt_rel, const std::string& status = "converged")
{
    return {{"label", label},
            {"solver", label},
            {"snapshot", {{"id", snapshot}}},
            {"status", status},
            {"iterations", iterations},
            {"tol", 1e-6},
            {"kkt_relative", {{"max", kkt_rel}}},
            {"counters", {{"a_products", a_products}, {"cholmod_factorizations", 0}, {"precond_applications", iterations}}},
            {"time", {{"total_s", 0.01}, {"repeat", 1}}}};
}

} // namespace

TEST(Compare, IdenticalRunsAreEqual)
{
    const std::vector<nlohmann::json> runs = {record("a", "mprgp", 10, 20, 5e-7), record("b", "mprgp", 12, 25, 8e-7)};
    const CompareReport r = compare_runs(runs, runs);
    EXPECT_FALSE(r.failed());
    EXPECT_EQ(r.equal, 2);
    EXPECT_EQ(r.verdict(), "verdict: PASS (2 runs compared: 2 equal, 0 improved, 0 regressed, 0 status changed, 0 missing in NEW; 0 new)");
}

TEST(Compare, CountersKktStatusAndMissing)
{
    const std::vector<nlohmann::json> base = {record("a", "mprgp", 10, 20, 5e-7), record("b", "mprgp", 12, 25, 8e-7),
                                              record("c", "mprgp", 12, 25, 8e-7), record("d", "mprgp", 12, 25, 8e-7),
                                              record("e", "mprgp", 12, 25, 8e-7)};
    const std::vector<nlohmann::json> next = {
        record("a", "mprgp", 10, 21, 5e-7),                  // one more A-product: regressed
        record("b", "mprgp", 11, 24, 8e-7),                  // fewer: improved
        record("c", "mprgp", 12, 25, 8e-7, "max_iterations"),  // status change
        record("e", "mprgp", 12, 25, 9.5e-7),                // kkt worse by 19% but below tol: fine
        record("f", "mprgp", 1, 1, 1e-7)};                   // new
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

    // KKT above tol and more than 10% worse: regressed; within --kkt-rtol: not.
    const std::vector<nlohmann::json> b2 = {record("a", "ica", 10, 20, 1e-5)};
    EXPECT_EQ(compare_runs(b2, {record("a", "ica", 10, 20, 1.2e-5)}).rows[0].regressed,
              std::vector<std::string>{"kkt_rel"});
    EXPECT_FALSE(compare_runs(b2, {record("a", "ica", 10, 20, 1.05e-5)}).failed());
    CompareOptions loose;
    loose.kkt_rtol = 0.5;
    EXPECT_FALSE(compare_runs(b2, {record("a", "ica", 10, 20, 1.2e-5)}, loose).failed());
}

TEST(Compare, BinaryExitCodesOnFolders)
{
    const char* b = std::getenv("CB_CONTACTBENCH");
    const std::string binary = b && *b ? b : std::string(CB_BINARY_DIR) + "/bin/contactbench";
    const fs::path dir = fs::temp_directory_path() / ("cb_test_compare_" + std::to_string(::getpid()));
    fs::remove_all(dir);
    const std::vector<nlohmann::json> runs = {record("a", "mprgp", 10, 20, 5e-7), record("b", "cg", 12, 25, 8e-7)};
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
    EXPECT_EQ(judge("'" + (dir / "base").string() + "' '" + (dir / "worse").string() + "' --json '" + json + "'", out), 1)
        << out;
    EXPECT_NE(out.find("25 -> 40 (+60%)"), std::string::npos) << out;
    EXPECT_NE(out.find("FAIL regressed: a_products"), std::string::npos) << out;
    EXPECT_NE(out.find("verdict: FAIL"), std::string::npos) << out;
    EXPECT_EQ(read_json_file(json)["regressed"], 1);
    EXPECT_EQ(judge("'" + (dir / "base").string() + "' '" + (dir / "nowhere").string() + "'", out), 2) << out;
    EXPECT_EQ(out, "contactbench compare: error: " + (dir / "nowhere").string() + ": no such results folder\n");
    fs::remove_all(dir);
}
