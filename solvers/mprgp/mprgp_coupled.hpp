#pragma once
/// `mprgp-coupled`: the extended MPRGP with a general J (no decoupling; ALGORITHMS.md §4).
/// The free gradient, chopped gradient and projection are small subproblems, one per component
/// of J's row graph (solvers/mprgp/coupled_face_operators.hpp): dense Cholesky factors kept per face,
/// LCPs by block principal pivoting (warm-started) with a projected Gauss-Seidel fallback;
/// `operators=global` keeps the single CHOLMOD problem over all rows. Dependent rows
/// (duplicates, parallel rows) are handled by a shift 1e-12 of the Gram matrices scaled to unit
/// diagonal. F(P(y)) is formed in difference form (one A-product per CG step, as `mprgp`).
/// Alg. 3's safeguards are on.
/// Ref: Li et al., CGF 2015, eq. (15)-(20), Alg. 3, Appendix A.
#include "solvers/core/registry.hpp"
#include "solvers/core/settings.hpp"
#include "solvers/core/solver.hpp"

#include <string>
#include <vector>

namespace cb {

struct MprgpCoupledSettings {
    CommonSettings common;
    double gamma = 1.0;                    ///< proportioning constant Gamma (> 0)
    std::string precond = "auto";          ///< auto (scaled or jacobi) | jacobi | scaled | none (Fig. 6) | ichol
    std::string deflation = "none";        ///< none | rigid (coupled_preconditioner.hpp); rigid with ichol
    long power_max = 100;                  ///< max power-method products
    long lcp_max_pivots = 200;             ///< block-principal-pivoting iterations before the PGS fallback
    long pgs_max_sweeps = 10000;           ///< PGS fallback sweeps
    long safeguard_max = 100;              ///< max repeats of Alg. 3's safeguard after one step
    std::string operators = "components";  ///< components (per row-graph component) | global (one CHOLMOD problem)
    long dense_max_rows = 128;  ///< largest component with dense factors (larger: CHOLMOD; measured crossover 100-200)
    long sparse_max_updates = 64;  ///< larger set changes of a large component refactor (fewer: row updates)
    std::string expansion_projection = "face";  ///< face (the face rows stay equalities) | all (P of Alg. 1)

    static MprgpCoupledSettings from_json(const nlohmann::json& settings);
    nlohmann::json to_json() const;
};

class MprgpCoupledSolver final : public Solver {
public:
    explicit MprgpCoupledSolver(MprgpCoupledSettings settings) : m_settings(std::move(settings)) {}
    std::string name() const override { return "mprgp-coupled"; }
    nlohmann::json settings() const override { return m_settings.to_json(); }
    SolverResult solve(const QpView& qp, const SolveContext& context) override;

private:
    MprgpCoupledSettings m_settings;
};

SolverEntry mprgp_coupled_entry();

/// The same solve for a solver that runs mprgp-coupled as one of its stages: not through a
/// `Solver::solve`, whose entries the instruction counts toggle on (tools/perf_gate.py TOGGLES),
/// so that a nested stage does not switch the count off.
SolverResult mprgp_coupled_solve(const QpView& qp, const MprgpCoupledSettings& settings, const SolveContext& context);

}  // namespace cb
