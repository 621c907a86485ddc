// Per-iteration cost of `ica` (ALGORITHMS.md §6) on the FEM-like ~100k-DOF A (fem_like_matrix,
// nx = ny = nz = 32: n = 107811) with plane rows, the problem of the mprgp benchmark, so that
// the two per-iteration costs are measured in the same binary. Also one A-product on the same A
// for scale (an ICA outer iteration costs about 2 A-products + the PGS sweeps on B).
#include "problems/synthetic.hpp"
#include "solvers/core/registry.hpp"

#include <benchmark/benchmark.h>

namespace {

const cb::Qp& dual_bench_problem()
{
    static const cb::Qp qp = cb::make_synthetic("plane", {{"nx", 32}, {"ny", 32}, {"nz", 32}}, 1);
    return qp;
}

/// Records the solver clock (monitor time excluded) at each outer iteration.
class ClockMonitor : public cb::Monitor {
public:
    bool on_iteration(const cb::IterationInfo& info) override
    {
        if (info.iteration == 1) m_first = info.elapsed_s;
        m_last = info.elapsed_s;
        m_last_iteration = info.iteration;
        return true;
    }
    double m_first = 0, m_last = 0;
    long m_last_iteration = 0;
};

/// Manual time: (t_k - t_1) / (k - 1) over k outer iterations of one solve, so that the
/// setup (block inverses, B = J D3^-1 J') and the first iteration's warm-up are excluded.
// NOLINTNEXTLINE(readability-identifier-naming): Google Benchmark's BM_<name> convention
void BM_ica_outer_iteration(benchmark::State& state)
{
    const cb::Qp& qp = dual_bench_problem();
    const long k = state.range(0);
    const auto solver = cb::builtin_registry().create("ica", {{"tol", 1e-300}, {"max_iterations", k}});
    long pgs = 0;
    for (auto _ : state) {
        ClockMonitor monitor;
        cb::SolveContext context;
        context.monitor = &monitor;
        const cb::SolverResult r = solver->solve(qp.view(), context);
        benchmark::DoNotOptimize(r.x.data());
        state.SetIterationTime((monitor.m_last - monitor.m_first) / static_cast<double>(monitor.m_last_iteration - 1));
        pgs = r.counters.pgs_sweeps;
    }
    state.counters["n"] = static_cast<double>(qp.n());
    state.counters["m"] = static_cast<double>(qp.m());
    state.counters["pgs_sweeps_per_outer"] = static_cast<double>(pgs) / static_cast<double>(k);
}
BENCHMARK(BM_ica_outer_iteration)->Arg(11)->UseManualTime()->Unit(benchmark::kMillisecond)->Iterations(3);

// NOLINTNEXTLINE(readability-identifier-naming): Google Benchmark's BM_<name> convention
void BM_ica_reference_a_product(benchmark::State& state)
{
    const cb::Qp& qp = dual_bench_problem();
    cb::Vec y(qp.n());
    for (auto _ : state) {
        y.noalias() = qp.A * qp.x0;
        benchmark::DoNotOptimize(y.data());
    }
    state.counters["nnz"] = static_cast<double>(qp.A.nonZeros());
}
BENCHMARK(BM_ica_reference_a_product)->Unit(benchmark::kMillisecond);

}  // namespace
