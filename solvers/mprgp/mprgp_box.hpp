#pragma once
/// `mprgp-box`: Dostal's MPRGP for bound constraints l <= x <= u (ALGORITHMS.md §5), the
/// original algorithm the paper extends. Accepts a J whose every row has at most one nonzero:
/// row a e_j' x >= c is x_j >= c/a for a > 0 (lower bound) and x_j <= c/a for a < 0 (upper
/// bound); both sides are supported.
/// Ref: Dostal, "Optimal Quadratic Programming Algorithms", Springer 2009, Ch. 5 (MPRGP);
///      Li et al., CGF 2015, Sec. 3.3, eq. (10)-(14), Alg. 1-2.
#include "solvers/core/registry.hpp"
#include "solvers/core/settings.hpp"
#include "solvers/core/solver.hpp"

#include <string>
#include <vector>

namespace cb {

/// True when every row of J has at most one nonzero (bound rows; the harness converts such
/// problems for mprgp-box).
bool is_bound_rows(const SpMat& J);

struct MprgpBoxSettings {
    CommonSettings common;
    double gamma = 1.0;              ///< proportioning constant Gamma (> 0)
    std::string precond = "jacobi";  ///< none | jacobi (diagonal scaling restricted to the free set)
    long power_max = 100;            ///< max power-method products for alpha_bar = 2 / ||A||

    static MprgpBoxSettings from_json(const nlohmann::json& settings);
    nlohmann::json to_json() const;
};

class MprgpBoxSolver final : public Solver {
public:
    explicit MprgpBoxSolver(MprgpBoxSettings settings) : m_settings(std::move(settings)) {}
    std::string name() const override { return "mprgp-box"; }
    nlohmann::json settings() const override { return m_settings.to_json(); }
    SolverResult solve(const QpView& qp, const SolveContext& context) override;

private:
    MprgpBoxSettings m_settings;
};

SolverEntry mprgp_box_entry();

/// The same solve for a solver that runs mprgp-box as one of its stages: not through a
/// `Solver::solve`, whose entries the instruction counts toggle on (tools/perf_gate.py TOGGLES).
SolverResult mprgp_box_solve(const QpView& qp, const MprgpBoxSettings& settings, const SolveContext& context);

}  // namespace cb
