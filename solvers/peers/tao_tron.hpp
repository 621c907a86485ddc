#pragma once
/// `tao-tron`: an external peer, PETSc TAO's TRON (Lin and More's Newton trust region method for
/// bound constraints, TAOTRON) on the QP whose rows are bounds: every row of J has one nonzero a,
/// a x_j >= c is x_j >= c/a (a > 0) or x_j <= c/a (a < 0), as for mprgp-box. A problem with a
/// row of two or more nonzeros is `not_applicable`; contradictory bounds or a zero row with c > 0
/// are `infeasible` (before PETSc is started). TRON has no multipliers for the rows: lambda is read
/// off the gradient at its point (g_j / a on the binding row of DOF j, 0 elsewhere).
/// Settings: tol -> TAO's gatol = 1e-2 * tol (stop=native: = tol); if TAO says converged at a point
/// the harness's KKT test rejects, the child re-solves once with gatol / 1e3. max_iterations ->
/// TaoSetMaximumIterations. TRON runs in a forked child process as tao-pdipm does, so
/// time_limit_s ends the child (status `time_limit`) and a crash is status `diverged` with
/// info.crashed = true. Final point only (no history). See docs/peers.md.
#include "solvers/core/registry.hpp"
#include "solvers/core/solver.hpp"

namespace cb {

struct TaoTronSettings {
    CommonSettings common;

    static TaoTronSettings from_json(const nlohmann::json& settings);  ///< throws InputError
    nlohmann::json to_json() const;
};

class TaoTronSolver : public Solver {
public:
    explicit TaoTronSolver(const TaoTronSettings& settings) : m_settings(settings) {}
    std::string name() const override { return "tao-tron"; }
    nlohmann::json settings() const override { return m_settings.to_json(); }
    SolverResult solve(const QpView& qp, const SolveContext& context) override;

private:
    TaoTronSettings m_settings;
};

SolverEntry tao_tron_entry();

}  // namespace cb
