#pragma once
/// Helpers shared by the tests that drive the contactbench binary (env CB_CONTACTBENCH): where
/// the binary is, a scratch folder per test process, and running a shell command with its
/// output captured.
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

}  // namespace cb::test
