#pragma once
/// `mprgp+bmf03`: the paper's second suggestion for friction (Sec. 8, after Bridson, Marino and
/// Fedkiw 2003): the frictionless step by `mprgp-coupled` (exact, every row), then one Coulomb
/// velocity update per contact. docs/friction.md "mprgp+bmf03" derives it; in short, with the
/// snapshot's step h (a backward-Euler step whose unknown x is the end position):
///   v_T,i  = (T_i x - cT_i) / h              the contact's tangential velocity after the solve,
///   dv_N,i = J_i (x* - x_free) / h >= 0      the normal velocity change the contact solve applied
///                                            (x_free = A^-1 b, the step without contacts),
///   v_T,i <- max(0, 1 - mu_i dv_N,i / |v_T,i|) v_T,i   (0: static friction)
/// on every contact with lambda_N,i > 0, one contact after the other (in row order). The new slip
/// is put into x on the contact's own unknowns, weighted by D^-1 = diag(A)^-1 (BMF03's mass
/// weighting with the lumped diagonal) and with the normal displacement unchanged; the impulse
/// that does so is reported as the contact's multipliers (lambda_N,i += p_N, lambda_T,i = p_T), so
/// that the harness's frictional e and FCLIB error judge the point. The method has no iteration of
/// its own: it ends `converged` when that point meets tol on the frictional e, else `stalled`
/// with the errors in its message.
///
/// Applies to a frictional snapshot that carries h and v0 (a simulator's step, qpsnap version 2);
/// a frictional problem without them (version 1 files have no friction; FCLIB-derived ones no h)
/// is `not_applicable`. Without friction (no mu > 0) it is mprgp-coupled, whose result and words
/// it returns under its own name.
#include "solvers/core/registry.hpp"
#include "solvers/core/settings.hpp"
#include "solvers/core/solver.hpp"

#include <string>

namespace cb {

struct MprgpBmf03Settings {
    CommonSettings common;  ///< given to mprgp-coupled's frictionless solve and to the final verdict

    static MprgpBmf03Settings from_json(const nlohmann::json& settings);  ///< throws InputError
    nlohmann::json to_json() const;
};

class MprgpBmf03Solver final : public Solver {
public:
    explicit MprgpBmf03Solver(const MprgpBmf03Settings& settings) : m_settings(settings) {}
    std::string name() const override { return "mprgp+bmf03"; }
    nlohmann::json settings() const override { return m_settings.to_json(); }
    bool handles_friction() const override { return true; }
    SolverResult solve(const QpView& qp, const SolveContext& context) override;

private:
    MprgpBmf03Settings m_settings;
};

/// The update alone: from the frictionless solution (x_star, lambda_n) and x_free = A^-1 b of a
/// problem with friction fields (T of 2m rows, mu of m), the point after the per-contact Coulomb
/// velocity update and its multipliers.
struct Bmf03Update {
    Vec x, lambda, lambda_t;
    long sticking = 0;  ///< contacts whose tangential velocity was set to 0
    long sliding = 0;   ///< contacts whose tangential speed was reduced by mu dv_N
    long free = 0;      ///< contacts left alone (lambda_N = 0 or mu = 0)
};
Bmf03Update bmf03_update(const QpView& qp, const Vec& x_star, const Vec& lambda_n, const Vec& x_free);

SolverEntry mprgp_bmf03_entry();

}  // namespace cb
