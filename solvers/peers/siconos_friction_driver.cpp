// One Siconos frictional driver call in a child process (see siconos_friction_driver.hpp).
#include "solvers/peers/siconos_friction_driver.hpp"

#include "solvers/core/types.hpp"

#ifdef CB_HAVE_SICONOS
#include "solvers/core/stopwatch.hpp"
#include "solvers/peers/child_process.hpp"

#include <SolverOptions.h>

#include <algorithm>
#include <cstring>
#endif

namespace cb {

const char* siconos_install_hint() { return "install libsiconos-numerics-dev and reconfigure with CB_PEERS=ON"; }

#ifndef CB_HAVE_SICONOS

SiconosDriverRun run_siconos_driver(int, long, double, double, size_t,
                                    const std::function<int(SolverOptions*, std::vector<double>&)>&)
{
    throw InputError(std::string("Siconos numerics is not built (") + siconos_install_hint() + ")");
}

#else

namespace {

/// Written by the child after the values (plain data: copied through the pipe).
struct DriverReport {
    int info = -1;
    int iterations = 0;
    double residual = -1.0;
};

}  // namespace

SiconosDriverRun run_siconos_driver(int solver_id, long max_iterations, double tol, double time_limit_s, size_t values,
                                    const std::function<int(SolverOptions*, std::vector<double>&)>& driver)
{
    SiconosDriverRun run;
    Stopwatch watch;
    watch.start();
    const size_t expected = values * sizeof(double) + sizeof(DriverReport);
    const ChildOutcome child = run_in_child(
        [&]() {
            std::vector<double> numbers(values, 0.0);
            SolverOptions* options = solver_options_create(solver_id);
            options->iparam[SICONOS_IPARAM_MAX_ITER] = static_cast<int>(std::min<long>(max_iterations, 1L << 30));
            options->dparam[SICONOS_DPARAM_TOL] = tol;
            DriverReport report;
            report.info = driver(options, numbers);
            report.iterations = options->iparam[SICONOS_IPARAM_ITER_DONE];
            report.residual = options->dparam[SICONOS_DPARAM_RESIDU];
            std::vector<char> bytes(expected);
            std::memcpy(bytes.data(), numbers.data(), values * sizeof(double));
            std::memcpy(bytes.data() + values * sizeof(double), &report, sizeof report);
            return bytes;  // the child exits without freeing: Siconos' options may hold its workspaces
        },
        watch, time_limit_s);
    watch.pause();
    run.seconds = watch.seconds();
    if (child.timed_out || child.failed || child.bytes.size() != expected) {
        run.status = child.timed_out ? "time_limit" : "diverged";
        run.failure = child.timed_out
                          ? "killed at the time limit"
                          : "Siconos child " + (child.failed ? child.failure
                                                             : "sent " + std::to_string(child.bytes.size()) +
                                                                   " bytes, expected " + std::to_string(expected));
        return run;
    }
    run.values.resize(values);
    std::memcpy(run.values.data(), child.bytes.data(), values * sizeof(double));
    DriverReport report;
    std::memcpy(&report, child.bytes.data() + values * sizeof(double), sizeof report);
    run.info = report.info;
    run.iterations = report.iterations;
    run.residual = report.residual;
    return run;
}

#endif

}  // namespace cb
