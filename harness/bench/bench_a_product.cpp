// Issue 47's A-product figures on one thread: the product with A read from CSR (Eigen's
// compressed rows), from 3x3 blocks (BSR) and from the upper block triangle (SBSR), beside a
// STREAM-like triad, alternating repetition by repetition in one benchmark iteration
// (harness/bench/alternating.hpp), on the thread's CPU clock. On the snapshots of
// CB_BENCH_SNAPSHOTS and on the kernels' synthetic 32^3 plane. Counters per format <f>: bytes per
// nonzero (A's storage only), ns per nonzero, GB/s (A's storage + x read once + y written), the
// fraction of the triad's GB/s (median times; _best: best times), the median time and the spread
// (max / min); csr_over_<f> is the median of the per-repetition time ratios CSR / <f>, with its
// min and max. same_y_bsr = 1 when BSR's y equals CSR's bit for bit (bsr_simd = 1: the AVX2 kernel); sbsr_y_err the
// largest |y_sbsr - y_csr| / (|A||x|) over the rows (rounding: SBSR sums in another order).
//   CB_BENCH_SNAPSHOTS=a.qpsnap:b.qpsnap build/bin/cb_bench --benchmark_filter=AProductFormats
#include "harness/bench/alternating.hpp"
#include "problems/synthetic.hpp"
#include "solvers/linalg/a_product.hpp"

#include <benchmark/benchmark.h>

#include <string>
#include <vector>

namespace {

using namespace cb::bench;

void measure_formats(benchmark::State& state, const cb::Qp& qp)
{
    const cb::SpMat& A = qp.A;
    const Eigen::Index n = A.rows();
    cb::AOperator csr(A), bsr(A), sbsr(A);
    csr.prepare(cb::AFormat::CSR);
    const double t0 = now_s(Clock::THREAD_CPU);
    bsr.prepare(cb::AFormat::BSR);
    const double t1 = now_s(Clock::THREAD_CPU);
    sbsr.prepare(cb::AFormat::SBSR);
    const double t2 = now_s(Clock::THREAD_CPU);
    const cb::Vec x = cb::Vec::LinSpaced(n, -1.0, 1.0);
    cb::Vec y_csr(n), y_bsr(n), y_sbsr(n);
    const std::ptrdiff_t t = triad_length(csr.matrix_bytes());
    cb::Vec a = triad_array(t, 0.0), b = triad_array(t, 1.0), c = triad_array(t, 2.0);
    std::vector<std::vector<double>> times;
    for (auto _ : state) {
        times = alternate({[&] {
                               triad(a.data(), b.data(), c.data(), 0, t);
                               benchmark::DoNotOptimize(a.data());
                           },
                           [&] {
                               cb::a_product(csr, x, y_csr);
                               benchmark::DoNotOptimize(y_csr.data());
                           },
                           [&] {
                               cb::a_product(bsr, x, y_bsr);
                               benchmark::DoNotOptimize(y_bsr.data());
                           },
                           [&] {
                               cb::a_product(sbsr, x, y_sbsr);
                               benchmark::DoNotOptimize(y_sbsr.data());
                           }},
                          Clock::THREAD_CPU);
        state.SetIterationTime(median(times[1]) + median(times[2]) + median(times[3]));
    }
    const double nnz = static_cast<double>(A.nonZeros());
    const double vectors = 16.0 * static_cast<double>(n);  // x read once, y written
    const std::vector<double>& t_triad = times[0];
    const double triad_gbps = 24.0 * static_cast<double>(t) / median(t_triad) * 1e-9;
    const double triad_gbps_best = 24.0 * static_cast<double>(t) / best(t_triad) * 1e-9;
    state.counters["n"] = static_cast<double>(n);
    state.counters["nnz"] = nnz;
    state.counters["triad_GBps"] = triad_gbps;
    state.counters["triad_spread"] = spread(t_triad);
    state.counters["bsr_build_ms"] = 1e3 * (t1 - t0);
    state.counters["sbsr_build_ms"] = 1e3 * (t2 - t1);
    const std::vector<std::pair<std::string, const cb::AOperator*>> formats{
        {"csr", &csr}, {"bsr", &bsr}, {"sbsr", &sbsr}};
    for (size_t f = 0; f < formats.size(); ++f) {
        const std::string& name = formats[f].first;
        const cb::AOperator& op = *formats[f].second;
        const std::vector<double>& tf = times[f + 1];
        const double bytes = op.matrix_bytes() + vectors;
        state.counters[name + "_format"] = static_cast<double>(op.format());  // 0 CSR, 1 BSR, 2 SBSR
        state.counters[name + "_bytes_per_nz"] = op.matrix_bytes() / nnz;
        state.counters[name + "_ns_per_nz"] = 1e9 * median(tf) / nnz;
        state.counters[name + "_ms"] = 1e3 * median(tf);
        state.counters[name + "_spread"] = spread(tf);
        state.counters[name + "_GBps"] = bytes / median(tf) * 1e-9;
        state.counters[name + "_of_triad"] = bytes / median(tf) * 1e-9 / triad_gbps;
        state.counters[name + "_of_triad_best"] = bytes / best(tf) * 1e-9 / triad_gbps_best;
        if (f == 0) continue;
        const std::vector<double> r = ratios(times[1], tf);
        state.counters["csr_over_" + name] = median(r);
        state.counters["csr_over_" + name + "_min"] = *std::min_element(r.begin(), r.end());
        state.counters["csr_over_" + name + "_max"] = *std::max_element(r.begin(), r.end());
        state.counters["csr_over_" + name + "_best"] = best(times[1]) / best(tf);
    }
    state.counters["same_y_bsr"] = (y_csr - y_bsr).lpNorm<Eigen::Infinity>() == 0.0 ? 1.0 : 0.0;
    state.counters["bsr_simd"] = cb::block_kernel_is_simd() ? 1.0 : 0.0;  // 1: the AVX2 kernel ran
    const cb::Vec size = A.cwiseAbs() * x.cwiseAbs();
    double err = 0.0;
    for (Eigen::Index i = 0; i < n; ++i)
        if (size[i] > 0.0) err = std::max(err, std::abs(y_sbsr[i] - y_csr[i]) / size[i]);
    state.counters["sbsr_y_err"] = err;
    state.SetLabel((bsr.format() == cb::AFormat::BSR ? std::string("bsr") : "bsr fallback: " + bsr.why_csr()) +
                   (sbsr.format() == cb::AFormat::SBSR ? ", sbsr" : ", sbsr fallback: " + sbsr.why_csr()));
}

// NOLINTNEXTLINE(readability-identifier-naming): Google Benchmark's BM_<name> convention
void BM_AProductFormats_plane32(benchmark::State& state)
{
    static const cb::Qp qp = cb::make_synthetic("plane", {{"nx", 32}, {"ny", 32}, {"nz", 32}}, 1);
    measure_formats(state, qp);
}
BENCHMARK(BM_AProductFormats_plane32)->UseManualTime()->Iterations(1)->Unit(benchmark::kMillisecond);

const bool formats_registered = register_per_snapshot("BM_AProductFormats", measure_formats);

}  // namespace
