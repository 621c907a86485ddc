// Issue 47's "part of an iteration outside its A-products": decoupled `mprgp` (the authors' row
// order) and `mprgp-coupled`, registry defaults, on each snapshot of CB_BENCH_SNAPSHOTS. A monitor
// reads the thread's CPU clock and the A-product counter at the first and the last iteration;
// then the fused product-with-dots on the solvers' storage (`a_format = auto` as the solvers: SBSR
// on one thread from 1M nonzeros, else BSR; `threads` as the solvers) is timed
// alone (harness/bench/alternating.hpp). outside_<s> = 1 - products x product time / iteration
// time: the share of an iteration spent in vector passes, projections and the stop test.
// CB_BENCH_SOLVES (default 3) rounds of both solves, each solve followed by its product's timing:
// one solve moves with the machine's memory by 10-20%, so the counters are medians over the rounds,
// with outside_<s>_low / _high their extremes.
// CB_BENCH_THREADS (default 1) sets the solvers' and the product's `threads` (then wall clock:
// a threaded product's CPU time is summed over its threads).
//   CB_BENCH_SNAPSHOTS=a.qpsnap:b.qpsnap build/bin/cb_bench --benchmark_filter=IterationShare
#include "harness/bench/alternating.hpp"
#include "solvers/core/registry.hpp"
#include "solvers/linalg/a_product.hpp"
#include "solvers/mprgp/decouple.hpp"

#include <benchmark/benchmark.h>

#include <algorithm>
#include <cstdlib>
#include <map>
#include <string>
#include <vector>

namespace {

using namespace cb::bench;

int threads()
{
    const char* env = std::getenv("CB_BENCH_THREADS");
    return std::max(1, env ? std::atoi(env) : 1);
}

Clock clock_for_threads() { return threads() > 1 ? Clock::WALL : Clock::THREAD_CPU; }

int solve_rounds()
{
    const char* env = std::getenv("CB_BENCH_SOLVES");
    return std::max(1, env ? std::atoi(env) : 3);
}

/// One solver's figures over the rounds: seconds an iteration, a product's seconds alone, the share.
struct ShareRounds {
    std::vector<double> per_iteration, product, outside;
    double iterations = 0.0, products_per_iteration = 0.0, product_spread = 0.0;
};

/// Clock and A-product count at the first and the last outer iteration.
class ShareMonitor : public cb::Monitor {
public:
    bool on_iteration(const cb::IterationInfo& info) override
    {
        const double now = now_s(clock_for_threads());
        const long products = cb::a_product_count();
        if (m_calls++ == 0) {
            m_first = now;
            m_first_products = products;
            m_first_iteration = info.iteration;
        }
        m_last = now;
        m_last_products = products;
        m_last_iteration = info.iteration;
        return true;
    }
    bool wants_iterate() const override { return false; }
    long iterations() const { return m_last_iteration - m_first_iteration; }
    long products() const { return m_last_products - m_first_products; }
    double seconds() const { return m_last - m_first; }

private:
    long m_calls = 0, m_first_iteration = 0, m_last_iteration = 0, m_first_products = 0, m_last_products = 0;
    double m_first = 0.0, m_last = 0.0;
};

void measure_share(benchmark::State& state, const cb::Qp& qp)
{
    const cb::DecoupleReport report = cb::decouple_rows(qp.view(), qp.contacts, cb::DecoupleOrder::AUTHORS, 0);
    const cb::Qp decoupled = cb::select_rows(qp, report.kept_rows);
    const nlohmann::json settings = {{"threads", threads()}};
    cb::AOperator op(qp.A);
    op.prepare(cb::AFormat::AUTO, threads());
    const cb::Vec x = cb::Vec::LinSpaced(qp.n(), -1.0, 1.0), w = cb::Vec::Constant(qp.n(), 0.5);
    cb::Vec y(qp.n());
    for (auto _ : state) {
        std::map<std::string, ShareRounds> by_key;
        for (int round = 0; round < solve_rounds(); ++round)
            for (const std::string& name : {std::string("mprgp"), std::string("mprgp-coupled")}) {
                const auto solver = cb::builtin_registry().create(name, settings);
                ShareMonitor monitor;
                cb::SolveContext context;
                context.monitor = &monitor;
                const cb::SolverResult r = solver->solve(name == "mprgp" ? decoupled.view() : qp.view(), context);
                const std::vector<std::vector<double>> t =
                    alternate({[&] {
                                  double xw = 0.0;
                                  benchmark::DoNotOptimize(cb::a_product_dots(op, x, y, w, xw));
                              }},
                              clock_for_threads());
                ShareRounds& k = by_key[name == "mprgp" ? "mprgp" : "coupled"];
                const double iterations = static_cast<double>(std::max(1L, monitor.iterations()));
                const double per_it = monitor.seconds() / iterations;
                k.iterations = static_cast<double>(r.counters.iterations);
                k.products_per_iteration = static_cast<double>(monitor.products()) / iterations;
                k.per_iteration.push_back(per_it);
                k.product.push_back(median(t[0]));
                k.product_spread = std::max(k.product_spread, spread(t[0]));
                k.outside.push_back(1.0 - k.products_per_iteration * median(t[0]) / per_it);
            }
        double total = 0.0;
        for (const auto& [key, k] : by_key) {
            state.counters[key + "_it"] = k.iterations;
            state.counters[key + "_ms_per_it"] = 1e3 * median(k.per_iteration);
            state.counters[key + "_products_per_it"] = k.products_per_iteration;
            state.counters[key + "_product_ms"] = 1e3 * median(k.product);
            state.counters[key + "_product_spread"] = k.product_spread;
            state.counters["outside_" + key] = median(k.outside);
            state.counters["outside_" + key + "_low"] = *std::min_element(k.outside.begin(), k.outside.end());
            state.counters["outside_" + key + "_high"] = *std::max_element(k.outside.begin(), k.outside.end());
            total += median(k.per_iteration);
        }
        state.SetIterationTime(total);
    }
    state.counters["threads"] = threads();
    state.counters["n"] = static_cast<double>(qp.n());
    state.SetLabel(op.format() == cb::AFormat::CSR ? "csr fallback: " + op.why_csr() : cb::to_string(op.format()));
}

const bool share_registered = register_per_snapshot("BM_IterationShare", measure_share);

}  // namespace
