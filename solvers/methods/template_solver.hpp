#pragma once
/// `template`: a model solver to copy when adding one (README "Adding a solver"). It is small on
/// purpose — projected gradient descent for bound rows — but complete: strict settings declared
/// once in a SettingsTable, the common stop rules, the solve-loop protocol (solvers/core/solve_loop.hpp:
/// one clock from the start of setup, the time limit on setup + solve, the exit checks in one
/// order, the monitor on a paused clock, one finisher), counters, an honest status and multipliers.
/// It is compiled and tested (tests/solvers/test_template_solver.cpp) but not registered in
/// builtin_solvers.cpp, so that suites, the stress table and `contactbench solvers` list only
/// real contenders; the test registers it in a registry of its own, exactly as step 2 of the
/// recipe does.
///
/// Algorithm: x <- P(x - t g) with g = Ax - b, P the clamp onto the bounds, and the fixed step
/// t = step_scale / |A|_inf (|A|_2 <= |A|_inf for symmetric A, so t < 2 / |A|_2 decreases F).
/// Accepts a J whose every row has at most one nonzero: a x_j >= c is x_j >= c/a when a > 0 and
/// x_j <= c/a when a < 0 (solvers/mprgp/bounds.hpp, shared with `mprgp-box` and `tao-tron`); any other J is
/// not_applicable, rows that contradict are infeasible.
#include "solvers/core/registry.hpp"
#include "solvers/core/settings.hpp"
#include "solvers/core/solver.hpp"

#include <string>
#include <vector>

namespace cb {

/// Every setting with its default (the table in template_solver.cpp adds key, bounds and doc);
/// `from_json` checks them, `to_json` records the effective values.
struct TemplateSettings {
    CommonSettings common;    ///< tol, stop, max_iterations, time_limit_s, seed
    double step_scale = 1.0;  ///< step t = step_scale / |A|_inf, in (0, 2)

    static TemplateSettings from_json(const nlohmann::json& settings);  ///< throws InputError
    nlohmann::json to_json() const;
};

class TemplateSolver final : public Solver {
public:
    explicit TemplateSolver(const TemplateSettings& settings) : m_settings(settings) {}
    std::string name() const override { return "template"; }
    nlohmann::json settings() const override { return m_settings.to_json(); }
    SolverResult solve(const QpView& qp, const SolveContext& context) override;

private:
    TemplateSettings m_settings;
};

/// Registry entry: factory, one-line description, setting docs, applicability.
SolverEntry template_entry();

}  // namespace cb
