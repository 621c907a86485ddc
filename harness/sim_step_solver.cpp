#include "harness/sim_step_solver.hpp"

#include "harness/runner.hpp"
#include "solvers/core/settings.hpp"

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

ReplacedSolverSettings settings_for_solver(const std::string& scene_solver, const nlohmann::json& scene_settings,
                                           const std::string& solver)
{
    ReplacedSolverSettings out;
    if (solver == scene_solver) {
        out.settings = scene_settings;
        return out;
    }
    const auto stop = scene_settings.find("stop");
    const bool native = stop != scene_settings.end() && stop->is_string() && stop->get<std::string>() == "native";
    for (const auto& item : scene_settings.items()) {
        bool common = false;
        for (const SettingDoc& doc : common_setting_docs()) common = common || doc.key == item.key();
        const bool native_tolerance = native && (item.key() == "stop" || item.key() == "tol");
        if (common && !native_tolerance)
            out.settings[item.key()] = item.value();
        else
            out.dropped.push_back(item.key());
    }
    return out;
}

}  // namespace cb
