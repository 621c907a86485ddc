// The `threads` setting's figures (docs/a_product.md): the A-product with 1 and 2 threads, CSR
// and 3x3 blocks, beside a STREAM-like triad on 1 and 2 threads (the machine's ceiling for a
// memory-bound kernel), all six alternating repetition by repetition in one benchmark iteration
// (harness/bench/alternating.hpp). The symmetric blocks (SBSR) run on one thread only: their
// one-thread figures are in bench_a_product.cpp.
// Times are wall clock (a threaded kernel's CPU time is the sum over its threads), so on a machine
// shared with other jobs a repetition may wait for a core: the medians of per-repetition ratios,
// with their min and max, are the figures. Counters: <fmt>_speedup = time(1 thread) / time(2),
// triad_speedup the same for the triad, <fmt>_of_triad_speedup their quotient (1 = the product
// gains what the memory system gives), <fmt>_speedup_best the ratio of the best times of each,
// same_y = 1 when both thread counts and both formats give the same y bits; <f>_GBps_2 and
// <f>_of_triad_2 the 2-thread GB/s and its fraction of the 2-thread triad's.
//   CB_BENCH_SNAPSHOTS=a.qpsnap:b.qpsnap build/bin/cb_bench --benchmark_filter=AProductThreads
#include "harness/bench/alternating.hpp"
#include "problems/synthetic.hpp"
#include "solvers/linalg/a_product.hpp"

#include <benchmark/benchmark.h>

#include <string>
#include <thread>
#include <vector>

namespace {

using namespace cb::bench;

/// The triad on `threads` (1 or 2) halves; the second thread is started per call (tens of
/// microseconds against the milliseconds of a triad beyond the caches).
void run_triad(cb::Vec& a, const cb::Vec& b, const cb::Vec& c, int threads)
{
    const std::ptrdiff_t t = a.size();
    if (threads == 1) return triad(a.data(), b.data(), c.data(), 0, t);
    std::thread other([&] { triad(a.data(), b.data(), c.data(), t / 2, t); });
    triad(a.data(), b.data(), c.data(), 0, t / 2);
    other.join();
}

/// Counters of one kernel timed with 1 and 2 threads (`one`, `two`: per-repetition times).
void report(benchmark::State& state, const std::string& name, const std::vector<double>& one,
            const std::vector<double>& two, double triad_speedup)
{
    const std::vector<double> r = ratios(one, two);
    state.counters[name + "_ms_1"] = 1e3 * median(one);
    state.counters[name + "_ms_2"] = 1e3 * median(two);
    state.counters[name + "_speedup"] = median(r);
    state.counters[name + "_speedup_min"] = *std::min_element(r.begin(), r.end());
    state.counters[name + "_speedup_max"] = *std::max_element(r.begin(), r.end());
    // Best times: the repetitions least disturbed by other jobs (a quiet machine's figure).
    state.counters[name + "_speedup_best"] = best(one) / best(two);
    if (triad_speedup > 0.0) state.counters[name + "_of_triad_speedup"] = median(r) / triad_speedup;
}

void measure_threads(benchmark::State& state, const cb::Qp& qp)
{
    const cb::SpMat& A = qp.A;
    const Eigen::Index n = A.rows();
    cb::AOperator csr1(A), csr2(A), bsr1(A), bsr2(A);
    csr1.prepare(cb::AFormat::CSR, 1);
    csr2.prepare(cb::AFormat::CSR, 2);
    bsr1.prepare(cb::AFormat::BSR, 1);
    bsr2.prepare(cb::AFormat::BSR, 2);
    const cb::Vec x = cb::Vec::LinSpaced(n, -1.0, 1.0);
    cb::Vec y1(n), y2(n), z1(n), z2(n);
    const std::ptrdiff_t t = triad_length(csr1.matrix_bytes());
    cb::Vec a = triad_array(t, 0.0), b = triad_array(t, 1.0), c = triad_array(t, 2.0);
    const auto product = [](const cb::AOperator& op, const cb::Vec& in, cb::Vec& out) {
        return [&op, &in, &out] {
            cb::a_product(op, in, out);
            benchmark::DoNotOptimize(out.data());
        };
    };
    std::vector<std::vector<double>> times;
    for (auto _ : state) {
        times = alternate({[&] { run_triad(a, b, c, 1); }, [&] { run_triad(a, b, c, 2); }, product(csr1, x, y1),
                           product(csr2, x, y2), product(bsr1, x, z1), product(bsr2, x, z2)},
                          Clock::WALL);
        state.SetIterationTime(median(times[2]) + median(times[4]));
    }
    const double triad_speedup = median(ratios(times[0], times[1]));
    const double vectors = 16.0 * static_cast<double>(n);
    state.counters["n"] = static_cast<double>(n);
    state.counters["nnz"] = static_cast<double>(A.nonZeros());
    state.counters["parts"] = bsr2.parts();
    state.counters["triad_GBps_1"] = 24.0 * static_cast<double>(t) / median(times[0]) * 1e-9;
    state.counters["triad_GBps_2"] = 24.0 * static_cast<double>(t) / median(times[1]) * 1e-9;
    state.counters["bsr_GBps_2"] = (bsr2.matrix_bytes() + vectors) / median(times[5]) * 1e-9;
    state.counters["bsr_of_triad_2"] = state.counters["bsr_GBps_2"] / state.counters["triad_GBps_2"];
    state.counters["csr_GBps_2"] = (csr2.matrix_bytes() + vectors) / median(times[3]) * 1e-9;
    state.counters["csr_of_triad_2"] = state.counters["csr_GBps_2"] / state.counters["triad_GBps_2"];
    report(state, "triad", times[0], times[1], 0.0);
    report(state, "csr", times[2], times[3], triad_speedup);
    report(state, "bsr", times[4], times[5], triad_speedup);
    state.counters["same_y"] = (y1 - y2).lpNorm<Eigen::Infinity>() == 0.0 &&
                                       (z1 - z2).lpNorm<Eigen::Infinity>() == 0.0 &&
                                       (y1 - z1).lpNorm<Eigen::Infinity>() == 0.0
                                   ? 1.0
                                   : 0.0;
    state.SetLabel(std::string(bsr2.format() == cb::AFormat::BSR ? "bsr" : "csr fallback") +
                   (cb::a_product_parallel_build() ? ", openmp" : ", serial build"));
}

// NOLINTNEXTLINE(readability-identifier-naming): Google Benchmark's BM_<name> convention
void BM_AProductThreads_plane32(benchmark::State& state)
{
    static const cb::Qp qp = cb::make_synthetic("plane", {{"nx", 32}, {"ny", 32}, {"nz", 32}}, 1);
    measure_threads(state, qp);
}
BENCHMARK(BM_AProductThreads_plane32)->UseManualTime()->Iterations(1)->Unit(benchmark::kMillisecond);

const bool threads_registered = register_per_snapshot("BM_AProductThreads", measure_threads);

}  // namespace
