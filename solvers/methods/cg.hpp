#pragma once
/// `cg`: (Jacobi-)preconditioned conjugate gradients on A x = b, ignoring J (ALGORITHMS.md §9).
/// The baseline of the paper's Fig. 8: it solves the UNCONSTRAINED relaxation, so its stop=kkt
/// test is the accuracy error of that problem (docs/accuracy.md: |D^-1 (Ax - b)|_inf / l), and the
/// harness reports a constrained problem it "solved" as `solved_relaxation`. It returns lambda = 0
/// and info {"ignores_constraints": true}.
/// Ref: Li et al. 2015, Sec. 6 (Fig. 8 comparison with PCG).
#include "solvers/core/registry.hpp"
#include "solvers/core/settings.hpp"
#include "solvers/core/solver.hpp"

#include <string>
#include <vector>

namespace cb {

struct CgSettings {
    CommonSettings common;
    std::string precond = "jacobi";  ///< none | jacobi (diagonal of A) | ichol (incomplete Cholesky of A)
    std::string start = "x0";        ///< x0 | zero (start point of the iteration)
    std::string deflation = "none";  ///< none | rigid (deflated PCG over the slow rigid modes of each body)

    /// Reads and checks the JSON settings (unknown keys are errors).
    static CgSettings from_json(const nlohmann::json& settings);
    nlohmann::json to_json() const;
};

class CgSolver final : public Solver {
public:
    explicit CgSolver(CgSettings settings) : m_settings(std::move(settings)) {}
    std::string name() const override { return "cg"; }
    nlohmann::json settings() const override { return m_settings.to_json(); }
    SolverResult solve(const QpView& qp, const SolveContext& context) override;

private:
    CgSettings m_settings;
};

/// Registry entry (factory, description, setting docs) for builtin_solvers.cpp.
SolverEntry cg_entry();

}  // namespace cb
