// Issue 31's per-iteration cost criterion: an iteration of `mprgp-coupled` (all rows) against one
// of decoupled `mprgp` (the authors' row order, as `contactbench run` with "decouple": "auto"
// gives it), both with their registry defaults (precond jacobi, tol 1e-6 on the accuracy error),
// on the snapshots named in CB_BENCH_SNAPSHOTS (colon-separated .qpsnap paths; unset: no
// benchmark is registered). Each benchmark iteration solves with both solvers back to back, so
// the ratio is measured under one machine load; --benchmark_repetitions=N gives its spread.
// Times are the solvers' iteration clocks (solve_s: setup, power method and monitor excluded).
#include "problems/qpsnap.hpp"
#include "solvers/decouple.hpp"
#include "solvers/registry.hpp"

#include <benchmark/benchmark.h>

#include <cstdlib>
#include <filesystem>
#include <memory>
#include <sstream>
#include <string>

namespace {

struct SnapshotPair {
    cb::Qp coupled;    ///< every row
    cb::Qp decoupled;  ///< the rows decoupled mprgp keeps
};

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
    const auto coupled = cb::builtin_registry().create("mprgp-coupled", nlohmann::json::object());
    const auto decoupled = cb::builtin_registry().create("mprgp", nlohmann::json::object());
    double ratio_sum = 0.0, coupled_sum = 0.0, decoupled_sum = 0.0;
    long runs = 0, coupled_iterations = 0, decoupled_iterations = 0;
    bool converged = true;
    for (auto _ : state) {
        const cb::SolverResult d = decoupled->solve(loaded->decoupled.view(), cb::SolveContext{});
        const cb::SolverResult c = coupled->solve(loaded->coupled.view(), cb::SolveContext{});
        const double per_d = d.solve_s / static_cast<double>(std::max(1L, d.counters.iterations));
        const double per_c = c.solve_s / static_cast<double>(std::max(1L, c.counters.iterations));
        state.SetIterationTime(per_c);
        ratio_sum += per_c / per_d;
        coupled_sum += per_c;
        decoupled_sum += per_d;
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
            ->Iterations(3);
    }
    return true;
}();

}  // namespace
