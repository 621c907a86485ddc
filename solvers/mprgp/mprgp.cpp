// `mprgp`: extended monotone MPRGP on decoupled constraints (ALGORITHMS.md §3): its settings and
// registry entry. The solve is solvers/mprgp/mprgp_decoupled.hpp's, run by the MPRGP engine.
#include "solvers/mprgp/mprgp.hpp"
#include "solvers/core/compressed_qp.hpp"
#include "solvers/mprgp/mprgp_decoupled.hpp"
#include "solvers/mprgp/mprgp_parts.hpp"

namespace cb {

namespace {

/// Every setting of `mprgp`, declared once (settings.hpp SettingsTable).
const SettingsTable<MprgpSettings>& mprgp_settings_table()
{
    static const SettingsTable<MprgpSettings> table =
        SettingsTable<MprgpSettings>()
            .choice(
                "precond", &MprgpSettings::precond, {"none", "jacobi", "ichol"},
                "none | jacobi: D-weighted projection of D^-1 g onto the face (J_A z = 0) | ichol: Q M^-1 Q g with M "
                "the incomplete Cholesky factor of the face matrix Q A Q + normal block, refactored when the face "
                "changes (docs/preconditioners.md)")
            .number("gamma", &MprgpSettings::gamma, 0.0, 1e300,
                    "proportioning constant Gamma > 0 (Alg. 1); default 10 with precond = ichol",
                    // With ichol the CG chains are short and cheap to restart; Gamma = 1 (the paper's)
                    // then spends most iterations proportioning (docs/preconditioners.md).
                    [](const MprgpSettings& s) { return s.precond == "ichol" ? 10.0 : s.gamma; })
            .choice("alpha", &MprgpSettings::alpha, {"power", "authors"},
                    "power (stop at rel. change 1e-3, warm start) | authors (||v_k+1 - v_k|| <= tol, <= 1001 products, "
                    "cold)")
            .integer("power_max", &MprgpSettings::power_max, 1, 1000000, "max power-method products (alpha = power)")
            .choice("objective", &MprgpSettings::objective, {"cheap", "recompute"},
                    "cheap: F(P(y)) without an extra A-product | recompute: the authors' 2 products per CG step")
            .integer("safeguard_max", &MprgpSettings::safeguard_max, 1, 100000000,
                     "max repeats of Alg. 3's safeguard after one step")
            .choice(
                "expansion", &MprgpSettings::expansion, expansion_variant_names(),
                "paper: x = P(x - alpha_bar phi), alpha_bar = 2/||A|| (Alg. 1) | precond: x = P(x - a z) with z the "
                "preconditioner's face direction and a = z'g / z'Az (one more A-product; Alg. 3's safeguard still "
                "guarantees descent); docs/preconditioners.md | bb: P(x - a phi) with the Barzilai-Borwein a = s's/s'y "
                "of the last two iterates in [alpha_bar/2, 100 alpha_bar] | projcg: P(y), the rejected CG trial "
                "projected (Kruzik et al. 2020); docs/DESIGN.md")
            .number("ichol_refactor", &MprgpSettings::ichol_refactor, -1e-300, 1.0,
                    "precond = ichol: refactor the face matrix when more than this fraction of the rows changed face "
                    "since the last factorization (0: at every face change; 1: factor once)")
            .choice("deflation", &MprgpSettings::deflation, {"none", "rigid"},
                    "none | rigid: each new face gets a Galerkin step over the slow rigid modes of each body (from "
                    "x0, projected on the face) and the preconditioner is balanced with them; default rigid with "
                    "precond = ichol (docs/preconditioners.md)",
                    // Measured on the whole stress suite: with ichol it never costs iterations and cuts the
                    // stiff dino's 3.4x cg to 1.3x; with jacobi the default stays the paper's (CI counters).
                    [](const MprgpSettings& s) { return s.precond == "ichol" ? std::string("rigid") : s.deflation; });
    return table;
}

}  // namespace

MprgpSettings MprgpSettings::from_json(const nlohmann::json& settings)
{
    return read_settings(settings, "mprgp", mprgp_settings_table());
}

nlohmann::json MprgpSettings::to_json() const { return write_settings(*this, mprgp_settings_table()); }

SolverEntry mprgp_entry()
{
    return solver_entry<MprgpSolver>("mprgp", mprgp_settings_table(),
                                     "extended monotone MPRGP on decoupled J (paper Alg. 1-3, closed-form operators)",
                                     "decoupled rows only (the harness decouples a coupled J first)");
}

SolverResult MprgpSolver::solve(const QpView& qp, const SolveContext& context)
{
    const CompressedQpView compressed(qp);  // the row kernels read J and A row by row
    DecoupledMprgp run(compressed.view(), m_settings, context);
    return run.run();
}

}  // namespace cb
