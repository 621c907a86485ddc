#pragma once
/// What the Siconos frictional peers (siconos_fc3d: local problem, siconos_gfc3d: global problem)
/// share: one driver call (fc3d_driver or gfc3d_driver) in a forked child process with Siconos'
/// options for a solver id, its arrays and its report sent back, and the reading of a child that
/// did not answer in full. Each peer keeps its own problem struct and its verdict.
#include <functional>
#include <string>
#include <vector>

struct SolverOptions;  // Siconos numerics' (SolverOptions.h)

namespace cb {

/// What to install when a Siconos peer is not built (the stubs' messages).
const char* siconos_install_hint();

/// One driver call's outcome in the parent.
struct SiconosDriverRun {
    std::vector<double> values;  ///< the driver's arrays as it left them (r, or r then v); empty when it failed
    int info = -1;               ///< the driver's return code (0: solved)
    int iterations = 0;          ///< SICONOS_IPARAM_ITER_DONE
    double residual = -1.0;      ///< SICONOS_DPARAM_RESIDU: Siconos' own error
    std::string status;          ///< empty when the child answered in full, else "time_limit" or "diverged"
    std::string failure;         ///< why not (status set): "killed at the time limit", "Siconos child ..."
    double seconds = 0.0;        ///< the child's wall time
};

/// Runs `driver` in a child with Siconos' options for `solver_id` (iteration cap max_iterations, at most 2^30;
/// tolerance tol); `driver` gets the options and `values` doubles to fill, and returns the driver's info. The child
/// is killed at time_limit_s (0: none). Compiled without Siconos: throws InputError.
SiconosDriverRun run_siconos_driver(
    int solver_id, long max_iterations, double tol, double time_limit_s, size_t values,
    const std::function<int(SolverOptions* options, std::vector<double>& values)>& driver);

}  // namespace cb
