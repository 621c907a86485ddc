// Timing benchmark (ctest -R MonitorTiming; label `timing`, run serially): a monitored run of every
// solver takes the same solver time as an unmonitored one, within noise, on a stiff snapshot of a few
// thousand DOF where the monitor's work once leaked into `pgs`'s clock (x21.9). A ratio measured in
// one process, min of 7 (or more: at least 1 s of each kind) interleaved runs each after a warm-up; no
// absolute wall-clock bound.
#include "harness/history.hpp"
#include "problems/synthetic.hpp"
#include "solvers/registry.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <iostream>
#include <limits>

namespace cb {
namespace {

constexpr int kSamples = 7;             ///< at least, each kind
constexpr double kMinSampledTime = 1.0;  ///< seconds of each kind: millisecond solves take more samples
constexpr double kMaxRatio = 1.2;

/// A stiff body (E = 1e9 Pa) of 13 x 7 x 13 vertices (n = 3549): on a plane (338 decoupled
/// rows) or, for mprgp-box, under bounds.
Qp stiff_problem(const std::string& solver)
{
    const nlohmann::json params = {{"nx", 12}, {"ny", 6}, {"nz", 12}, {"youngs", 1e9}};
    return make_synthetic(solver == "mprgp-box" ? "box" : "plane", params, 0);
}

/// Solver time (setup + solve, monitor excluded) of one run, with the harness's recording
/// monitor or without any.
double solver_time(const std::string& name, const Qp& qp, bool monitored, SolveStatus& status)
{
    const QpView view = qp.view();
    const AccuracyScale scale = accuracy_scale(view);
    HistoryMonitor history(view, scale, 2000, true);
    SolveContext context;
    context.monitor = monitored ? &history : nullptr;
    const auto solver = builtin_registry().create(name, nlohmann::json::object());
    const SolverResult r = solver->solve(view, context);
    status = r.status;
    return r.setup_s + r.solve_s;
}

TEST(MonitorTiming, MonitoredAndUnmonitoredRunsTakeTheSameTime)
{
    for (const std::string& name : builtin_registry().names()) {
        SCOPED_TRACE(name);
        const Qp qp = stiff_problem(name);
        SolveStatus status_monitored = SolveStatus::NOT_RUN, status_plain = SolveStatus::NOT_RUN;
        // warm-up: caches, allocator, CHOLMOD's first call; it also sizes the sample count
        const double once = solver_time(name, qp, false, status_plain);
        const int samples = std::max(kSamples, static_cast<int>(std::min(200.0, kMinSampledTime / once)));
        double monitored = std::numeric_limits<double>::infinity(), plain = monitored;
        for (int k = 0; k < samples; ++k) {
            monitored = std::min(monitored, solver_time(name, qp, true, status_monitored));
            plain = std::min(plain, solver_time(name, qp, false, status_plain));
        }
        EXPECT_EQ(status_monitored, SolveStatus::CONVERGED);
        EXPECT_EQ(status_plain, status_monitored);
        const double ratio = monitored / plain;
        std::cout << "monitor timing: " << name << " monitored " << monitored << " s, unmonitored " << plain
                  << " s, ratio " << ratio << " (min of " << samples << " each)\n";
        EXPECT_LE(ratio, kMaxRatio) << "monitored " << monitored << " s, unmonitored " << plain << " s";
    }
}

}  // namespace
}  // namespace cb
