#pragma once
/// `ipopt`: an external peer, COIN-OR Ipopt (interior point, MUMPS inside) on the primal QP
///   minimize 1/2 x'Ax - b'x  subject to  Jx >= c   (any J; no variable bounds).
/// Compiled only when CMake finds pkg-config `ipopt` (option CB_PEERS); see docs/peers.md.
///
/// Settings map onto Ipopt's own options as follows (the mapping is recorded in result.info):
///   tol            -> stop=kkt: the harness's relative KKT error is tested on Ipopt's iterate in
///                     its intermediate callback, which ends the solve when it holds; Ipopt's own
///                     `tol` is set to 1e-2 * tol so that Ipopt does not stop first; if Ipopt still
///                     declares success at a point the KKT test rejects, it re-solves with its tol
///                     / 1e3 (at most twice).
///                     stop=native: Ipopt's `tol` (its scaled NLP error) = tol.
///   max_iterations -> `max_iter`;  time_limit_s -> wall clock checked in the callback (Ipopt 3.11's
///                     `max_cpu_time` counts CPU, not wall time, so it is only a backstop).
/// Fixed options: `bound_relax_factor 0` (otherwise Ipopt relaxes Jx >= c and leaves a ~1e-8
/// violation at any tolerance), `hessian_constant`, `jac_d_constant` (the QP is linear-quadratic).
/// Ipopt's own verdict ("Solve_Succeeded", ...) goes to result.message and info.ipopt_status; the
/// status is CONVERGED only when the common KKT test holds at the returned point.
/// Ipopt is run in-process: it reports failures through return codes and did not crash on the
/// CI and stress problems, so no child process is used.
#include "solvers/core/registry.hpp"
#include "solvers/core/solver.hpp"

namespace cb {

struct IpoptSettings {
    CommonSettings common;
    std::string nlp_scaling = "gradient-based";  ///< Ipopt's nlp_scaling_method
    long print_level = 0;                        ///< Ipopt's print_level (0: silent)

    static IpoptSettings from_json(const nlohmann::json& settings);  ///< throws InputError
    nlohmann::json to_json() const;
};

class IpoptSolver : public Solver {
public:
    explicit IpoptSolver(IpoptSettings settings) : m_settings(std::move(settings)) {}
    std::string name() const override { return "ipopt"; }
    nlohmann::json settings() const override { return m_settings.to_json(); }
    SolverResult solve(const QpView& qp, const SolveContext& context) override;

private:
    IpoptSettings m_settings;
};

SolverEntry ipopt_entry();

/// The library version compiled against (e.g. "3.11.9").
std::string ipopt_version();

}  // namespace cb
