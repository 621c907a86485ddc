// Kernel benchmarks (Google Benchmark): a STREAM-like triad (the machine's bandwidth bound),
// one product with A, one Jacobi-PCG iteration and one `mprgp` iteration on the same
// FEM-like A (~108k DOF) with a ground-plane contact J, so that the per-iteration ratio and
// the A-product's distance to the bandwidth bound are measured in one run (DESIGN.md
// "Performance targets").
//   build-*/bin/cb_bench --benchmark_filter='Triad|AProduct|Pcg|Mprgp'
#include "problems/synthetic.hpp"
#include "solvers/core/registry.hpp"
#include "solvers/measure/accuracy.hpp"

#include <benchmark/benchmark.h>

#include <chrono>
#include <cstdio>

namespace {

/// The shared problem: "plane" family on a 32^3 grid of cubes (n = 3 * 33^3 = 107811).
const cb::Qp& problem()
{
    static const cb::Qp qp = cb::make_synthetic("plane", {{"nx", 32}, {"ny", 32}, {"nz", 32}}, 1);
    return qp;
}

/// Bytes one y = A x streams: values (8) + column indices (4) per nonzero, row pointers,
/// x read once (best case: every reuse hits cache) and y written.
double a_product_bytes(const cb::SpMat& A)
{
    return static_cast<double>(A.nonZeros()) * 12.0 + static_cast<double>(A.rows() + 1) * 4.0 +
           static_cast<double>(A.rows()) * 8.0 * 2.0;
}

// NOLINTNEXTLINE(readability-identifier-naming): Google Benchmark's BM_<name> convention
void BM_Triad(benchmark::State& state)
{
    // Arrays well beyond the last-level cache, as large in all as A's bytes (about 100 MB).
    const Eigen::Index n = state.range(0);
    cb::Vec a = cb::Vec::Zero(n), b = cb::Vec::Constant(n, 1.0), c = cb::Vec::Constant(n, 2.0);
    const double s = 3.0;
    for (auto _ : state) {
        double* pa = a.data();
        const double* pb = b.data();
        const double* pc = c.data();
        for (Eigen::Index i = 0; i < n; ++i) pa[i] = pb[i] + s * pc[i];
        benchmark::DoNotOptimize(a.data());
        benchmark::ClobberMemory();
    }
    // STREAM counts 2 reads + 1 write per element (write-allocate traffic not counted).
    state.SetBytesProcessed(static_cast<int64_t>(state.iterations()) * n * 3 * 8);
}
BENCHMARK(BM_Triad)->Arg(1 << 22)->Unit(benchmark::kMillisecond);

/// y = A x with a plain CSR loop (the loop the solvers use).
void csr_product(const cb::SpMat& A, const cb::Vec& x, cb::Vec& y)
{
    const int* outer = A.outerIndexPtr();
    const int* inner = A.innerIndexPtr();
    const double* val = A.valuePtr();
    for (Eigen::Index i = 0; i < A.rows(); ++i) {
        double s = 0.0;
        for (int k = outer[i]; k < outer[i + 1]; ++k) s += val[k] * x[inner[k]];
        y[i] = s;
    }
}

// NOLINTNEXTLINE(readability-identifier-naming): Google Benchmark's BM_<name> convention
void BM_AProduct(benchmark::State& state)
{
    const cb::SpMat& A = problem().A;
    const cb::Vec x = cb::Vec::Ones(A.cols());
    cb::Vec y(A.rows());
    for (auto _ : state) {
        if (state.range(0) == 0)
            csr_product(A, x, y);
        else
            y.noalias() = A * x;  // Eigen's kernel, for comparison
        benchmark::DoNotOptimize(y.data());
        benchmark::ClobberMemory();
    }
    state.SetBytesProcessed(static_cast<int64_t>(static_cast<double>(state.iterations()) * a_product_bytes(A)));
    state.counters["n"] = static_cast<double>(A.rows());
    state.counters["nnz"] = static_cast<double>(A.nonZeros());
    state.counters["bytes_per_product"] = a_product_bytes(A);
    state.SetLabel(state.range(0) == 0 ? "csr loop" : "eigen");
}
BENCHMARK(BM_AProduct)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

/// Jacobi-PCG on A x = b, written with the same fused loops as the `mprgp` CG step
/// (product + p'Ap in one pass; x, r, z and r'z in one pass; p update).
struct Pcg {
    const cb::SpMat& A;
    cb::Vec x, r, z, p, Ap, dinv;
    double rz = 0.0;
    explicit Pcg(const cb::Qp& qp) : A(qp.A) { reset(qp); }
    void reset(const cb::Qp& qp)
    {
        dinv = A.diagonal().cwiseInverse();
        x = qp.x0;
        Ap.resize(x.size());
        csr_product(A, x, Ap);
        r = qp.b - Ap;
        z = dinv.cwiseProduct(r);
        p = z;
        rz = r.dot(z);
    }
    void iterate()
    {
        const int* __restrict outer = A.outerIndexPtr();
        const int* __restrict inner = A.innerIndexPtr();
        const double* __restrict val = A.valuePtr();
        double* __restrict px = x.data();
        double* __restrict pr = r.data();
        double* __restrict pz = z.data();
        double* __restrict pp = p.data();
        double* __restrict pap_v = Ap.data();
        const double* __restrict pd = dinv.data();
        const Eigen::Index n = x.size();
        double pap = 0.0;
        for (Eigen::Index i = 0; i < n; ++i) {
            double s = 0.0;
            for (int k = outer[i]; k < outer[i + 1]; ++k) s += val[k] * pp[inner[k]];
            pap_v[i] = s;
            pap += pp[i] * s;
        }
        const double alpha = rz / pap;
        double rz_new = 0.0;
        for (Eigen::Index j = 0; j < n; ++j) {
            px[j] += alpha * pp[j];
            pr[j] -= alpha * pap_v[j];
            pz[j] = pd[j] * pr[j];
            rz_new += pz[j] * pr[j];
        }
        const double beta = rz_new / rz;
        rz = rz_new;
        for (Eigen::Index j = 0; j < n; ++j) pp[j] = pz[j] + beta * pp[j];
    }
};

constexpr int k_restart = 100;  // PCG restarted every k iterations so values stay normal

// NOLINTNEXTLINE(readability-identifier-naming): Google Benchmark's BM_<name> convention
void BM_PcgIteration(benchmark::State& state)
{
    const cb::Qp& qp = problem();
    Pcg pcg(qp);
    int since_reset = 0;
    for (auto _ : state) {
        if (since_reset == k_restart) {
            state.PauseTiming();
            pcg.reset(qp);
            since_reset = 0;
            state.ResumeTiming();
        }
        pcg.iterate();
        ++since_reset;
        benchmark::DoNotOptimize(pcg.x.data());
    }
    state.SetBytesProcessed(static_cast<int64_t>(static_cast<double>(state.iterations()) * a_product_bytes(qp.A)));
}
BENCHMARK(BM_PcgIteration)->Unit(benchmark::kMillisecond);

/// Seconds per outer iteration of a registered solver: (solve time of k2 iterations - of k1)
/// / (k2 - k1), which removes the start (projection, first gradient) and the final step.
struct PerIteration {
    double seconds = 0.0;
    double products_per_iteration = 0.0;
    double cg_share = 0.0;
};
PerIteration solver_per_iteration(const std::string& name, nlohmann::json settings, long k1, long k2)
{
    const cb::Qp& qp = problem();
    static cb::Vec eigenvector;  // warm power method: setup stays out of the way
    cb::SolveContext context;
    context.eigenvector = &eigenvector;
    settings["tol"] = 1e-15;  // never stop on the criterion inside the measured window
    settings["max_iterations"] = k1;
    const auto short_run = cb::builtin_registry().create(name, settings)->solve(qp.view(), context);
    settings["max_iterations"] = k2;
    const auto long_run = cb::builtin_registry().create(name, settings)->solve(qp.view(), context);
    PerIteration p;
    const double di = static_cast<double>(long_run.iterations - short_run.iterations);
    if (di <= 0) return p;
    p.seconds = (long_run.solve_s - short_run.solve_s) / di;
    const long products_long = long_run.counters.a_products - long_run.counters.power_products;
    const long products_short = short_run.counters.a_products - short_run.counters.power_products;
    p.products_per_iteration = static_cast<double>(products_long - products_short) / di;
    p.cg_share = static_cast<double>(long_run.counters.cg_steps) / static_cast<double>(long_run.iterations);
    return p;
}

// NOLINTNEXTLINE(readability-identifier-naming): Google Benchmark's BM_<name> convention
void BM_MprgpIteration(benchmark::State& state)
{
    PerIteration p;
    for (auto _ : state) {
        p = solver_per_iteration("mprgp", {}, 20, 120);
        state.SetIterationTime(p.seconds);
    }
    state.counters["a_products_per_iteration"] = p.products_per_iteration;
    state.counters["cg_share"] = p.cg_share;
}
BENCHMARK(BM_MprgpIteration)->UseManualTime()->Iterations(3)->Unit(benchmark::kMillisecond);

// NOLINTNEXTLINE(readability-identifier-naming): Google Benchmark's BM_<name> convention
void BM_RegistryCgIteration(benchmark::State& state)
{
    if (!cb::builtin_registry().contains("cg")) {
        state.SkipWithError("solver 'cg' is not registered");
        return;
    }
    PerIteration p;
    for (auto _ : state) {
        p = solver_per_iteration("cg", {{"precond", "jacobi"}}, 20, 120);
        state.SetIterationTime(p.seconds);
    }
    state.counters["a_products_per_iteration"] = p.products_per_iteration;
}
BENCHMARK(BM_RegistryCgIteration)->UseManualTime()->Iterations(3)->Unit(benchmark::kMillisecond);

/// Both in one benchmark: counters mprgp_over_pcg (per-iteration time ratio, target <= 1.15)
/// and aproduct_over_triad_bound (A-product time / (bytes / triad bandwidth), target <= 1.3).
// NOLINTNEXTLINE(readability-identifier-naming): Google Benchmark's BM_<name> convention
void BM_Ratios(benchmark::State& state)
{
    const cb::Qp& qp = problem();
    using clock = std::chrono::steady_clock;
    double ratio = 0.0, bound_ratio = 0.0, pcg_s = 0.0, mprgp_s = 0.0;
    for (auto _ : state) {
        // Interleaved and best-of-3, so that load from other processes hits both alike.
        pcg_s = mprgp_s = 1e300;
        for (int rep = 0; rep < 3; ++rep) {
            Pcg pcg(qp);
            const auto t0 = clock::now();
            for (int k = 0; k < k_restart; ++k) pcg.iterate();
            pcg_s = std::min(pcg_s, std::chrono::duration<double>(clock::now() - t0).count() / k_restart);
            mprgp_s = std::min(mprgp_s, solver_per_iteration("mprgp", {}, 20, 120).seconds);
        }
        ratio = mprgp_s / pcg_s;
        // Triad bandwidth on 3 x 32 MB.
        const Eigen::Index n = 1 << 22;
        cb::Vec a = cb::Vec::Zero(n), b = cb::Vec::Constant(n, 1.0), c = cb::Vec::Constant(n, 2.0);
        double best_triad = 1e300;
        for (int rep = 0; rep < 5; ++rep) {
            const auto s0 = clock::now();
            for (Eigen::Index i = 0; i < n; ++i) a[i] = b[i] + 3.0 * c[i];
            benchmark::DoNotOptimize(a.data());
            best_triad = std::min(best_triad, std::chrono::duration<double>(clock::now() - s0).count());
        }
        const double bandwidth = 3.0 * 8.0 * static_cast<double>(n) / best_triad;
        cb::Vec y(qp.n());
        const cb::Vec x = cb::Vec::Ones(qp.n());
        double best_product = 1e300;
        for (int rep = 0; rep < 10; ++rep) {
            const auto s0 = clock::now();
            csr_product(qp.A, x, y);
            benchmark::DoNotOptimize(y.data());
            best_product = std::min(best_product, std::chrono::duration<double>(clock::now() - s0).count());
        }
        bound_ratio = best_product / (a_product_bytes(qp.A) / bandwidth);
        state.counters["triad_GBps"] = bandwidth * 1e-9;
    }
    state.counters["pcg_ms"] = pcg_s * 1e3;
    state.counters["mprgp_ms"] = mprgp_s * 1e3;
    state.counters["mprgp_over_pcg"] = ratio;
    state.counters["aproduct_over_triad_bound"] = bound_ratio;
}
BENCHMARK(BM_Ratios)->Iterations(1)->Unit(benchmark::kMillisecond);

}  // namespace

// main() is harness/bench/bench_main.cpp (it prints the note on Debian's DEBUG-built library).
