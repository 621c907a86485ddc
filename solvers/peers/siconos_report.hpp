#pragma once
/// What a peer's child process reports (Siconos's, and Bullet's in the same shape), and the one
/// rule that turns it into a result: the status is the accuracy measure's verdict at the returned
/// point (docs/accuracy.md), the library's own word goes into the message.
#include "solvers/core/solve_loop.hpp"
#include "solvers/core/solver.hpp"

#include <string>

namespace cb {

/// Written by the child after its numbers (plain data: copied through the pipe).
struct SiconosReport {
    int info = -1;       ///< the library's return code (0: solved)
    int iterations = 0;  ///< pivots or Newton iterations
    double residual = 0.0;
    bool max_iterations_reached = false;  ///< the library stopped at the iteration cap it was given
    /// Lemke ended on a ray (its pivot column is nonpositive): Jx >= c may have no solution, or the
    /// pivoting lost accuracy on a singular W (seen on a feasible problem with duplicate rows).
    bool ray_termination = false;
};

/// The one verdict of a peer that reports in this shape: fills result.iterations,
/// native_residual and info, calls the monitor once at the returned point (through the loop, on
/// its paused clock), then lets the loop judge (result.x, result.lambda): non-finite -> DIVERGED,
/// the stop rule (stop=native: the library said solved and its residual <= tol) -> CONVERGED, the
/// library at its own cap -> MAX_ITERATIONS, else STALLED. `what` names the method ("Siconos
/// Lemke"), `steps` its iterations ("pivots"); `extra` is appended to the message. Returns the
/// finished result.
SolverResult finish_siconos_result(const QpView& qp, SolveLoop& loop, const SiconosReport& report,
                                   const std::string& what, const std::string& steps, Counters& counters,
                                   SolverResult& result, const std::string& extra = "");

}  // namespace cb
