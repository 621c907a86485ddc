#pragma once
/// The simulator's step solver built on run_solver (harness/runner.hpp): decoupling, the accuracy
/// error e on the original QP and the run's status are exactly those of `contactbench solve`.
#include "sim/simulator.hpp"

namespace cb {

/// A StepSolver for sim::SimulatorOptions::solve_step (no history recorded).
sim::StepSolver harness_step_solver();

}  // namespace cb
