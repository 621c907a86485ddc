// Bullet's Dantzig LCP pivoting on the dual LCP, in a child process (see bullet_dantzig.hpp).
#include "solvers/peers/bullet_dantzig.hpp"
#include "solvers/peers/dual_lcp_peer.hpp"

#include <BulletDynamics/MLCPSolvers/btDantzigLCP.h>

#include <climits>
#include <vector>

namespace cb {

namespace {

/// Its own settings, declared once (settings.hpp SettingsTable); the common block comes first.
const SettingsTable<BulletDantzigSettings>& bullet_dantzig_settings_table()
{
    static const SettingsTable<BulletDantzigSettings> table = SettingsTable<BulletDantzigSettings>().integer(
        "max_rows", &BulletDantzigSettings::max_rows, 0, LONG_MAX,
        "refuse (not_applicable) problems with more rows of J (W is dense m x m)");
    return table;
}

}  // namespace

BulletDantzigSettings BulletDantzigSettings::from_json(const nlohmann::json& settings)
{
    return read_settings(settings, "bullet-dantzig", bullet_dantzig_settings_table());
}

nlohmann::json BulletDantzigSettings::to_json() const { return write_settings(*this, bullet_dantzig_settings_table()); }

namespace {

static_assert(sizeof(btScalar) == sizeof(double), "bullet-dantzig needs Bullet's double-precision build");

/// In the child: Bullet's A x = b + w with lo = 0, hi = inf is our w = W lambda + q with b = -q
/// (Bullet overwrites A and b: the child's copies). Returns lambda (m doubles), then a
/// SiconosReport: info 0 when Bullet returned true with a finite lambda (btDantzigSolver's own
/// test), iterations = m (the driving indexes; Bullet does not count the pivots within each).
std::vector<char> run_dantzig(Eigen::MatrixXd& W, const Vec& q)
{
    const int m = static_cast<int>(q.size());
    std::vector<double> x(static_cast<size_t>(m), 0.0), b(static_cast<size_t>(m)), w(static_cast<size_t>(m), 0.0),
        lo(static_cast<size_t>(m), 0.0), hi(static_cast<size_t>(m), BT_INFINITY);
    for (int i = 0; i < m; ++i) b[static_cast<size_t>(i)] = -q[i];
    std::vector<int> findex(static_cast<size_t>(m), -1);  // no friction dependencies
    btDantzigScratchMemory scratch;
    // W is symmetric, so its column-major storage is the row-major m x m matrix Bullet expects.
    const bool ok =
        btSolveDantzigLCP(m, W.data(), x.data(), b.data(), w.data(), 0, lo.data(), hi.data(), findex.data(), scratch);
    SiconosReport report;
    report.info = ok && Eigen::Map<const Vec>(x.data(), m).allFinite() ? 0 : 1;
    report.iterations = m;
    return encode_child_reply(x.data(), x.size(), report);
}

}  // namespace

SolverResult BulletDantzigSolver::solve(const QpView& qp, const SolveContext& context)
{
    SolverResult result;
    result.info["library"] = std::string("Bullet ") + CB_BULLET_VERSION;
    result.info["history"] = "final point only (Bullet's Dantzig pivoting has no iteration callback)";
    result.info["native_residual_definition"] = "||min(lambda, W lambda + q)||_2 / (1 + ||q||_2) on the dual LCP";
    result.info["not_passed"] = "tol and max_iterations (Dantzig's method takes neither; tol is the harness's verdict)";
    DualLcpPeer peer;
    peer.name = "bullet-dantzig";
    peer.library = "Bullet";
    peer.method = "Bullet btSolveDantzigLCP";
    peer.steps = "driving indexes (m: Bullet counts neither its pivots nor where it stopped)";
    peer.max_rows = m_settings.max_rows;
    peer.residual_from_lcp = true;  // Bullet reports no error of its own
    peer.run = [](Eigen::MatrixXd& W, Vec& q) { return run_dantzig(W, q); };
    return solve_dual_lcp_peer(qp, context, m_settings.common, peer, std::move(result));
}

SolverEntry bullet_dantzig_entry()
{
    SolverEntry e = solver_entry<BulletDantzigSolver>(
        "bullet-dantzig", bullet_dantzig_settings_table(),
        std::string("peer: Bullet ") + CB_BULLET_VERSION +
            " Dantzig pivoting (btDantzigSolver's LCP) on the dual LCP W = J A^-1 J' (CHOLMOD, dense; "
            "child process)",
        "any J with at most max_rows rows (dense dual LCP)");
    e.library = std::string("Bullet ") + CB_BULLET_VERSION;
    return e;
}

}  // namespace cb
