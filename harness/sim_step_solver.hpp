#pragma once
/// The simulator's step solver built on run_solver (harness/runner.hpp): decoupling, the accuracy
/// error e on the original QP and the run's status are exactly those of `contactbench solve`.
#include "sim/simulator.hpp"

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace cb {

/// A StepSolver for sim::SimulatorOptions::solve_step (no history recorded).
sim::StepSolver harness_step_solver();

/// The settings of a stepping solver that replaces the scene's (`simulate --solver NAME`).
struct ReplacedSolverSettings {
    nlohmann::json settings = nlohmann::json::object();
    std::vector<std::string> dropped;  ///< the scene's keys not passed on (in key order)
};

/// The scene's settings when `solver` is the scene's own; otherwise `solver`'s defaults plus the
/// scene's common settings (max_iterations, time_limit_s, seed, and tol and stop when stop is kkt).
/// A native stop is dropped with its tol: a native residual is each solver's own, in its own units,
/// so the scene solver's tolerance means nothing to another solver (which then stops on e).
ReplacedSolverSettings settings_for_solver(const std::string& scene_solver, const nlohmann::json& scene_settings,
                                           const std::string& solver);

}  // namespace cb
