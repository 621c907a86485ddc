#pragma once
/// A block of rows closed under J's row graph (a component, or all rows) with its face and its
/// solves: the interface of the coupled face operators' blocks (solvers/mprgp/coupled_face_operators.*).
/// Dense blocks: solvers/mprgp/coupled_dense_block.cpp; CHOLMOD blocks (the global oracle and large
/// components): solvers/mprgp/coupled_sparse_blocks.cpp, their LCPs solvers/mprgp/coupled_sparse_lcp.*.
#include "solvers/linalg/masked_gram_factor.hpp"
#include "solvers/mprgp/coupled_face_operators.hpp"

#include <memory>
#include <vector>

namespace cb {

// The Gram matrices are scaled to unit diagonal, then shifted by this: relative to each row's
// own norm, so rows scaled by 1e-3 and 1e3 in one J are not regularised away, while a duplicated
// or parallel row still gets a (split) multiplier.
inline constexpr double GRAM_SHIFT = 1e-12;

/// Counters an LCP solve adds to (the operators' totals).
struct LcpTally {
    long& pgs_fallbacks;
    long& solves;
};

/// A set of rows closed under the row graph (a component, or all rows): its face and its solves.
class RowBlock {
public:
    explicit RowBlock(std::vector<int> rows) : m_rows(std::move(rows))
    {
        m_face.reserve(m_rows.size());
        m_next.reserve(m_rows.size());
        m_face_set.reserve(m_rows.size());
        m_next_set.reserve(m_rows.size());
        m_proj_set.assign(m_rows.size(), 0);
    }
    virtual ~RowBlock() = default;
    RowBlock(const RowBlock&) = delete;
    RowBlock& operator=(const RowBlock&) = delete;

    const std::vector<int>& rows() const { return m_rows; }
    const std::vector<int>& face() const { return m_face; }  ///< block-local indices of the active rows

    /// @return true when the face changed (the factors were rebuilt)
    bool set_face(const std::vector<char>& active, const Vec& s, Counters& cnt)
    {
        m_next.clear();
        for (size_t r = 0; r < m_rows.size(); ++r) {
            const int i = m_rows[r];
            if (active[static_cast<size_t>(i)] && s[i] > 0.0) m_next.push_back(static_cast<int>(r));
        }
        if (m_initialised && m_next == m_face) return false;
        m_initialised = true;
        // The chopped LCP's warm set follows the face: a row that stays keeps its state (the next
        // chopped problem is near the last one), a row that joins takes m_fresh_face_set.
        m_next_set.assign(m_next.size(), m_fresh_face_set);
        for (size_t a = 0, b = 0; a < m_face.size() && b < m_next.size();) {
            if (m_face[a] < m_next[b]) {
                ++a;
            } else if (m_next[b] < m_face[a]) {
                ++b;
            } else {
                m_next_set[b++] = m_face_set[a++];
            }
        }
        m_face.swap(m_next);
        m_face_set.swap(m_next_set);
        if (!m_face.empty()) refactor(cnt);
        return true;
    }
    /// out = (scaled, shifted G_AA)^-1 rhs on the face rows (G = J J', or J D^-1 J' when `weighted`).
    virtual void face_solve(const double* rhs, double* out, bool weighted, Counters& cnt) = 0;
    /// The chopped LCP on the face rows (warm-started from the last chopped set of this face).
    virtual bool face_lcp(const double* q, double* mu, Counters& cnt, LcpTally& tally) = 0;
    /// The projection LCP on all rows of the block (warm-started from the last projection).
    /// `fixed` (per block row, or null): rows kept as equalities, their lam of either sign.
    /// `use` (ProjectionUse): large components keep a warm start and a factor per use (flank_press
    /// frame 0: 6332 row modifications and 73 refactorisations against 6430 and 95 with one set, a
    /// small gain); dense blocks share one (8450 pivots shared against 11553 per use).
    virtual bool block_lcp(const double* q, double* lam, const char* fixed, int use, Counters& cnt,
                           LcpTally& tally) = 0;
    /// Adds the block's masked sparse factor counts (large components only).
    virtual void add_tally(MaskedFactorTally& /*t*/) const {}

protected:
    virtual void refactor(Counters& cnt) = 0;
    std::vector<int> m_rows, m_face, m_next;
    std::vector<char> m_face_set, m_next_set, m_proj_set;
    char m_fresh_face_set = 0;  ///< a row joining the face joins the chopped LCP's warm set (1) or not (0)
    bool m_initialised = false;
};

/// A component's Gram matrices formed once per solve, Cholesky factors per face (small components).
std::unique_ptr<RowBlock> make_dense_block(const SpMat& J, std::vector<int> rows, const Vec& dinv,
                                           const CoupledOperatorOptions& opt, std::vector<double>& scatter);
/// All rows on CHOLMOD, every face and LCP set factored afresh (operators = global, the oracle).
std::unique_ptr<RowBlock> make_global_block(const SpMat& J, std::vector<int> rows, const Vec& dinv,
                                            const CoupledOperatorOptions& opt);
/// A component too large for dense factors: masked CHOLMOD factors modified by row changes.
std::unique_ptr<RowBlock> make_large_block(const SpMat& J, std::vector<int> rows, const Vec& dinv,
                                           const CoupledOperatorOptions& opt);

}  // namespace cb
