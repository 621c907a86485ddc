#include "harness/sim_step_solver.hpp"

#include "harness/runner.hpp"

namespace cb {

sim::StepSolver harness_step_solver()
{
    return [](const sim::StepSolveRequest& request) {
        RunOptions options;
        options.record_history = false;
        options.decouple = request.decouple;
        options.decouple_seed = request.decouple_seed;
        SolveContext warm;
        warm.eigenvector = request.eigenvector;
        RunOutcome run = run_solver(*request.qp, request.solver, request.settings, options, {}, warm);
        sim::StepSolveOutcome out;
        out.x = std::move(run.result.x);
        out.status = run.status;
        out.solver_status = to_string(run.result.status);
        out.iterations = run.result.iterations;
        out.accuracy = run.accuracy.max();
        out.accuracy_solved = run.accuracy_solved.max();
        out.rows_solved = run.m_solved;
        out.solve_s = run.result.setup_s + run.result.solve_s;
        return out;
    };
}

}  // namespace cb
