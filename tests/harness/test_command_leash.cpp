// Issue 40 through the contactbench binary (env CB_CONTACTBENCH): a scene runs a program only
// with both opt-ins (C1); SIGTERM to the harness ends the program and removes its work folder
// (C3), and a command solver without a time limit gets the default one; the program's stderr is
// stored and printed without escapes (C9); its peak memory is in the record's (C10).
#include "harness/command_solver.hpp"
#include "harness/results.hpp"
#include "problems/qpsnap.hpp"
#include "problems/synthetic.hpp"
#include "tests/harness/process_exists.hpp"
#include "tests/harness/shell_quoted.hpp"

#include "tests/harness/cli_test_util.hpp"
#include "tests/harness/remove_at_end.hpp"

#include <gtest/gtest.h>

#include <cerrno>
#include <csignal>
#include <fcntl.h>
#include <filesystem>
#include <fstream>
#include <sys/wait.h>
#include <thread>
#include <unistd.h>

namespace fs = std::filesystem;
using namespace cb;
using cb::test::Output;
using cb::test::slurp;

namespace {

const fs::path& leash_work_dir()
{
    static const fs::path dir = test::make_test_work_dir("command_leash");
    return dir;
}

fs::path fresh_leash_dir(const std::string& name) { return test::fresh_subdir(leash_work_dir(), name); }

/// `cd DIR && [ENV] timeout 120 contactbench ARGS` in bash, output captured.
Output run_leashed_in(const fs::path& dir, const std::string& args, const std::string& env = "")
{
    test::CliCall call;
    call.cd = dir;
    call.env = env;
    return test::run_contactbench(args, dir, call);
}

fs::path write_program(const fs::path& path, const std::string& body)
{
    std::ofstream(path) << "#!/bin/sh\n" << body;
    fs::permissions(path, fs::perms::owner_all);
    return path;
}

fs::path plane_snapshot(const fs::path& dir)
{
    const fs::path p = dir / "plane.qpsnap";
    write_qpsnap(p.string(), make_synthetic("plane", {{"nx", 2}, {"ny", 2}, {"nz", 2}}, 1));
    return p;
}

/// --set argv=... for `solve --solver command`, as one shell word.
std::string argv_setting(const std::vector<std::string>& argv) { return "'argv=" + nlohmann::json(argv).dump() + "'"; }

const auto* const LEASH_CLEAN_UP = ::testing::AddGlobalTestEnvironment(new test::RemoveAtEnd(leash_work_dir));

}  // namespace

// C1: a scene that names the command solver runs nothing unless the scene says
// "allow_commands": true and the command line gives --allow-commands.
TEST(SceneCommand, RunsOnlyWithBothOptIns)
{
    const fs::path d = fresh_leash_dir("scene");
    const fs::path marker = d / "PWNED";
    write_program(d / "marker.sh", "echo ran >> " + test::shell_quoted(marker) + "\nexit 1\n");
    auto scene = [&](bool allow) {
        nlohmann::json s = {
            {"name", "evil"},
            {"frames", 1},
            {"solver", "command"},
            {"solver_settings", {{"argv", {(d / "marker.sh").string(), "{settings}"}}, {"time_limit_s", 20}}},
            {"bodies", {{{"box", {{"cells", {2, 2, 2}}, {"size", {0.2, 0.2, 0.2}}}}, {"translate", {0, 0.09, 0}}}}},
            {"obstacles", {{{"type", "plane"}, {"normal", {0, 1, 0}}, {"point", {0, 0, 0}}}}}};
        if (allow) s["allow_commands"] = true;
        const fs::path p = d / (allow ? "allowed.json" : "evil.json");
        write_json_atomic(p.string(), s);
        return p;
    };
    const fs::path evil = scene(false), allowed = scene(true);
    const std::string rule = "'command' runs an external program; the scene must opt in with \"allow_commands\": "
                             "true (and the command line with --allow-commands)\n";
    for (const char* flag : {"", " --allow-commands"}) {
        const Output o = run_leashed_in(d, "simulate " + test::shell_quoted(evil) + " --frames 1 --out sim" + flag);
        EXPECT_EQ(o.status, 2) << flag;
        EXPECT_EQ(o.err, "contactbench simulate: error: " + evil.string() + ": /solver: " + rule) << flag;
        const Output c =
            run_leashed_in(d, "chains " + test::shell_quoted(evil) + " --frames 1 --out ch --orders authors" + flag);
        EXPECT_EQ(c.status, 2) << flag;
        EXPECT_EQ(c.err, "contactbench chains: error: " + evil.string() + ": /solver: " + rule) << flag;
    }
    const std::string no_flag = ": /solver: 'command' runs an external program: it runs only when the scene says "
                                "\"allow_commands\": true and the command line gives --allow-commands "
                                "(--allow-commands not given)\n";
    const Output sim = run_leashed_in(d, "simulate " + test::shell_quoted(allowed) + " --frames 1 --out sim");
    EXPECT_EQ(sim.status, 2);
    EXPECT_EQ(sim.err, "contactbench simulate: error: " + allowed.string() + no_flag);
    const Output chains =
        run_leashed_in(d, "chains " + test::shell_quoted(allowed) + " --frames 1 --out ch --orders authors");
    EXPECT_EQ(chains.status, 2);
    EXPECT_EQ(chains.err, "contactbench chains: error: " + allowed.string() + no_flag);
    EXPECT_FALSE(fs::exists(marker)) << "a program ran without both opt-ins";
    EXPECT_FALSE(fs::exists(d / "sim"));
    EXPECT_FALSE(fs::exists(d / "ch"));

    // Both given: the program runs (its failure is the step's, not the harness's).
    run_leashed_in(d,
                   "simulate " + test::shell_quoted(allowed) + " --frames 1 --no-snapshots --out sim --allow-commands");
    EXPECT_TRUE(fs::exists(marker));
}

// C3: SIGTERM to the harness while a program that ignores it runs: the program's group gets it,
// then SIGKILL; the work folder is removed; the harness ends by SIGTERM.
TEST(CommandLeash, SigtermEndsProgramAndRemovesWorkFolder)
{
    const fs::path d = fresh_leash_dir("sigterm"), tmp = fresh_leash_dir("sigterm/tmp");
    const fs::path snap = plane_snapshot(d), pid_file = d / "program.pid";
    const fs::path prog =
        write_program(d / "ignore_term.sh", "trap '' TERM INT HUP\necho $$ > " + test::shell_quoted(pid_file) +
                                                ".tmp\nmv " + test::shell_quoted(pid_file) + ".tmp " +
                                                test::shell_quoted(pid_file) + "\nwhile :; do sleep 1; done\n");
    const std::string argv = nlohmann::json(std::vector<std::string>{prog.string(), "{settings}"}).dump();
    const pid_t harness = ::fork();
    ASSERT_GE(harness, 0);
    if (harness == 0) {
        ::setenv("TMPDIR", tmp.c_str(), 1);
        const int out = ::open((d / "harness.err").c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
        ::dup2(out, 1);
        ::dup2(out, 2);
        const std::string set = "argv=" + argv;
        ::execl(test::contactbench_binary().c_str(), "contactbench", "solve", snap.c_str(), "--solver", "command",
                "--set", set.c_str(), static_cast<char*>(nullptr));
        _exit(126);
    }
    for (int i = 0; i < 1200 && !fs::exists(pid_file); ++i) std::this_thread::sleep_for(std::chrono::milliseconds(50));
    ASSERT_TRUE(fs::exists(pid_file)) << slurp(d / "harness.err");
    const pid_t program = std::stoi(slurp(pid_file));
    ASSERT_EQ(::kill(harness, SIGTERM), 0);
    int status = 0;
    ASSERT_EQ(::waitpid(harness, &status, 0), harness);
    EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGTERM) << "status " << status;
    EXPECT_FALSE(test::process_exists(program)) << "the program " << program << " outlived the harness";
    if (test::process_exists(program)) ::kill(program, SIGKILL);
    EXPECT_TRUE(fs::is_empty(tmp)) << "work folder left in " << tmp;
    EXPECT_NE(slurp(d / "harness.err")
                  .find("command: Terminated received: the program's process group was "
                        "signalled, its work folder removed: " +
                        tmp.string() + "/contactbench-command-"),
              std::string::npos)
        << slurp(d / "harness.err");
}

// C3: `solve` without --time-limit hands the program the command solver's default limit.
TEST(CommandLeash, DefaultTimeLimit)
{
    const fs::path d = fresh_leash_dir("default_limit");
    const fs::path snap = plane_snapshot(d), copy = d / "settings_seen.json";
    const Output o = run_leashed_in(
        d, "solve " + test::shell_quoted(snap) + " --solver command --json rec.json --set " +
               argv_setting({"/bin/sh", "-c", "cp \"$0\" " + test::shell_quoted(copy) + "; exit 1", "{settings}"}));
    EXPECT_EQ(o.status, 0) << o.err;
    EXPECT_EQ(read_json_file(copy.string())["time_limit_s"], DEFAULT_COMMAND_TIME_LIMIT_S);
    EXPECT_EQ(read_json_file((d / "rec.json").string())["info"]["command"]["time_limit_s"], 600.0);
}

// C9: a program's escape sequences reach neither the terminal nor the record.
TEST(CommandLeash, StderrEscapesStripped)
{
    const fs::path d = fresh_leash_dir("ansi");
    const fs::path snap = plane_snapshot(d);
    write_program(d / "ansi.sh",
                  "printf '\\033[2J\\033[31mFAKE: all runs converged\\033[0m\\a,\"q\"\\n' >&2\nexit 3\n");
    const Output o =
        run_leashed_in(d, "solve " + test::shell_quoted(snap) + " --solver command --json rec.json --set " +
                              argv_setting({(d / "ansi.sh").string(), "{settings}"}));
    EXPECT_EQ(o.out.find('\x1b'), std::string::npos) << o.out;
    EXPECT_EQ(o.err.find('\x1b'), std::string::npos) << o.err;
    const nlohmann::json rec = read_json_file((d / "rec.json").string());
    EXPECT_EQ(rec["message"],
              "command: the program exited with status 3; stderr: FAKE: all runs converged ,\"q\"; solver "
              "returned x of size 0, measured at x0");
}

// C10: a program that touches ~200 MiB shows in the record's peak.
TEST(CommandLeash, ProgramMemoryInTheRecord)
{
    const fs::path d = fresh_leash_dir("memory");
    const fs::path snap = plane_snapshot(d);
    const std::string script = "import json, os, sys\n"
                               "s = json.load(open(sys.argv[1]))\n"
                               "block = b'x' * (200 * 1024 * 1024)\n"
                               "open(os.path.join(s['out'], 'x.txt'), 'w').write('0\\n' * s['n'])\n";
    std::ofstream(d / "bigmem.py") << script;
    const Output o =
        run_leashed_in(d, "solve " + test::shell_quoted(snap) + " --solver command --json rec.json --set " +
                              argv_setting({"/usr/bin/python3", (d / "bigmem.py").string(), "{settings}"}));
    ASSERT_EQ(o.status, 0) << o.err;
    const nlohmann::json rec = read_json_file((d / "rec.json").string());
    EXPECT_EQ(rec["info"]["command"]["crashed"], false) << rec["message"];
    EXPECT_GE(rec["info"]["command"]["peak_rss_mb"].get<double>(), 200.0);
    EXPECT_GE(rec["memory"]["children_peak_rss_mb"].get<double>(), 200.0);
    EXPECT_GE(rec["memory"]["peak_rss_mb"].get<double>(), 200.0);
}

// C6: the program starts in its work folder, so its relative writes stay out of the user's
// folder; a relative argument naming an existing file (the program here) still finds it.
TEST(CommandLeash, RelativeWritesStayInTheWorkFolder)
{
    const fs::path d = fresh_leash_dir("relative");
    const fs::path snap = plane_snapshot(d);
    write_program(d / "relative.sh", "echo written > escaped_by_command.txt\npwd > \"$1/../cwd.txt\"\n"
                                     "cp \"$1/../cwd.txt\" " +
                                         test::shell_quoted(d / "cwd_seen.txt") + "\nexit 1\n");
    const Output o =
        run_leashed_in(d, "solve " + test::shell_quoted(snap) + " --solver command --json rec.json --set " +
                              argv_setting({"./relative.sh", "{out}", "{snapshot}"}));
    EXPECT_EQ(o.status, 0) << o.err;
    EXPECT_FALSE(fs::exists(d / "escaped_by_command.txt"));
    const std::string cwd = slurp(d / "cwd_seen.txt");
    EXPECT_NE(cwd.find("/contactbench-command-"), std::string::npos) << cwd;
    const nlohmann::json rec = read_json_file((d / "rec.json").string());
    EXPECT_EQ(rec["info"]["command"]["argv"][0], (d / "relative.sh").string());
}
