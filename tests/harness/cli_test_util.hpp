#pragma once
/// Helpers shared by the tests that drive the contactbench binary (env CB_CONTACTBENCH): where
/// the binary is, a scratch folder per test process, running a shell command with its output
/// captured, and running the binary itself under a time limit.
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <sys/wait.h>
#include <unistd.h>

namespace cb::test {

inline std::string contactbench_binary()
{
    if (const char* b = std::getenv("CB_CONTACTBENCH"); b && *b) return b;
    return std::string(CB_BINARY_DIR) + "/bin/contactbench";
}

/// A fresh folder `<tmp>/cb_test_<name>_<pid>`; CB_CACHE points inside it (generated snapshots
/// and references stay there) and BLAS runs on one thread, as the Makefile runs it.
inline std::filesystem::path make_test_work_dir(const std::string& name)
{
    std::filesystem::path d =
        std::filesystem::temp_directory_path() / ("cb_test_" + name + "_" + std::to_string(::getpid()));
    std::filesystem::remove_all(d);
    std::filesystem::create_directories(d);
    ::setenv("CB_CACHE", (d / "cache").c_str(), 1);
    ::setenv("OPENBLAS_NUM_THREADS", "1", 1);
    return d;
}

inline std::string slurp(const std::filesystem::path& p)
{
    std::ifstream in(p);
    return std::string(std::istreambuf_iterator<char>(in), {});
}

struct Output {
    int status = -1;  ///< exit status, -1 when the command did not exit normally
    std::string out, err;
};

/// Runs `command` through the shell with stdout and stderr captured in files of `dir`.
inline Output run_captured(const std::string& command, const std::filesystem::path& dir)
{
    const std::filesystem::path out = dir / "stdout.txt", err = dir / "stderr.txt";
    const std::string full = command + " >'" + out.string() + "' 2>'" + err.string() + "'";
    const int raw = std::system(full.c_str());
    Output o;
    o.status = WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
    o.out = slurp(out);
    o.err = slurp(err);
    return o;
}

/// `text` as one shell word: in single quotes, its own single quotes escaped.
inline std::string shell_quote(const std::string& text)
{
    std::string quoted = "'";
    for (char ch : text) quoted += ch == '\'' ? std::string("'\\''") : std::string(1, ch);
    return quoted + "'";
}

/// A fresh (emptied) folder `parent/name`.
inline std::filesystem::path fresh_subdir(const std::filesystem::path& parent, const std::string& name)
{
    std::filesystem::path d = parent / name;
    std::filesystem::remove_all(d);
    std::filesystem::create_directories(d);
    return d;
}

/// How run_contactbench calls the binary.
struct CliCall {
    std::filesystem::path cd;  ///< the working folder; empty: the test process's
    std::string prefix;        ///< shell commands run first (e.g. "ulimit -f 4")
    std::string env;           ///< "NAME=value ..." for the binary's environment
    std::string program = contactbench_binary();
};

/// Runs `[cd CD &&] [PREFIX;] [ENV] exec timeout 120 PROGRAM ARGS` in bash (ARGS shell-quoted where
/// needed), stdout and stderr captured in files of `capture_dir`; a hang ends as exit status 124.
inline Output run_contactbench(const std::string& args, const std::filesystem::path& capture_dir,
                               const CliCall& call = {})
{
    std::string inner = call.cd.empty() ? "" : "cd " + shell_quote(call.cd.string()) + " && ";
    if (!call.prefix.empty()) inner += call.prefix + "; ";
    if (!call.env.empty()) inner += call.env + " ";
    inner += "exec timeout 120 " + shell_quote(call.program) + " " + args;
    return run_captured("bash -c " + shell_quote(inner), capture_dir);
}

}  // namespace cb::test
