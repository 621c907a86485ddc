#pragma once
// The A-product benchmarks' common timing loop (bench_a_product*.cpp, bench_iteration_share.cpp):
// several kernels run in turn, repetition by repetition, so that a load from other processes hits
// them alike; the figures are medians of per-repetition times and ratios, with their spread.
// CB_BENCH_REPS sets the repetitions (default 15); repetition 0 warms up and is not kept.
#include "problems/qpsnap.hpp"
#include "solvers/linalg/prefault.hpp"

#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <functional>
#include <sstream>
#include <string>
#include <vector>

namespace cb::bench {

inline double median(std::vector<double> v)
{
    std::sort(v.begin(), v.end());
    const size_t k = v.size() / 2;
    return v.size() % 2 ? v[k] : 0.5 * (v[k - 1] + v[k]);
}

/// max / min.
inline double spread(const std::vector<double>& v)
{
    return *std::max_element(v.begin(), v.end()) / *std::min_element(v.begin(), v.end());
}

inline double best(const std::vector<double>& v) { return *std::min_element(v.begin(), v.end()); }

inline int repetitions()
{
    const char* env = std::getenv("CB_BENCH_REPS");
    return std::max(3, env ? std::atoi(env) : 15);
}

/// Which clock a kernel is timed on: the thread's CPU time (one-thread kernels: on a shared machine
/// the wall clock also counts the time the process waited for a core) or the wall clock
/// (threaded kernels, whose CPU time is the sum over their threads).
enum class Clock { THREAD_CPU, WALL };

inline double now_s(Clock clock)
{
    if (clock == Clock::WALL)
        return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
    timespec t{};
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
    return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

/// Per kernel, its times over the kept repetitions (kernels run in the order given, every repetition).
inline std::vector<std::vector<double>> alternate(const std::vector<std::function<void()>>& kernels, Clock clock)
{
    const int reps = repetitions();
    std::vector<std::vector<double>> times(kernels.size());
    for (int r = 0; r < reps + 1; ++r) {  // repetition 0 warms up (page faults, caches, thread start)
        for (size_t k = 0; k < kernels.size(); ++k) {
            const double t0 = now_s(clock);
            kernels[k]();
            benchmark::ClobberMemory();
            const double t = now_s(clock) - t0;
            if (r > 0) times[k].push_back(t);
        }
    }
    return times;
}

/// Per repetition a / b.
inline std::vector<double> ratios(const std::vector<double>& a, const std::vector<double>& b)
{
    std::vector<double> r(a.size());
    for (size_t i = 0; i < a.size(); ++i) r[i] = a[i] / b[i];
    return r;
}

/// a[i] = b[i] + 3 c[i] over [first, last): the STREAM triad.
inline void triad(double* a, const double* b, const double* c, std::ptrdiff_t first, std::ptrdiff_t last)
{
    for (std::ptrdiff_t i = first; i < last; ++i) a[i] = b[i] + 3.0 * c[i];
}

/// Triad arrays at least as large as `bytes` together (and 3 x 32 MB): beyond the caches.
inline std::ptrdiff_t triad_length(double bytes)
{
    return std::max<std::ptrdiff_t>(std::ptrdiff_t{1} << 22, static_cast<std::ptrdiff_t>(bytes / 24.0));
}

/// A triad array of t entries, all equal to `value`, on huge pages where the system gives them as A's
/// blocks are (solvers/linalg/prefault.hpp): the ceiling measured on the pages the products read.
inline Vec triad_array(std::ptrdiff_t t, double value)
{
    Vec v(t);  // not written yet: the advice takes effect at the first touch below
    advise_huge_pages(v.data(), static_cast<std::size_t>(t) * sizeof(double));
    v.setConstant(value);
    return v;
}

/// Registers `body` once per snapshot of CB_BENCH_SNAPSHOTS (colon-separated .qpsnap paths) as
/// `prefix`/<stem>, one iteration each, in milliseconds of manual time.
inline bool register_per_snapshot(const std::string& prefix,
                                  const std::function<void(benchmark::State&, const Qp&)>& body)
{
    const char* list = std::getenv("CB_BENCH_SNAPSHOTS");
    if (list == nullptr) return false;
    std::istringstream in(list);
    std::string path;
    while (std::getline(in, path, ':')) {
        if (path.empty()) continue;
        const std::string name = prefix + "/" + std::filesystem::path(path).stem().string();
        benchmark::RegisterBenchmark(name.c_str(),
                                     [path, body](benchmark::State& state) {
                                         const Qp qp = read_qpsnap(path);
                                         body(state, qp);
                                     })
            ->UseManualTime()
            ->Iterations(1)
            ->Unit(benchmark::kMillisecond);
    }
    return true;
}

}  // namespace cb::bench
