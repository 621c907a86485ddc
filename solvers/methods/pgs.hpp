#pragma once
/// `pgs`: projected Gauss-Seidel on the exact dual of the contact QP (ALGORITHMS.md §7).
/// Ref: Li et al., "Deformable Objects Collision Handling with Fast Convergence", CGF 2015, eq. (2).
///
/// Dual:  min 1/2 lambda' S lambda - lambda' q,  lambda >= 0,  S = J A^-1 J',  q = c - J A^-1 b.
/// A is factored once with CHOLMOD; S is formed column by column (m solves, in blocks of
/// right-hand sides), so the solver answers NOT_APPLICABLE for problems with more than `max_rows`
/// rows (default 2000: S is dense, m^2 doubles). One iteration = one ascending sweep
///   lambda_i = max(0, lambda_i - (S lambda - q)_i / S_ii),
/// and the primal point is x = A^-1 (b + J' lambda) (exact stationarity up to the solve's error).
/// Rows with S_ii = 0 (zero rows of J) keep lambda_i = 0; one with c_i > 0 makes the problem
/// infeasible (status INFEASIBLE).
///
/// Stop rules: stop=native: the LCP natural residual ||min(lambda, S lambda - q)||_inf <= tol
/// (absolute, constraint units), which is zero exactly at a solution; stop=kkt (default): the
/// accuracy error e (docs/accuracy.md), evaluated in dual space (J x - c = S lambda - q) at every sweep and
/// confirmed at the primal x before "converged" is returned.
#include "solvers/core/registry.hpp"
#include "solvers/core/solver.hpp"

namespace cb {

struct PgsSettings {
    CommonSettings common;
    long max_rows = 2000;  ///< refuse problems with m > max_rows (S is a dense m x m matrix)
    long block = 64;       ///< right-hand sides per CHOLMOD solve when forming S

    static PgsSettings from_json(const nlohmann::json& settings);  ///< throws InputError
    nlohmann::json to_json() const;
};

class PgsSolver : public Solver {
public:
    explicit PgsSolver(PgsSettings settings) : m_settings(settings) {}
    std::string name() const override { return "pgs"; }
    nlohmann::json settings() const override { return m_settings.to_json(); }
    SolverResult solve(const QpView& qp, const SolveContext& context) override;

private:
    PgsSettings m_settings;
};

SolverEntry pgs_entry();

}  // namespace cb
