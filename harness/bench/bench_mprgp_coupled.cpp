// Issue 31's per-iteration cost criterion: an iteration of `mprgp-coupled` (all rows) against one
// of decoupled `mprgp` (the authors' row order, as `contactbench run` with "decouple": "auto"
// gives it), both with their registry defaults (tol 1e-6 on the accuracy error; precond jacobi for `mprgp`, auto
// for `mprgp-coupled`: scaled on a component beyond dense_max_rows, else jacobi),
// on the snapshots named in CB_BENCH_SNAPSHOTS (colon-separated .qpsnap paths; unset: no
// benchmark is registered). Each benchmark iteration solves with both solvers back to back, so
// the ratio is measured under one machine load; --benchmark_repetitions=N gives its spread.
// The time per iteration is the thread's CPU time from the first monitor call (after the setup,
// the power method and the first projection) to the last, over the iterations between: on a
// machine shared with other jobs the wall clock counts the time the process waited for a core
// (measured: 0.3 CPUs utilised under load 10 on 2 cores). The wall-clock figures (solve_s per
// iteration) are reported beside it.
// The build aligns loops and functions to 64 bytes (CMakeLists.txt): the A-product's inner loop
// runs ~20% slower when it crosses a 64-byte boundary, so without that rule unrelated code moving it
// swung the ratio of identical solver code from 0.85 to 1.21 (two_dinos_1303 frame 11;
// docs/ALGORITHMS.md §4). Compare builds made under the same rule.
// With CB_BENCH_CALLGRIND set, under `valgrind --tool=callgrind --collect-atstart=no` (tools/
// iteration_instructions.py runs it), each benchmark solves once with each solver and callgrind
// collects from the first monitor call to the solve's return, one dump per solve labelled
// "coupled <snapshot>" / "mprgp <snapshot>": instructions per iteration, the same on every run
// (thread CPU time per iteration swings ~10% run to run on a shared VM).
// CB_BENCH_COUPLED_SETTINGS (a JSON object, e.g. {"precond": "scaled"}) sets `mprgp-coupled`'s
// settings instead of its defaults; decoupled `mprgp` keeps its own.
#include "problems/qpsnap.hpp"
#include "solvers/core/registry.hpp"
#include "solvers/mprgp/decouple.hpp"

#include <benchmark/benchmark.h>
#if __has_include(<valgrind/callgrind.h>)
#include <valgrind/callgrind.h>
#define CB_BENCH_HAVE_CALLGRIND 1
#endif

#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <memory>
#include <sstream>
#include <string>

namespace {

struct SnapshotPair {
    cb::Qp coupled;    ///< every row
    cb::Qp decoupled;  ///< the rows decoupled mprgp keeps
};

double thread_cpu_s()
{
    timespec t{};
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
    return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

/// CB_BENCH_CALLGRIND: callgrind collects only inside the solves' iterations (see the header).
bool callgrind_mode() { return std::getenv("CB_BENCH_CALLGRIND") != nullptr; }

/// Starts (at the first monitor call) or ends (after the solve, with a dump named `label`) callgrind's
/// collection in callgrind mode; no-ops otherwise and outside valgrind.
void toggle_callgrind(const std::string* dump_label = nullptr)
{
#ifdef CB_BENCH_HAVE_CALLGRIND
    if (!callgrind_mode()) return;
    CALLGRIND_TOGGLE_COLLECT;
    if (dump_label != nullptr) CALLGRIND_DUMP_STATS_AT(dump_label->c_str());
#else
    (void)dump_label;
#endif
}

/// Thread CPU time at the first and the last outer iteration.
class CpuClockMonitor : public cb::Monitor {
public:
    bool on_iteration(const cb::IterationInfo& info) override
    {
        const double now = thread_cpu_s();
        if (m_calls++ == 0) {
            toggle_callgrind();
            m_first = now;
            m_first_iteration = info.iteration;
        }
        m_last = now;
        m_last_iteration = info.iteration;
        return true;
    }
    bool wants_iterate() const override { return false; }
    bool called() const { return m_calls > 0; }
    double per_iteration() const
    {
        const long k = m_last_iteration - m_first_iteration;
        return k > 0 ? (m_last - m_first) / static_cast<double>(k) : 0.0;
    }

private:
    long m_calls = 0, m_first_iteration = 0, m_last_iteration = 0;
    double m_first = 0.0, m_last = 0.0;
};

// NOLINTNEXTLINE(readability-identifier-naming): Google Benchmark's BM_<name> convention
void BM_mprgp_coupled_iteration_ratio(benchmark::State& state, const std::string& path)
{
    static std::unique_ptr<SnapshotPair> loaded;  // one snapshot in memory at a time
    static std::string loaded_path;
    if (loaded_path != path) {
        loaded.reset();
        auto pair = std::make_unique<SnapshotPair>();
        pair->coupled = cb::read_qpsnap(path);
        const cb::DecoupleReport report =
            cb::decouple_rows(pair->coupled.view(), pair->coupled.contacts, cb::DecoupleOrder::AUTHORS, 0);
        pair->decoupled = cb::select_rows(pair->coupled, report.kept_rows);
        loaded = std::move(pair);
        loaded_path = path;
    }
    nlohmann::json coupled_settings = nlohmann::json::object();
    if (const char* s = std::getenv("CB_BENCH_COUPLED_SETTINGS"); s != nullptr && *s != '\0') {
        coupled_settings = nlohmann::json::parse(s, nullptr, false);
        if (!coupled_settings.is_object()) {
            state.SkipWithError("CB_BENCH_COUPLED_SETTINGS: not a JSON object");
            return;
        }
    }
    std::unique_ptr<cb::Solver> coupled;
    try {
        coupled = cb::builtin_registry().create("mprgp-coupled", coupled_settings);
    } catch (const std::exception& e) {
        state.SkipWithError((std::string("CB_BENCH_COUPLED_SETTINGS: ") + e.what()).c_str());
        return;
    }
    const auto decoupled = cb::builtin_registry().create("mprgp", nlohmann::json::object());
    double ratio_sum = 0.0, coupled_sum = 0.0, decoupled_sum = 0.0, wall_ratio_sum = 0.0;
    long runs = 0, coupled_iterations = 0, decoupled_iterations = 0;
    bool converged = true;
    for (auto _ : state) {
        CpuClockMonitor clock_d, clock_c;
        cb::SolveContext context_d, context_c;
        context_d.monitor = &clock_d;
        context_c.monitor = &clock_c;
        const std::string stem = std::filesystem::path(path).stem().string();
        const std::string label_d = "mprgp " + stem, label_c = "coupled " + stem;
        const cb::SolverResult d = decoupled->solve(loaded->decoupled.view(), context_d);
        if (clock_d.called()) toggle_callgrind(&label_d);  // collection ends (it began at the first call)
        const cb::SolverResult c = coupled->solve(loaded->coupled.view(), context_c);
        if (clock_c.called()) toggle_callgrind(&label_c);
        const double per_d = clock_d.per_iteration(), per_c = clock_c.per_iteration();
        state.SetIterationTime(per_c);
        ratio_sum += per_c / per_d;
        coupled_sum += per_c;
        decoupled_sum += per_d;
        wall_ratio_sum += (c.solve_s / static_cast<double>(std::max(1L, c.counters.iterations))) /
                          (d.solve_s / static_cast<double>(std::max(1L, d.counters.iterations)));
        coupled_iterations = c.counters.iterations;
        decoupled_iterations = d.counters.iterations;
        converged = converged && c.status == cb::SolveStatus::CONVERGED;
        ++runs;
    }
    const double k = static_cast<double>(std::max(1L, runs));
    state.counters["n"] = static_cast<double>(loaded->coupled.n());
    state.counters["m"] = static_cast<double>(loaded->coupled.m());
    state.counters["coupled_ms_per_it"] = 1e3 * coupled_sum / k;
    state.counters["mprgp_ms_per_it"] = 1e3 * decoupled_sum / k;
    state.counters["ratio"] = ratio_sum / k;
    state.counters["wall_ratio"] = wall_ratio_sum / k;
    state.counters["coupled_it"] = static_cast<double>(coupled_iterations);
    state.counters["mprgp_it"] = static_cast<double>(decoupled_iterations);
    state.counters["coupled_converged"] = converged ? 1.0 : 0.0;
}

/// Registers one benchmark per snapshot of CB_BENCH_SNAPSHOTS before main() runs.
const bool registered = [] {
    const char* list = std::getenv("CB_BENCH_SNAPSHOTS");
    if (list == nullptr) return false;
    std::istringstream in(list);
    std::string path;
    while (std::getline(in, path, ':')) {
        if (path.empty()) continue;
        const std::string name = "BM_mprgp_coupled_iteration_ratio/" + std::filesystem::path(path).stem().string();
        benchmark::RegisterBenchmark(name.c_str(), BM_mprgp_coupled_iteration_ratio, path)
            ->UseManualTime()
            ->Unit(benchmark::kMillisecond)
            ->Iterations(callgrind_mode() ? 1 : 3);
    }
    return true;
}();

}  // namespace
