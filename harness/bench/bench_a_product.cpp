// Issue 47's A-product figures: one product with A read from CSR (Eigen's, the solvers' storage
// until now) and from 3x3 blocks (BSR, solvers/a_product), beside a STREAM-like triad, in one
// benchmark iteration with the three kernels alternating repetition by repetition, so that a load
// from other processes hits them alike. On the snapshots of CB_BENCH_SNAPSHOTS (colon-separated
// .qpsnap paths) and on the kernels' synthetic 32^3 plane. Counters per format: bytes per nonzero
// (A's storage only), GB/s (A's storage + x read once + y written), the fraction of the triad's
// GB/s, the median time and the spread (max / min over the repetitions); csr_over_bsr is the
// median of the per-repetition time ratios, with its min and max, and csr_over_bsr_best the ratio
// of the best times. Times are the thread's CPU time (on a machine shared with other jobs the wall
// clock also counts the time the process waited for a core); memory traffic of other jobs still
// slows every kernel alike. CB_BENCH_REPS sets the repetitions (default 15).
//   CB_BENCH_SNAPSHOTS=a.qpsnap:b.qpsnap build/bin/cb_bench --benchmark_filter=AProductFormats
#include "problems/qpsnap.hpp"
#include "problems/synthetic.hpp"
#include "solvers/a_product.hpp"

#include <benchmark/benchmark.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include <ctime>

namespace {

double median(std::vector<double> v)
{
    std::sort(v.begin(), v.end());
    const size_t k = v.size() / 2;
    return v.size() % 2 ? v[k] : 0.5 * (v[k - 1] + v[k]);
}

double spread(const std::vector<double>& v)
{
    return *std::max_element(v.begin(), v.end()) / *std::min_element(v.begin(), v.end());
}

int repetitions()
{
    const char* env = std::getenv("CB_BENCH_REPS");
    const int reps = env ? std::atoi(env) : 15;
    return std::max(3, reps);
}

double thread_cpu_s()
{
    timespec t{};
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
    return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

template <typename F> double seconds(F&& f)
{
    const double t0 = thread_cpu_s();
    f();
    return thread_cpu_s() - t0;
}

void measure(benchmark::State& state, const cb::Qp& qp)
{
    const cb::SpMat& A = qp.A;
    const Eigen::Index n = A.rows();
    cb::AOperator bsr(A);
    const double build_s = seconds([&] { bsr.prepare(cb::AFormat::BSR); });
    cb::AOperator csr(A);
    csr.prepare(cb::AFormat::CSR);
    const cb::Vec x = cb::Vec::LinSpaced(n, -1.0, 1.0);
    cb::Vec y_csr(n), y_bsr(n);
    // The triad on arrays as large as A's CSR storage (at least 3 x 32 MB): beyond the caches.
    const Eigen::Index t =
        std::max<Eigen::Index>(Eigen::Index{1} << 22, static_cast<Eigen::Index>(csr.matrix_bytes() / 24));
    cb::Vec a = cb::Vec::Zero(t), b = cb::Vec::Constant(t, 1.0), c = cb::Vec::Constant(t, 2.0);
    const int reps = repetitions();
    std::vector<double> t_csr, t_bsr, t_triad, ratio;
    for (auto _ : state) {
        for (int r = 0; r < reps + 1; ++r) {  // repetition 0 warms up (page faults, caches)
            const double s_triad = seconds([&] {
                double* pa = a.data();
                const double* pb = b.data();
                const double* pc = c.data();
                for (Eigen::Index i = 0; i < t; ++i) pa[i] = pb[i] + 3.0 * pc[i];
                benchmark::DoNotOptimize(a.data());
                benchmark::ClobberMemory();
            });
            const double s_csr = seconds([&] {
                cb::a_product(csr, x, y_csr);
                benchmark::DoNotOptimize(y_csr.data());
                benchmark::ClobberMemory();
            });
            const double s_bsr = seconds([&] {
                cb::a_product(bsr, x, y_bsr);
                benchmark::DoNotOptimize(y_bsr.data());
                benchmark::ClobberMemory();
            });
            if (r == 0) continue;
            t_triad.push_back(s_triad);
            t_csr.push_back(s_csr);
            t_bsr.push_back(s_bsr);
            ratio.push_back(s_csr / s_bsr);
        }
        state.SetIterationTime(median(t_csr) + median(t_bsr));
    }
    const double nnz = static_cast<double>(A.nonZeros());
    const double vectors = 16.0 * static_cast<double>(n);  // x read once, y written
    const double triad_gbps = 24.0 * static_cast<double>(t) / median(t_triad) * 1e-9;
    const double csr_gbps = (csr.matrix_bytes() + vectors) / median(t_csr) * 1e-9;
    const double bsr_gbps = (bsr.matrix_bytes() + vectors) / median(t_bsr) * 1e-9;
    state.counters["n"] = static_cast<double>(n);
    state.counters["nnz"] = nnz;
    state.counters["bsr"] = bsr.format() == cb::AFormat::BSR ? 1.0 : 0.0;
    state.counters["bsr_fill"] = bsr.fill();
    state.counters["bsr_build_ms"] = 1e3 * build_s;
    state.counters["csr_bytes_per_nz"] = csr.matrix_bytes() / nnz;
    state.counters["bsr_bytes_per_nz"] = bsr.matrix_bytes() / nnz;
    state.counters["triad_GBps"] = triad_gbps;
    state.counters["csr_ms"] = 1e3 * median(t_csr);
    state.counters["bsr_ms"] = 1e3 * median(t_bsr);
    state.counters["csr_spread"] = spread(t_csr);
    state.counters["bsr_spread"] = spread(t_bsr);
    state.counters["triad_spread"] = spread(t_triad);
    state.counters["csr_GBps"] = csr_gbps;
    state.counters["bsr_GBps"] = bsr_gbps;
    state.counters["csr_of_triad"] = csr_gbps / triad_gbps;
    state.counters["bsr_of_triad"] = bsr_gbps / triad_gbps;
    state.counters["csr_over_bsr"] = median(ratio);
    state.counters["csr_over_bsr_min"] = *std::min_element(ratio.begin(), ratio.end());
    state.counters["csr_over_bsr_max"] = *std::max_element(ratio.begin(), ratio.end());
    state.counters["csr_over_bsr_best"] =
        *std::min_element(t_csr.begin(), t_csr.end()) / *std::min_element(t_bsr.begin(), t_bsr.end());
    state.counters["bsr_of_triad_best"] =
        (bsr.matrix_bytes() + vectors) / *std::min_element(t_bsr.begin(), t_bsr.end()) /
        (24.0 * static_cast<double>(t) / *std::min_element(t_triad.begin(), t_triad.end()));
    state.counters["csr_of_triad_best"] =
        (csr.matrix_bytes() + vectors) / *std::min_element(t_csr.begin(), t_csr.end()) /
        (24.0 * static_cast<double>(t) / *std::min_element(t_triad.begin(), t_triad.end()));
    state.counters["same_y"] = (y_csr - y_bsr).lpNorm<Eigen::Infinity>() == 0.0 ? 1.0 : 0.0;
    state.SetLabel(bsr.format() == cb::AFormat::BSR ? "bsr" : "csr fallback: " + bsr.why_csr());
}

// NOLINTNEXTLINE(readability-identifier-naming): Google Benchmark's BM_<name> convention
void BM_AProductFormats_plane32(benchmark::State& state)
{
    static const cb::Qp qp = cb::make_synthetic("plane", {{"nx", 32}, {"ny", 32}, {"nz", 32}}, 1);
    measure(state, qp);
}
BENCHMARK(BM_AProductFormats_plane32)->UseManualTime()->Iterations(1)->Unit(benchmark::kMillisecond);

/// One benchmark per snapshot of CB_BENCH_SNAPSHOTS, registered before main() runs.
const bool registered = [] {
    const char* list = std::getenv("CB_BENCH_SNAPSHOTS");
    if (list == nullptr) return false;
    std::istringstream in(list);
    std::string path;
    while (std::getline(in, path, ':')) {
        if (path.empty()) continue;
        const std::string name = "BM_AProductFormats/" + std::filesystem::path(path).stem().string();
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
