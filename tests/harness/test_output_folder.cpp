// Issue 40 (R1): nothing a command writes or deletes inside an output folder may be a link or a
// special file (problems/output_folder.hpp), through the contactbench binary (env CB_CONTACTBENCH).
#include "harness/results.hpp"
#include "problems/output_folder.hpp"
#include "problems/qpsnap.hpp"
#include "problems/synthetic.hpp"

#include "tests/harness/cli_test_util.hpp"
#include "tests/harness/remove_at_end.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sys/stat.h>

namespace fs = std::filesystem;
using namespace cb;
using cb::test::Output;
using cb::test::slurp;

namespace {

const fs::path& output_work_dir()
{
    static const fs::path dir = test::make_test_work_dir("output_folder");
    return dir;
}

fs::path fresh_output_dir(const std::string& name) { return test::fresh_subdir(output_work_dir(), name); }

/// `cd DIR && timeout 120 contactbench ARGS` in bash, output captured.
Output run_output_in(const fs::path& dir, const std::string& args)
{
    test::CliCall call;
    call.cd = dir;
    return test::run_contactbench(args, dir, call);
}

/// a.qpsnap and suite.json (one pgs run) in `dir`.
void write_output_suite(const fs::path& dir)
{
    write_qpsnap((dir / "a.qpsnap").string(), make_synthetic("plane", {{"nx", 2}, {"ny", 2}, {"nz", 2}}, 1));
    write_json_atomic((dir / "suite.json").string(),
                      {{"name", "r1"}, {"snapshots", {"a.qpsnap"}}, {"solvers", {"pgs"}}, {"time_limit_s", 20}});
}

std::vector<std::string> names_in(const fs::path& dir)
{
    std::vector<std::string> names;
    for (const auto& e : fs::directory_iterator(dir)) names.push_back(e.path().filename().string());
    std::sort(names.begin(), names.end());
    return names;
}

const std::string REFUSAL = "contactbench writes and deletes nothing through links or special files inside an "
                            "output folder; remove it or use another output folder\n";

const auto* const OUTPUT_CLEAN_UP = ::testing::AddGlobalTestEnvironment(new test::RemoveAtEnd(output_work_dir));

}  // namespace

// R1: a `runs` link planted in OUT: `run` and `run --fresh` refuse it; the link's target keeps
// its file and gets none.
TEST(OutputFolder, RunRefusesPlantedRunsLink)
{
    const fs::path d = fresh_output_dir("runs_link");
    write_output_suite(d);
    fs::create_directories(d / "victim");
    std::ofstream(d / "victim" / "precious.json") << "{}";
    fs::create_directories(d / "out1");
    fs::create_directory_symlink(d / "victim", d / "out1" / "runs");
    for (const char* fresh : {"", " --fresh"}) {
        const Output o = run_output_in(d, std::string("run suite.json --out out1") + fresh);
        EXPECT_EQ(o.status, 2) << fresh;
        EXPECT_EQ(o.err, "contactbench run: error: out1/runs: is a symbolic link: " + REFUSAL) << fresh;
        EXPECT_EQ(names_in(d / "victim"), std::vector<std::string>{"precious.json"}) << fresh;
    }
    EXPECT_EQ(names_in(d / "out1"), std::vector<std::string>{"runs"});  // nothing written beside it
}

// A planted summary.csv link and a FIFO among the run files are refused by name too.
TEST(OutputFolder, RunRefusesLinkedOrSpecialFiles)
{
    const fs::path d = fresh_output_dir("files");
    write_output_suite(d);
    std::ofstream(d / "victim.txt") << "precious\n";
    fs::create_directories(d / "out2" / "runs");
    fs::create_symlink(d / "victim.txt", d / "out2" / "summary.csv");
    const Output link = run_output_in(d, "run suite.json --out out2 --fresh");
    EXPECT_EQ(link.status, 2);
    EXPECT_EQ(link.err, "contactbench run: error: out2/summary.csv: is a symbolic link: " + REFUSAL);
    EXPECT_EQ(slurp(d / "victim.txt"), "precious\n");

    fs::create_directories(d / "out3" / "runs");
    ASSERT_EQ(::mkfifo((d / "out3" / "runs" / "a__pgs.json").c_str(), 0644), 0);
    const Output fifo = run_output_in(d, "run suite.json --out out3 --fresh");
    EXPECT_EQ(fifo.status, 2);
    EXPECT_EQ(fifo.err, "contactbench run: error: out3/runs/a__pgs.json: is a FIFO: " + REFUSAL);
}

// merge into an OUT whose runs/ is a link: refused before anything is copied.
TEST(OutputFolder, MergeRefusesPlantedRunsLink)
{
    const fs::path d = fresh_output_dir("merge");
    write_output_suite(d);
    ASSERT_EQ(run_output_in(d, "run suite.json --out shard").status, 0);
    fs::create_directories(d / "victim");
    fs::create_directories(d / "merged");
    fs::create_directory_symlink(d / "victim", d / "merged" / "runs");
    const Output o = run_output_in(d, "merge merged shard");
    EXPECT_EQ(o.status, 2);
    EXPECT_EQ(o.err, "contactbench merge: error: merged/runs: is a symbolic link: " + REFUSAL);
    EXPECT_TRUE(fs::is_empty(d / "victim"));
}

TEST(OutputFolder, SubfolderRules)
{
    const fs::path d = fresh_output_dir("unit");
    EXPECT_EQ(make_output_subfolder((d / "new").string(), "runs"), (d / "new" / "runs").string());
    EXPECT_TRUE(fs::is_directory(d / "new" / "runs"));
    std::ofstream(d / "new" / "file") << "x";
    try {
        make_output_subfolder((d / "new").string(), "file");
        ADD_FAILURE() << "a file accepted as a folder";
    } catch (const InputError& e) {
        EXPECT_EQ(std::string(e.what()),
                  (d / "new" / "file").string() + ": expected a folder; remove it or use another output folder");
    }
    EXPECT_NO_THROW(check_output_entry((d / "missing").string()));
}

// solve --save-solution: a planted x.mtx link is refused before the solve; its target is untouched.
TEST(OutputFolder, SaveSolutionRefusesPlantedLink)
{
    const fs::path d = fresh_output_dir("save_solution");
    write_output_suite(d);
    std::ofstream(d / "victim.txt") << "precious\n";
    fs::create_directories(d / "sol");
    fs::create_symlink(d / "victim.txt", d / "sol" / "x.mtx");
    const Output o = run_output_in(d, "solve a.qpsnap --solver pgs --save-solution sol");
    EXPECT_EQ(o.status, 2);
    EXPECT_EQ(o.err, "contactbench solve: error: sol/x.mtx: is a symbolic link: " + REFUSAL);
    EXPECT_EQ(o.out, "");  // refused before the solve
    EXPECT_EQ(slurp(d / "victim.txt"), "precious\n");
}

// stress --out: a planted runs link is refused before the first case runs.
TEST(OutputFolder, StressRefusesPlantedRunsLink)
{
    const fs::path d = fresh_output_dir("stress");
    fs::create_directories(d / "victim");
    fs::create_directories(d / "st");
    fs::create_directory_symlink(d / "victim", d / "st" / "runs");
    const Output o = run_output_in(d, "stress --quick --out st");
    EXPECT_EQ(o.status, 2);
    EXPECT_EQ(o.err, "contactbench stress: error: st/runs: is a symbolic link: " + REFUSAL);
    EXPECT_TRUE(fs::is_empty(d / "victim"));
}
