#pragma once
/// `mprgp-staggered`: Coulomb friction on a frictional snapshot (solvers/core/qp.hpp Friction) by the
/// staggered projections of Kaufman, Sueda, James, Pai (SIGGRAPH Asia 2008), each half an exact
/// MPRGP solve. One round, with lambda_T fixed from the round before (0 at the start):
///   (a) normal:     min 1/2 x'Ax - (b + T'lambda_T)'x  s.t.  Jx >= c, by `mprgp-coupled` (x, lambda_N);
///   (b) tangential: min 1/2 l'W_TT l + q_T'l  s.t.  ||l_i|| <= mu_i lambda_N,i per contact, by the
///       MPRGP engine over DiscSet (MPGP, Jacobi-preconditioned), W_TT = T A^-1 T' (dense, formed
///       once by DualLcp), q_T = T A^-1 (b + J'lambda_N) - cT (one CHOLMOD solve per round).
/// Its gradient u_T = W_TT l + q_T is the tangential displacement at x = A^-1 (b + J'lambda_N +
/// T'l), so (b)'s optimality is maximal dissipation: stick inside the disc, slide against u_T on
/// its circle. A fixed point of the rounds is a Coulomb solution.
///
/// Stop: the outer loop's rule at (x, lambda_N, lambda_T) after each normal solve: stop=kkt the
/// frictional accuracy error e (docs/accuracy.md "e for Coulomb friction"), stop=native FCLIB's
/// relative error (solvers/measure/friction_snapshot_error.hpp). The inner solves stop at max(inner_fraction
/// tol, inner_relative e_k), e_k the frictional e at the last point whatever the stop rule (in their
/// own units: e of the normal QP; ||phi + beta|| relative to l and the normal rows' smallest norm),
/// loose while lambda_N still moves.
/// `iterations` counts every inner MPRGP iteration (normal and tangential); max_iterations caps
/// their sum. Other exits: `max_iterations` when max_outer rounds end unconverged (its message
/// says so), `stalled` when stall_rounds rounds pass without a 1% lower error, an inner solve's
/// breakdown with its message. Without friction (no mu, or every mu = 0) it is one normal solve,
/// `mprgp-coupled`'s run with its iterates (tests/solvers/test_mprgp_staggered.cpp).
#include "solvers/core/registry.hpp"
#include "solvers/core/settings.hpp"
#include "solvers/core/solver.hpp"

namespace cb {

struct MprgpStaggeredSettings {
    CommonSettings common;
    long max_outer = 200;         ///< staggered rounds (normal + tangential solve)
    long max_contacts = 700;      ///< refuse more contacts (not_applicable): W_TT is a dense 2m x 2m matrix
    double inner_fraction = 0.5;  ///< each inner solve stops at max(inner_fraction tol,
    double inner_relative = 0.1;  ///< inner_relative e_k), e_k the outer error of the round before
    long stall_rounds = 20;       ///< rounds without a 1% lower outer error: stalled

    static MprgpStaggeredSettings from_json(const nlohmann::json& settings);  ///< throws InputError
    nlohmann::json to_json() const;
};

class MprgpStaggeredSolver final : public Solver {
public:
    explicit MprgpStaggeredSolver(MprgpStaggeredSettings settings) : m_settings(settings) {}
    std::string name() const override { return "mprgp-staggered"; }
    nlohmann::json settings() const override { return m_settings.to_json(); }
    bool handles_friction() const override { return true; }
    SolverResult solve(const QpView& qp, const SolveContext& context) override;

private:
    MprgpStaggeredSettings m_settings;
};

SolverEntry mprgp_staggered_entry();

}  // namespace cb
