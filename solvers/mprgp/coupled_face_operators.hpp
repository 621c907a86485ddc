#pragma once
/// The face operators of the coupled MPRGP (ALGORITHMS.md §4), on m-vectors only: the caller
/// forms J g, J D^-1 g, c - J v and applies J' to the multipliers returned here.
///   free gradient    nu  = (J_A J_A')^-1 J_A g                 (phi = g - J_A' nu, eq. 15-16)
///   Jacobi direction eta = (J_A D^-1 J_A')^-1 J_A D^-1 g       (z = D^-1 (g - J_A' eta))
///   chopped gradient 0 <= mu  perp  J_A J_A' mu - q >= 0      (beta = J_A' (nu - mu), eq. 17-18)
///   projection       0 <= lam perp  J J' lam - q >= 0         (P(v) = v + J' lam, eq. 19-20)
/// Rows of different components of J's row graph (solvers/linalg/row_components.hpp) share no column,
/// so each operator splits into one problem per component. `global` keeps the single CHOLMOD
/// problem over all rows (the test oracle); otherwise components of up to `dense_max_rows`
/// rows use dense Cholesky factors kept per face, larger ones CHOLMOD on their sparse Gram.
/// Every Gram matrix is scaled to unit diagonal and shifted by 1e-12 before factoring, so
/// dependent rows stay solvable (the solve splits their multiplier).
/// Ref: Li et al., CGF 2015, eq. (15)-(20).
#include "solvers/core/solver.hpp"
#include "solvers/core/types.hpp"
#include "solvers/linalg/row_components.hpp"

#include <nlohmann/json.hpp>
#include <memory>
#include <vector>

namespace cb {

struct CoupledOperatorOptions {
    bool global = false;        ///< one CHOLMOD problem over all rows (the old operators)
    bool jacobi = true;         ///< also keep the J D^-1 J' factors
    long dense_max_rows = 400;  ///< largest component done with dense factors
    long lcp_max_pivots = 200;  ///< block principal pivoting iterations before the PGS fallback
    long pgs_max_sweeps = 10000;
    long sparse_max_updates = 64;  ///< large components: a set change of more rows refactors instead of modifying
    /// Large components: projected Gauss-Seidel sweeps that pick an LCP's set when the active-set
    /// method would drop more than sparse_max_updates rows at once (0: drop them all, as before).
    long sweep_start_sweeps = 20;
};

class RowBlock;

/// Which point a projection is of: large components keep one warm-start set and one factor per
/// use, since the three sets differ (the trial's y is past x, the reduced gradient's point short of it).
enum class ProjectionUse { ITERATE = 0, REDUCED_GRADIENT = 1, TRIAL = 2 };
constexpr int PROJECTION_USES = 3;

class CoupledFaceOperators {
public:
    /// @param dinv  1 / diag(A) (used only when options.jacobi)
    CoupledFaceOperators(const SpMat& J, const Vec& dinv, const CoupledOperatorOptions& options);
    /// With J's row components already found (find_row_components(J), or of a column scaling of J).
    CoupledFaceOperators(const SpMat& J, const Vec& dinv, const CoupledOperatorOptions& options,
                         RowComponents components);
    ~CoupledFaceOperators();
    CoupledFaceOperators(const CoupledFaceOperators&) = delete;
    CoupledFaceOperators& operator=(const CoupledFaceOperators&) = delete;

    /// ||J_i||^2 (zero rows are never active and never projected).
    const Vec& row_norm2() const { return m_s; }
    const RowComponents& components() const { return m_comp; }

    /// The face (active flag per row); refactors only the blocks whose face changed.
    void set_face(const std::vector<char>& active, Counters& cnt);
    /// nu on the face rows (0 elsewhere) from jg = J g.
    void face_multipliers(const Vec& jg, Vec& nu, Counters& cnt);
    /// eta on the face rows (0 elsewhere) from jdg = J D^-1 g.
    void jacobi_multipliers(const Vec& jdg, Vec& eta, Counters& cnt);
    /// mu on the face rows (0 elsewhere) for q = J_A (g - phi) on the face rows; nu of the same g.
    void chopped_multipliers(const Vec& q, const Vec& nu, Vec& mu, Counters& cnt);
    /// lam (all rows) of the projection for q = c - J v. Only components with a row flagged in
    /// `violated` are solved; the others get lam = 0 (q of their rows is overwritten).
    /// With `keep`, the rows it flags stay equalities (J v' = c there, their lam of either sign): the
    /// projection onto the feasible set's part that keeps the face, whose rows then cannot be lifted
    /// off by a coupled neighbour's correction. @return the number of components solved (0: v is kept)
    long projection_multipliers(Vec& q, const std::vector<char>& violated, Vec& lam, Counters& cnt,
                                const std::vector<char>* keep = nullptr, ProjectionUse use = ProjectionUse::ITERATE);

    /// {components, largest_component, singleton_components, dense_blocks, sparse_blocks,
    ///  face_refactorizations, dense_factorizations, chopped_fast_paths, lcp_solves, pgs_fallbacks, lcp_failures}
    nlohmann::json stats() const;
    long lcp_failures() const { return m_lcp_failures; }

private:
    CoupledOperatorOptions m_opt;
    RowComponents m_comp;
    Vec m_s;
    std::vector<std::unique_ptr<RowBlock>> m_blocks;
    std::vector<int> m_block_of_component;  // global: all 0
    std::vector<char> m_block_violated, m_fixed;
    long m_face_refactorizations = 0, m_fast_paths = 0, m_lcp_solves = 0;
    long m_pgs_fallbacks = 0, m_lcp_failures = 0;
    int m_dense_blocks = 0, m_sparse_blocks = 0;
};

}  // namespace cb
