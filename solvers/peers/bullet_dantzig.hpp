#pragma once
/// `bullet-dantzig`: an external peer, Bullet's Dantzig pivoting (btSolveDantzigLCP, the routine
/// behind btDantzigSolver, from Open Dynamics Engine) on the harness's own dual LCP
///   w = W lambda + q >= 0,  lambda >= 0,  lambda'w = 0,   W = J A^-1 J',  q = J A^-1 b - c,
/// formed by CHOLMOD (solvers/linalg/dual_lcp.hpp, counted as setup, as for `siconos-lemke`), and
/// x = A^-1 (b + J'lambda). Compiled only when pkg-config finds `bullet-float64` (Debian's
/// libbullet-dev; double precision). The pivoting runs in a forked child process: Bullet asserts
/// and can produce NaN, so a crash is status `diverged` with info.crashed = true, and time_limit_s
/// ends the child (status `time_limit`). Dantzig's method drives each of the m indexes into the
/// complementary region once; it takes no tolerance and no iteration cap, so `tol` is the
/// harness's verdict only and `max_iterations` is not passed.
#include "solvers/core/registry.hpp"
#include "solvers/core/solver.hpp"

namespace cb {

struct BulletDantzigSettings {
    CommonSettings common;
    long max_rows = 4000;  ///< refuse problems with m > max_rows (W is dense m x m)

    static BulletDantzigSettings from_json(const nlohmann::json& settings);  ///< throws InputError
    nlohmann::json to_json() const;
};

class BulletDantzigSolver : public Solver {
public:
    explicit BulletDantzigSolver(BulletDantzigSettings settings) : m_settings(settings) {}
    std::string name() const override { return "bullet-dantzig"; }
    nlohmann::json settings() const override { return m_settings.to_json(); }
    SolverResult solve(const QpView& qp, const SolveContext& context) override;

private:
    BulletDantzigSettings m_settings;
};

SolverEntry bullet_dantzig_entry();

}  // namespace cb
