#pragma once
/// `mprgp`: the paper's extended monotone MPRGP on decoupled constraints (ALGORITHMS.md §3).
/// Requires a decoupled J (no two rows touch the same vertex, vertex = column / 3); the harness
/// applies solvers/mprgp/decouple.hpp first. A coupled J gives INVALID_INPUT.
/// Ref: Li et al., "Deformable Objects Collision Handling with Fast Convergence", CGF 2015,
///      Alg. 1-3, eq. (13)-(20), Appendix B; Dostal 2009, monotone MPRGP.
#include "solvers/core/registry.hpp"
#include "solvers/core/settings.hpp"
#include "solvers/core/solver.hpp"

#include <string>
#include <vector>

namespace cb {

struct MprgpSettings {
    CommonSettings common;
    double gamma = 1.0;  ///< proportioning constant Gamma (> 0)
    std::string precond =
        "jacobi";  ///< none | jacobi (D-weighted projection onto the face) | ichol (face IC, docs/preconditioners.md)
    std::string alpha = "power";      ///< power (rel. change 1e-3, warm start) | authors
    long power_max = 100;             ///< max power-method products (alpha = power)
    std::string objective = "cheap";  ///< cheap (1 A-product per CG step) | recompute (authors: 2)
    long safeguard_max = 100;         ///< max Alg. 3 safeguard repeats after one step
    double ichol_refactor = 0.1;  ///< precond = ichol: refactor when more than this fraction of the rows changed face
    std::string expansion = "paper";  ///< paper: P(x - alpha_bar phi) | precond: P(x - a z), z the preconditioned free
                                      ///< gradient, a its exact step | bb | projcg (solvers/mprgp/mprgp_parts.hpp)
    std::string deflation = "none";   ///< none | rigid: Galerkin step and balanced preconditioner with the face's
                                      ///< rigid modes (solvers/mprgp/mprgp_deflation.hpp)

    static MprgpSettings from_json(const nlohmann::json& settings);
    nlohmann::json to_json() const;
};

class MprgpSolver final : public Solver {
public:
    explicit MprgpSolver(MprgpSettings settings) : m_settings(std::move(settings)) {}
    std::string name() const override { return "mprgp"; }
    nlohmann::json settings() const override { return m_settings.to_json(); }
    bool requires_decoupled() const override { return true; }
    SolverResult solve(const QpView& qp, const SolveContext& context) override;

private:
    MprgpSettings m_settings;
};

/// Registry entry (factory, description, settings docs).
SolverEntry mprgp_entry();

}  // namespace cb
