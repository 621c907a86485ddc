#pragma once
/// `tao-pdipm`: an external peer, PETSc TAO's primal-dual interior point method (TAOPDIPM) on the
/// primal QP
///   minimize 1/2 x'Ax - b'x  subject to  Jx - c >= 0   (any J),
/// with A as the (constant) Hessian and J as the inequality Jacobian, both sequential AIJ.
/// Compiled only when pkg-config finds `petsc` (option CB_PEERS); see docs/peers.md.
/// Fixed options: variable bounds -inf/+inf are set (TAOPDIPM dereferences them and segfaults
/// without), and the KKT systems are solved directly (`-ksp_type preonly -pc_type lu`, MUMPS when
/// PETSc has it): the default GMRES + ILU fails on stiff problems.
/// Settings: tol -> TAO's gatol and catol = 1e-2 * tol (stop=native: = tol); if TAO says converged
/// at a point the harness's KKT test rejects, the child re-solves once with them / 1e3.
/// max_iterations -> TaoSetMaximumIterations. TAO runs in a forked child process (PETSc and MPI
/// are initialised there, once per solve), so time_limit_s ends the child (status `time_limit`)
/// and a crash is status `diverged` with info.crashed = true. TAO's converged reason goes to the
/// message; the status is the harness's accuracy verdict. Final point only (no history).
#include "solvers/core/registry.hpp"
#include "solvers/core/solver.hpp"

namespace cb {

struct TaoPdipmSettings {
    CommonSettings common;

    static TaoPdipmSettings from_json(const nlohmann::json& settings);  ///< throws InputError
    nlohmann::json to_json() const;
};

class TaoPdipmSolver : public Solver {
public:
    explicit TaoPdipmSolver(const TaoPdipmSettings& settings) : m_settings(settings) {}
    std::string name() const override { return "tao-pdipm"; }
    nlohmann::json settings() const override { return m_settings.to_json(); }
    SolverResult solve(const QpView& qp, const SolveContext& context) override;

private:
    TaoPdipmSettings m_settings;
};

SolverEntry tao_pdipm_entry();

}  // namespace cb
