// Siconos numerics' Lemke on the dual LCP, in a child process (see siconos_lemke.hpp).
#include "solvers/peers/siconos_lemke.hpp"
#include "solvers/peers/dual_lcp_peer.hpp"

#include <LCP_Solvers.h>
#include <LinearComplementarityProblem.h>
#include <NonSmoothDrivers.h>
#include <NumericsMatrix.h>
#include <SolverOptions.h>
#include <lcp_cst.h>

#include <algorithm>
#include <climits>
#include <vector>

namespace cb {

namespace {

/// Its own settings, declared once (settings.hpp SettingsTable); the common block comes first.
const SettingsTable<SiconosLemkeSettings>& siconos_lemke_settings_table()
{
    static const SettingsTable<SiconosLemkeSettings> table = SettingsTable<SiconosLemkeSettings>().integer(
        "max_rows", &SiconosLemkeSettings::max_rows, 0, LONG_MAX,
        "refuse (not_applicable) problems with more rows of J (W is dense m x m)");
    return table;
}

}  // namespace

SiconosLemkeSettings SiconosLemkeSettings::from_json(const nlohmann::json& settings)
{
    return read_settings(settings, "siconos-lemke", siconos_lemke_settings_table());
}

nlohmann::json SiconosLemkeSettings::to_json() const { return write_settings(*this, siconos_lemke_settings_table()); }

namespace {

/// What the child sends back through the pipe after the lambda values.
/// Runs Lemke on (W, q) (in the child); returns lambda (m doubles) then a SiconosReport.
std::vector<char> run_lemke(Eigen::MatrixXd& W, Vec& q, long max_iterations, double tol)
{
    const int m = static_cast<int>(q.size());
    NumericsMatrix* M = NM_new();
    M->storageType = NM_DENSE;
    M->size0 = m;
    M->size1 = m;
    M->matrix0 = W.data();  // column-major, as Siconos expects
    LinearComplementarityProblem problem{m, M, q.data()};
    std::vector<double> z(static_cast<size_t>(m), 0.0), w(static_cast<size_t>(m), 0.0);
    SolverOptions* options = solver_options_create(SICONOS_LCP_LEMKE);
    options->iparam[SICONOS_IPARAM_MAX_ITER] = static_cast<int>(std::min<long>(max_iterations, 1L << 30));
    options->dparam[SICONOS_DPARAM_TOL] = tol;
    SiconosReport report;
    report.info = linearComplementarity_driver(&problem, z.data(), w.data(), options);
    report.iterations = options->iparam[SICONOS_IPARAM_ITER_DONE];
    report.residual = options->dparam[SICONOS_DPARAM_RESIDU];
    // Lemke's info is 1 both at the cap and on a ray (a nonpositive pivot column); the count tells them apart.
    report.max_iterations_reached = report.info != 0 && report.iterations >= options->iparam[SICONOS_IPARAM_MAX_ITER];
    report.ray_termination = report.info != 0 && !report.max_iterations_reached;
    return encode_child_reply(z.data(), z.size(), report);
}

}  // namespace

SolverResult SiconosLemkeSolver::solve(const QpView& qp, const SolveContext& context)
{
    const SiconosLemkeSettings& s = m_settings;
    SolverResult result;
    result.info["library"] = std::string("Siconos numerics ") + CB_SICONOS_VERSION;
    result.info["history"] = "final point only (Siconos's Lemke has no iteration callback)";
    result.info["native_residual_definition"] = "Siconos's LCP error (SICONOS_DPARAM_RESIDU)";
    DualLcpPeer peer;
    peer.name = "siconos-lemke";
    peer.library = "Siconos";
    peer.method = "Siconos Lemke";
    peer.steps = "pivots";
    peer.max_rows = s.max_rows;
    peer.steps_are_pivots = true;
    peer.run = [&s](Eigen::MatrixXd& W, Vec& q) { return run_lemke(W, q, s.common.max_iterations, s.common.tol); };
    return solve_dual_lcp_peer(qp, context, s.common, peer, std::move(result));
}

SolverEntry siconos_lemke_entry()
{
    SolverEntry e =
        solver_entry<SiconosLemkeSolver>("siconos-lemke", siconos_lemke_settings_table(),
                                         std::string("peer: Siconos numerics ") + CB_SICONOS_VERSION +
                                             " Lemke on the dual LCP W = J A^-1 J' (CHOLMOD, dense; child process)",
                                         "any J with at most max_rows rows (dense dual LCP)");
    e.library = std::string("Siconos numerics ") + CB_SICONOS_VERSION;
    return e;
}

}  // namespace cb
