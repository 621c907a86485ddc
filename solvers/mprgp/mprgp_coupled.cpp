// `mprgp-coupled`: extended MPRGP with general J (ALGORITHMS.md §4): its settings and registry
// entry. The solve is solvers/mprgp/mprgp_coupled_run.hpp's, run by the MPRGP engine.
#include "solvers/mprgp/mprgp_coupled.hpp"
#include "solvers/core/compressed_qp.hpp"
#include "solvers/mprgp/mprgp_coupled_run.hpp"

namespace cb {

namespace {

/// Every setting of `mprgp-coupled`, declared once (settings.hpp SettingsTable).
const SettingsTable<MprgpCoupledSettings>& mprgp_coupled_settings_table()
{
    static const SettingsTable<MprgpCoupledSettings> table =
        SettingsTable<MprgpCoupledSettings>()
            .number("gamma", &MprgpCoupledSettings::gamma, 0.0, 1e300, "proportioning constant Gamma > 0")
            .choice("precond", &MprgpCoupledSettings::precond, {"auto", "none", "jacobi", "ichol", "scaled"},
                    "auto: scaled when a component of J's row graph has more than dense_max_rows rows (CHOLMOD "
                    "face factors, where jacobi's second factor and solve per CG step cost most) and deflation = "
                    "none, else jacobi; the record's info.precond names the one used | "
                    "none (the authors' Fig. 6 setting) | jacobi (D-weighted face projection, J_A D^-1 J_A' solve) | "
                    "ichol: Q M^-1 Q g, M the incomplete Cholesky factor of A (once), Q the per-component face "
                    "projector (docs/preconditioners.md) | scaled: Jacobi as a change of variables, MPRGP on y = "
                    "D^1/2 x (A -> D^-1/2 A D^-1/2, J -> J D^-1/2), one face factor instead of two; judged on the "
                    "original QP")
            .choice(
                "deflation", &MprgpCoupledSettings::deflation, {"none", "rigid"},
                "none | rigid: the slow rigid modes of each body, projected on each new face (E = V'AV per body), "
                "balance the preconditioner, and a Galerkin step over them follows the start, each expansion and "
                "each proportioning step; default rigid with precond = ichol (docs/preconditioners.md)",
                // As for `mprgp`: ichol alone hits the iteration cap on the stiff dino (stress case
                // dino-stiff-1e10, tol 1e-8), ichol with the rigid modes converges in 746 iterations.
                [](const MprgpCoupledSettings& s) { return s.precond == "ichol" ? std::string("rigid") : s.deflation; })
            .integer("power_max", &MprgpCoupledSettings::power_max, 1, 1000000, "max power-method products")
            .integer("lcp_max_pivots", &MprgpCoupledSettings::lcp_max_pivots, 1, 100000000,
                     "block principal pivoting iterations per LCP before the PGS fallback")
            .integer("pgs_max_sweeps", &MprgpCoupledSettings::pgs_max_sweeps, 1, 100000000,
                     "PGS fallback sweeps per LCP")
            .integer("safeguard_max", &MprgpCoupledSettings::safeguard_max, 1, 100000000,
                     "max repeats of Alg. 3's safeguard after one step")
            .choice("operators", &MprgpCoupledSettings::operators, {"components", "global"},
                    "components: one small problem per component of J's row graph (dense factors per face) | "
                    "global: one CHOLMOD problem over all rows (the reference)")
            .integer("dense_max_rows", &MprgpCoupledSettings::dense_max_rows, 1, 100000000,
                     "operators = components: largest component with dense factors; larger ones use CHOLMOD")
            .integer("sparse_max_updates", &MprgpCoupledSettings::sparse_max_updates, 1, 100000000,
                     "operators = components, components above dense_max_rows: a face or LCP set that changes in "
                     "more rows than this is refactored; fewer are CHOLMOD row additions / deletions")
            .choice(
                "expansion_projection", &MprgpCoupledSettings::expansion_projection, {"face", "all"},
                "the expansion's projections (of an infeasible chain iterate and of x - alpha_bar phi): face (onto "
                "the feasible points that keep the face rows active, as decoupled MPRGP's projection does) | all (P "
                "of Alg. 1: coupled neighbours may lift face rows off)");
    return table;
}

}  // namespace

MprgpCoupledSettings MprgpCoupledSettings::from_json(const nlohmann::json& settings)
{
    return read_settings(settings, "mprgp-coupled", mprgp_coupled_settings_table());
}

nlohmann::json MprgpCoupledSettings::to_json() const { return write_settings(*this, mprgp_coupled_settings_table()); }

SolverEntry mprgp_coupled_entry()
{
    return solver_entry<MprgpCoupledSolver>(
        "mprgp-coupled", mprgp_coupled_settings_table(),
        "extended MPRGP with general (coupled) J: exact operators per component of the row graph (dense, or CHOLMOD "
        "factors updated by row changes)");
}

SolverResult MprgpCoupledSolver::solve(const QpView& qp, const SolveContext& context)
{
    return mprgp_coupled_solve(qp, m_settings, context);
}

SolverResult mprgp_coupled_solve(const QpView& qp, const MprgpCoupledSettings& settings, const SolveContext& context)
{
    const CompressedQpView compressed(qp);  // the face operators read J and A row by row
    CoupledRun run(compressed.view(), settings, context);
    return run.run();
}

}  // namespace cb
