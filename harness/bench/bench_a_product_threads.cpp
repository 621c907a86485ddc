// The `threads` setting's figures (docs/a_product.md): the A-product with 1 and 2 threads, CSR
// and 3x3 blocks, beside a STREAM-like triad on 1 and 2 threads (the machine's ceiling for a
// memory-bound kernel), all six alternating repetition by repetition in one benchmark iteration.
// Times are wall clock (a threaded kernel's CPU time is the sum over its threads), so on a machine
// shared with other jobs a repetition may wait for a core: the medians of per-repetition ratios,
// with their min and max, are the figures. Counters: <fmt>_speedup = time(1 thread) / time(2),
// triad_speedup the same for the triad, <fmt>_of_triad_speedup their quotient (1 = the product
// gains what the memory system gives), <fmt>_speedup_best the ratio of the best times of each,
// same_y = 1 when both thread counts and both formats give the same y bits.
//   CB_BENCH_SNAPSHOTS=a.qpsnap:b.qpsnap build/bin/cb_bench --benchmark_filter=AProductThreads
#include "problems/qpsnap.hpp"
#include "problems/synthetic.hpp"
#include "solvers/a_product.hpp"

#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

namespace {

double median(std::vector<double> v)
{
    std::sort(v.begin(), v.end());
    const size_t k = v.size() / 2;
    return v.size() % 2 ? v[k] : 0.5 * (v[k - 1] + v[k]);
}

int repetitions()
{
    const char* env = std::getenv("CB_BENCH_REPS");
    return std::max(3, env ? std::atoi(env) : 15);
}

template <typename F> double wall_s(F&& f)
{
    const auto t0 = std::chrono::steady_clock::now();
    f();
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

/// a = b + 3 c over [first, last).
void triad(double* a, const double* b, const double* c, Eigen::Index first, Eigen::Index last)
{
    for (Eigen::Index i = first; i < last; ++i) a[i] = b[i] + 3.0 * c[i];
}

/// The triad on `threads` (1 or 2) halves; the second thread is started per call (tens of
/// microseconds against the milliseconds of a triad beyond the caches).
void run_triad(cb::Vec& a, const cb::Vec& b, const cb::Vec& c, int threads)
{
    const Eigen::Index t = a.size();
    if (threads == 1) return triad(a.data(), b.data(), c.data(), 0, t);
    std::thread other([&] { triad(a.data(), b.data(), c.data(), t / 2, t); });
    triad(a.data(), b.data(), c.data(), 0, t / 2);
    other.join();
}

struct Ratios {
    std::vector<double> one, two, ratio;  // times with 1 and 2 threads, and their ratio per repetition
    void add(double t1, double t2)
    {
        one.push_back(t1);
        two.push_back(t2);
        ratio.push_back(t1 / t2);
    }
};

void report(benchmark::State& state, const std::string& name, const Ratios& r, double triad_speedup)
{
    state.counters[name + "_ms_1"] = 1e3 * median(r.one);
    state.counters[name + "_ms_2"] = 1e3 * median(r.two);
    state.counters[name + "_speedup"] = median(r.ratio);
    state.counters[name + "_speedup_min"] = *std::min_element(r.ratio.begin(), r.ratio.end());
    state.counters[name + "_speedup_max"] = *std::max_element(r.ratio.begin(), r.ratio.end());
    // Best times: the repetitions least disturbed by other jobs (a quiet machine's figure).
    state.counters[name + "_speedup_best"] =
        *std::min_element(r.one.begin(), r.one.end()) / *std::min_element(r.two.begin(), r.two.end());
    if (triad_speedup > 0.0) state.counters[name + "_of_triad_speedup"] = median(r.ratio) / triad_speedup;
}

void measure(benchmark::State& state, const cb::Qp& qp)
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
    // The triad on arrays as large as A's CSR storage (at least 3 x 32 MB): beyond the caches.
    const Eigen::Index t =
        std::max<Eigen::Index>(Eigen::Index{1} << 22, static_cast<Eigen::Index>(csr1.matrix_bytes() / 24));
    cb::Vec a = cb::Vec::Zero(t), b = cb::Vec::Constant(t, 1.0), c = cb::Vec::Constant(t, 2.0);
    const auto product = [](const cb::AOperator& op, const cb::Vec& in, cb::Vec& out) {
        return wall_s([&] {
            cb::a_product(op, in, out);
            benchmark::DoNotOptimize(out.data());
            benchmark::ClobberMemory();
        });
    };
    const auto triad_s = [&](int threads) {
        return wall_s([&] {
            run_triad(a, b, c, threads);
            benchmark::DoNotOptimize(a.data());
            benchmark::ClobberMemory();
        });
    };
    Ratios tri, csr, bsr;
    const int reps = repetitions();
    for (auto _ : state) {
        for (int r = 0; r < reps + 1; ++r) {  // repetition 0 warms up (page faults, thread start)
            const double t1 = triad_s(1), t2 = triad_s(2);
            const double c1 = product(csr1, x, y1), c2 = product(csr2, x, y2);
            const double b1 = product(bsr1, x, z1), b2 = product(bsr2, x, z2);
            if (r == 0) continue;
            tri.add(t1, t2);
            csr.add(c1, c2);
            bsr.add(b1, b2);
        }
        state.SetIterationTime(median(csr.one) + median(bsr.one));
    }
    const double triad_speedup = median(tri.ratio);
    state.counters["n"] = static_cast<double>(n);
    state.counters["nnz"] = static_cast<double>(A.nonZeros());
    state.counters["parts"] = bsr2.parts();
    state.counters["triad_GBps_1"] = 24.0 * static_cast<double>(t) / median(tri.one) * 1e-9;
    report(state, "triad", tri, 0.0);
    report(state, "csr", csr, triad_speedup);
    report(state, "bsr", bsr, triad_speedup);
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
    measure(state, qp);
}
BENCHMARK(BM_AProductThreads_plane32)->UseManualTime()->Iterations(1)->Unit(benchmark::kMillisecond);

/// One benchmark per snapshot of CB_BENCH_SNAPSHOTS, registered before main() runs.
const bool registered = [] {
    const char* list = std::getenv("CB_BENCH_SNAPSHOTS");
    if (list == nullptr) return false;
    std::istringstream in(list);
    std::string path;
    while (std::getline(in, path, ':')) {
        if (path.empty()) continue;
        const std::string name = "BM_AProductThreads/" + std::filesystem::path(path).stem().string();
        benchmark::RegisterBenchmark(name.c_str(),
                                     [path](benchmark::State& state) {
                                         const cb::Qp qp = cb::read_qpsnap(path);
                                         measure(state, qp);
                                     })
            ->UseManualTime()
            ->Iterations(1)
            ->Unit(benchmark::kMillisecond);
    }
    return true;
}();

}  // namespace
