#pragma once
/// `ica`: iterative constraint anticipation (Otaduy, Tamstorf, Steinemann, Gross 2009), as the
/// authors of Li et al. 2015 ran it for their Figs. 9-11 (ALGORITHMS.md §6).
/// Ref: Li et al., "Deformable Objects Collision Handling with Fast Convergence", CGF 2015,
///      Sec. 6.2; Otaduy et al., "Implicit Contact Handling for Deformable Objects", CGF 2009.
///
/// Split A = L + D3 + U (D3 = the 3x3 vertex blocks of A, each inverted once) and
/// B = J D3^-1 J'. Each outer iteration:
///   1. anticipate  q = c + J D3^-1 ((L + U) x - b)   (the LCP of a block-Jacobi predicted x);
///   2. warm-started projected Gauss-Seidel on  B lambda >= q, lambda >= 0, complementary:
///      at most `pgs_sweeps` sweeps, stop when ||dlambda||_2 <= `pgs_tol`;
///   3. one ascending block Gauss-Seidel sweep on  A x = b + J' lambda;
///   4. stop (stop=native) when ||A x - b - J' lambda||_2 <= tol (absolute, stationarity only,
///      as published), or (stop=kkt, default) on the accuracy error e (docs/accuracy.md).
///
/// Counting (Counters::a_products): one A-product equivalent per block Gauss-Seidel sweep and one
/// per residual product A x; the residual's A x is reused by the next anticipation ((L+U)x =
/// Ax - D3 x), so an outer iteration costs 2 A-products (+1 for A x0 at the start, + those of the accuracy scale's
/// fallback for a point-like start). The published implementation recomputes (L+U)x, i.e. about 3 per outer iteration.
/// PGS sweeps on B are counted in pgs_sweeps (and lcp_iterations), not as A-products.
#include "solvers/core/registry.hpp"
#include "solvers/core/solver.hpp"

#include <string>

namespace cb {

struct IcaSettings {
    CommonSettings common;
    long pgs_sweeps = 20;      ///< max PGS sweeps per outer iteration (authors: 20)
    double pgs_tol = 1e-3;     ///< PGS stops when ||dlambda||_2 <= pgs_tol (authors: 1e-3)
    std::string start = "x0";  ///< x0 | unconstrained (CHOLMOD solve of A x = b, timed in setup_s)

    static IcaSettings from_json(const nlohmann::json& settings);  ///< throws InputError
    nlohmann::json to_json() const;
};

class IcaSolver : public Solver {
public:
    explicit IcaSolver(IcaSettings settings) : m_settings(std::move(settings)) {}
    std::string name() const override { return "ica"; }
    nlohmann::json settings() const override { return m_settings.to_json(); }
    SolverResult solve(const QpView& qp, const SolveContext& context) override;

private:
    IcaSettings m_settings;
};

/// Registry entry (factory, description, setting docs).
SolverEntry ica_entry();

}  // namespace cb
