// Issue 40: the external program's leash (harness/program_run.hpp) and the text and argument
// rules of the command solver, tested on run_program directly with small shell programs.
#include "harness/command_solver.hpp"
#include "harness/printable_text.hpp"
#include "harness/program_run.hpp"
#include "tests/harness/process_exists.hpp"

#include "tests/harness/cli_test_util.hpp"
#include "tests/harness/remove_at_end.hpp"

#include <gtest/gtest.h>

#include <cerrno>
#include <csignal>
#include <filesystem>
#include <fstream>

namespace fs = std::filesystem;
using namespace cb;

namespace {

const fs::path& program_work_dir()
{
    static const fs::path dir = test::make_test_work_dir("program_run");
    return dir;
}

fs::path fresh_program_dir(const std::string& name) { return test::fresh_subdir(program_work_dir(), name); }

ProgramOutcome run_sh(const fs::path& dir, const std::string& script, ProgramOptions options = {})
{
    if (options.time_limit_s <= 0) options.time_limit_s = 60;
    return run_program({"/bin/sh", "-c", script}, (dir / "stdout.txt").string(), (dir / "stderr.txt").string(),
                       options);
}

const auto* const PROGRAM_CLEAN_UP = ::testing::AddGlobalTestEnvironment(new test::RemoveAtEnd(program_work_dir));

}  // namespace

// C8: a program's own exit status 127 is its own; a program that cannot be started says why.
TEST(ProgramRun, OwnExit127IsNotAnExecFailure)
{
    const fs::path d = fresh_program_dir("exit127");
    const ProgramOutcome own = run_sh(d, "echo 'my own failure' >&2; exit 127");
    EXPECT_FALSE(own.exec_failed);
    EXPECT_EQ(own.exit_status, 127);
    EXPECT_EQ(own.failure(), "exited with status 127");
    EXPECT_EQ(test::slurp(d / "stderr.txt"), "my own failure\n");

    const ProgramOutcome missing = run_program({(d / "no-such-program").string()}, (d / "o.txt").string(),
                                               (d / "e.txt").string(), ProgramOptions{});
    EXPECT_TRUE(missing.exec_failed);
    EXPECT_EQ(missing.failure(),
              "could not be started (exec " + (d / "no-such-program").string() + ": No such file or directory)");
}

// C6: the program starts in the folder it is given, so its relative writes land there.
TEST(ProgramRun, StartsInItsWorkFolder)
{
    const fs::path d = fresh_program_dir("cwd"), work = fresh_program_dir("cwd/work");
    ProgramOptions options;
    options.workdir = work.string();
    const ProgramOutcome run = run_sh(d, "pwd -P > here.txt", options);
    EXPECT_EQ(run.failure(), "");
    EXPECT_EQ(test::slurp(work / "here.txt"), fs::canonical(work).string() + "\n");
    EXPECT_FALSE(fs::exists(fs::current_path() / "here.txt"));
}

// C2: a child that left the program's group (setsid) and one that stayed are both gone when
// run_program returns; the setsid one is counted as an orphan.
TEST(ProgramRun, OrphansThatLeftTheGroupAreKilled)
{
    const fs::path d = fresh_program_dir("orphans");
    const ProgramOutcome run = run_sh(d,
                                      "setsid sleep 313 </dev/null >/dev/null 2>&1 & echo $! > setsid.pid; "
                                      "sleep 317 </dev/null >/dev/null 2>&1 & echo $! > group.pid; exit 0",
                                      ProgramOptions{60, d.string(), PROGRAM_OUTPUT_CAP_BYTES, 2.0});
    EXPECT_EQ(run.failure(), "");
    const pid_t setsid_pid = std::stoi(test::slurp(d / "setsid.pid"));
    const pid_t group_pid = std::stoi(test::slurp(d / "group.pid"));
    EXPECT_FALSE(test::process_exists(setsid_pid)) << "setsid child " << setsid_pid << " survived";
    EXPECT_FALSE(test::process_exists(group_pid)) << "group child " << group_pid << " survived";
    EXPECT_GE(run.orphans_killed, 1);
}

// C11: stdout beyond the cap is counted, not stored; the last bytes are kept after a note.
TEST(ProgramRun, OutputIsCapped)
{
    const fs::path d = fresh_program_dir("cap");
    const ProgramOutcome run = run_sh(d, "head -c 5000000 /dev/zero; printf END");
    EXPECT_EQ(run.failure(), "");
    EXPECT_EQ(run.stdout_bytes, 5000003u);
    EXPECT_TRUE(run.stdout_capped);
    EXPECT_FALSE(run.stderr_capped);
    const std::string kept = test::slurp(d / "stdout.txt");
    const std::string note = "\n[contactbench: the program wrote 5000003 bytes here; only the first 1048576 "
                             "(above) and the last 4096 (below) are kept]\n";
    ASSERT_EQ(kept.size(), PROGRAM_OUTPUT_CAP_BYTES + note.size() + PROGRAM_OUTPUT_TAIL_BYTES);
    EXPECT_EQ(kept.substr(PROGRAM_OUTPUT_CAP_BYTES, note.size()), note);
    EXPECT_EQ(kept.substr(kept.size() - 3), "END");
}

// C10: the program's peak resident memory comes back from wait4 (here about 200 MiB touched).
TEST(ProgramRun, PeakMemoryOfTheProgram)
{
    const fs::path d = fresh_program_dir("peak");
    const ProgramOutcome run =
        run_program({"/usr/bin/python3", "-c", "b = b'x' * (200 * 1024 * 1024); print(len(b))"}, (d / "o.txt").string(),
                    (d / "e.txt").string(), ProgramOptions{60, "", PROGRAM_OUTPUT_CAP_BYTES, 2.0});
    ASSERT_EQ(run.failure(), "") << test::slurp(d / "e.txt");
    EXPECT_GE(run.peak_rss_bytes, 200L * 1024 * 1024);
    EXPECT_GT(run.start_rss_bytes, 0);  // the floor: this test process's resident memory
    EXPECT_LT(run.start_rss_bytes, run.peak_rss_bytes);
}

// The time limit kills a program that ignores SIGTERM.
TEST(ProgramRun, TimeLimitKillsTheGroup)
{
    const fs::path d = fresh_program_dir("limit");
    ProgramOptions options;
    options.time_limit_s = 0.5;
    const ProgramOutcome run = run_sh(d, "trap '' TERM INT; while :; do sleep 1; done", options);
    EXPECT_TRUE(run.timed_out);
    EXPECT_EQ(run.failure(), "was killed at the time limit");
}

// C7: a substituted value is never scanned again for placeholders.
TEST(CommandPlaceholders, ExpandedOnce)
{
    const std::vector<std::pair<std::string, std::string>> values = {{"{snapshot}", "/t/ph{out}x/problem.qpsnap"},
                                                                     {"{settings}", "/t/ph{settings}y/settings.json"},
                                                                     {"{out}", "/t/ph{out}x/out"}};
    EXPECT_EQ(expand_placeholders("{settings}", values), "/t/ph{settings}y/settings.json");
    EXPECT_EQ(expand_placeholders("{snapshot}", values), "/t/ph{out}x/problem.qpsnap");
    EXPECT_EQ(expand_placeholders("--o={out}/x,{unknown},{", values), "--o=/t/ph{out}x/out/x,{unknown},{");
}

// C9: escapes and control characters from a program never reach a terminal or a record.
TEST(PrintableText, EscapesStrippedControlsReplaced)
{
    EXPECT_EQ(printable_text("\x1b[2J\x1b[31mFAKE: all runs converged\x1b[0m\a,\"q\"\n"),
              "FAKE: all runs converged ,\"q\"\n");
    EXPECT_EQ(printable_text("a\x1b]0;title\x07"
                             "b\x1b]2;t\x1b\\c\rd\te"),
              "abc d\te");
    EXPECT_EQ(printable_text("caf\xc3\xa9 \xc2\x9b"
                             "1m \xff\xfe"),
              "caf\xc3\xa9 ?1m ??");  // C1 CSI, bad UTF-8
    EXPECT_EQ(printable_text("tail\x1b["), "tail");
}
