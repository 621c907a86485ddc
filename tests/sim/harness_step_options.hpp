#pragma once
/// Simulator options with the harness's step solver (the simulator needs one).
#include "harness/sim_step_solver.hpp"
#include "sim/simulator.hpp"

namespace cb::test {

inline sim::SimulatorOptions harness_step_options()
{
    sim::SimulatorOptions opt;
    opt.solve_step = harness_step_solver();
    return opt;
}

}  // namespace cb::test
