#include "harness/provenance.hpp"

#include "harness/blas_threads.hpp"
#include "harness/slurm.hpp"
#include "solvers/core/registry.hpp"
#include "solvers/linalg/a_product.hpp"

#include <Eigen/Core>
#include <SuiteSparse_config.h>

#include <array>
#include <cstdio>
#include <ctime>
#include <fstream>
#include <string>
#include <thread>
#include <unistd.h>
#include <vector>

#ifndef CB_BUILD_TYPE
#define CB_BUILD_TYPE "unknown"
#endif
#ifndef CB_SOURCE_DIR
#define CB_SOURCE_DIR "."
#endif
#ifndef CB_CHOLMOD_VERSION
#define CB_CHOLMOD_VERSION "unknown"
#endif

namespace cb {

namespace {

/// Output of a shell command (stdout), or nullopt-like empty + ok=false on failure.
bool run_capture(const std::string& command, std::string& out)
{
    out.clear();
    FILE* pipe = ::popen(command.c_str(), "r");
    if (!pipe) return false;
    std::array<char, 4096> buffer{};
    size_t got = 0;
    while ((got = std::fread(buffer.data(), 1, buffer.size(), pipe)) > 0) out.append(buffer.data(), got);
    return ::pclose(pipe) == 0;
}

std::string trim(std::string s)
{
    while (!s.empty() && (s.back() == '\n' || s.back() == ' ' || s.back() == '\r' || s.back() == '\t')) s.pop_back();
    size_t i = 0;
    while (i < s.size() && (s[i] == ' ' || s[i] == '\t')) ++i;
    return s.substr(i);
}

std::string cpu_model()
{
    std::ifstream in("/proc/cpuinfo");
    std::string line;
    while (std::getline(in, line)) {
        if (line.rfind("model name", 0) == 0) {
            const auto colon = line.find(':');
            if (colon != std::string::npos) return trim(line.substr(colon + 1));
        }
    }
    return "unknown";
}

std::string blas_in_use()
{
    char target[4096];
    for (const char* link : {"/etc/alternatives/libblas.so.3-x86_64-linux-gnu", "/etc/alternatives/libblas.so.3"}) {
        const ssize_t len = ::readlink(link, target, sizeof(target) - 1);
        if (len > 0) {
            target[len] = '\0';
            return target;
        }
    }
    return "unknown";
}

nlohmann::json compute()
{
    nlohmann::json p;
    const std::string source = CB_SOURCE_DIR;
    std::string out;
    std::string commit = "unknown";
    nlohmann::json dirty = nullptr;
    if (run_capture("git -C '" + source + "' rev-parse HEAD 2>/dev/null", out)) {
        commit = trim(out);
        if (run_capture("git -C '" + source + "' status --porcelain 2>/dev/null", out)) dirty = !trim(out).empty();
    } else {
#ifdef CB_GIT_COMMIT
        commit = CB_GIT_COMMIT;
#endif
    }
    p["git_commit"] = commit;
    p["git_dirty"] = dirty;
    p["build_type"] = CB_BUILD_TYPE;
#ifdef __VERSION__
    p["compiler"] = std::string(
#if defined(__clang__)
                        "clang "
#elif defined(__GNUC__)
                        "gcc "
#endif
                        ) +
                    __VERSION__;
#else
    p["compiler"] = "unknown";
#endif
    p["cpu"] = cpu_model();
    p["cores"] = std::thread::hardware_concurrency();
    p["date"] = utc_now_iso();
    p["eigen"] = std::to_string(EIGEN_WORLD_VERSION) + "." + std::to_string(EIGEN_MAJOR_VERSION) + "." +
                 std::to_string(EIGEN_MINOR_VERSION);
    p["suitesparse"] = std::to_string(SUITESPARSE_MAIN_VERSION) + "." + std::to_string(SUITESPARSE_SUB_VERSION) + "." +
                       std::to_string(SUITESPARSE_SUBSUB_VERSION) + " (CHOLMOD " + CB_CHOLMOD_VERSION + ")";
    p["blas"] = blas_in_use();
    p["blas_threads"] = blas_threads();  // 0: not OpenBLAS (harness/blas_threads.hpp)
    // How the solvers' `threads` setting runs (each run records its own threads in its settings).
    p["a_product_threads"] = a_product_parallel_build() ? "openmp" : "serial";
    // The external peers compiled in, with their libraries' versions (docs/peers.md).
    nlohmann::json peers = nlohmann::json::object();
    const SolverRegistry& registry = builtin_registry();
    for (const std::string& name : registry.names())
        if (!registry.entry(name).library.empty()) peers[name] = registry.entry(name).library;
    p["peers"] = peers;
    char host[256] = {0};
    p["hostname"] = ::gethostname(host, sizeof(host) - 1) == 0 ? std::string(host) : std::string("unknown");
    const nlohmann::json job = slurm_job_provenance(slurm_environment());
    if (!job.is_null()) p["slurm"] = job;
    return p;
}

}  // namespace

std::string utc_now_iso()
{
    const std::time_t now = std::time(nullptr);
    std::tm tm{};
    ::gmtime_r(&now, &tm);
    char buffer[32];
    std::strftime(buffer, sizeof(buffer), "%Y-%m-%dT%H:%M:%SZ", &tm);
    return buffer;
}

nlohmann::json load_average()
{
    std::ifstream in("/proc/loadavg");
    double one = 0, five = 0, fifteen = 0;
    if (!(in >> one >> five >> fifteen)) return nullptr;
    return {one, five, fifteen};
}

const nlohmann::json& build_identity()
{
    static const nlohmann::json cached = [] {
        // FNV-1a 64 of the executable's bytes: the same source rebuilt with other flags differs.
        std::uint64_t h = 14695981039346656037ULL;
        std::ifstream in("/proc/self/exe", std::ios::binary);
        std::vector<char> buffer(1 << 20);
        bool read_any = false;
        while (in) {
            in.read(buffer.data(), std::streamsize(buffer.size()));
            const std::streamsize got = in.gcount();
            read_any = read_any || got > 0;
            for (std::streamsize i = 0; i < got; ++i) {
                h ^= static_cast<unsigned char>(buffer[size_t(i)]);
                h *= 1099511628211ULL;
            }
        }
        char hex[17];
        std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(h));
        return nlohmann::json{{"commit", provenance()["git_commit"]},
                              {"binary", read_any ? nlohmann::json(hex) : nlohmann::json()}};
    }();
    return cached;
}

nlohmann::json provenance()
{
    static const nlohmann::json cached = compute();
    nlohmann::json p = cached;
    p["load_average"] = load_average();  // now, not at the first call: a busy node shows per run
    return p;
}

}  // namespace cb
