#pragma once
/// A sparse LDL' factor (CHOLMOD, simplicial) of a symmetric positive definite k x k matrix S
/// restricted to a mask of its rows: the factored matrix is S with every row and column outside
/// the mask replaced by the identity's, so a solve with a right-hand side that is zero outside the
/// mask returns S(mask, mask)^-1 b on the mask and zero elsewhere. The symbolic analysis of the
/// whole S is done once (natural order: the caller orders S); a row entering or leaving the mask
/// is a rank-2 modification (cholmod_rowadd / cholmod_rowdel, O(the touched columns of L)) and
/// a mask that changes in many rows at once is refactored numerically on the same analysis.
/// Used for the large components of mprgp-coupled (solvers/mprgp/coupled_face_operators.hpp), whose
/// face and LCP sets move by a few rows at a time.
/// Ref: Davis and Hager, "Row modifications of a sparse Cholesky factorization", SIMAX 2005.
#include "solvers/core/solver.hpp"
#include "solvers/core/types.hpp"

#include <cholmod.h>
#include <vector>

namespace cb {

/// How a MaskedGramFactor met its masks (summed into mprgp-coupled's component statistics).
struct MaskedFactorTally {
    long refactorizations = 0;  ///< numeric factorisations of a masked S
    long row_additions = 0;     ///< cholmod_rowadd calls
    long row_deletions = 0;     ///< cholmod_rowdel calls
    long reuses = 0;            ///< set_mask calls with the mask already factored
    long copies = 0;            ///< a donor's factor copied instead of a refactorisation
    // The dense factors of small LCP sets beside the masked ones (coupled_face_operators.cpp).
    long dense_set_solves = 0, dense_set_appends = 0, dense_set_removals = 0, dense_set_rebuilds = 0;
};

class MaskedGramFactor {
public:
    /// @param S            symmetric positive definite, both triangles stored, already in a fill-reducing order
    /// @param max_updates  a mask change of more rows than this is refactored instead of modified
    MaskedGramFactor(const SpMatCol& S, long max_updates);
    /// A factor of the same S as `twin` (not yet factored): its symbolic analysis is copied, not redone.
    MaskedGramFactor(const MaskedGramFactor& twin, long max_updates);
    ~MaskedGramFactor();
    MaskedGramFactor(const MaskedGramFactor&) = delete;
    MaskedGramFactor& operator=(const MaskedGramFactor&) = delete;

    /// Makes the factor that of S restricted to `mask` (size k, nonzero = in).
    /// @param donors  factors of the same S: when a donor's mask is within max_updates rows of `mask`
    ///                and nearer than this factor's by more than a copy costs (~8 row changes), the
    ///                nearest donor's factor is copied and modified instead (a copy is a memcpy of L, a
    ///                refactorisation ~75 row modifications)
    /// @return false when CHOLMOD failed (S(mask, mask) not positive definite to rounding)
    bool set_mask(const std::vector<char>& mask, Counters& cnt,
                  const std::vector<const MaskedGramFactor*>* donors = nullptr);
    /// Rows in which `mask` differs from the factored mask (k + 1 when nothing usable is factored).
    long distance(const std::vector<char>& mask) const;
    /// b = S(mask, mask)^-1 b in place (b of size k, zero outside the mask on entry and on exit).
    void solve(double* b, Counters& cnt);
    bool ok() const { return m_ok; }
    const MaskedFactorTally& tally() const { return m_tally; }

private:
    /// The workspace of every factor of S (m_S set): CHOLMOD's common, the masked lower triangle's
    /// and one column's arrays, the right-hand side.
    void allocate();
    /// m_masked = the lower triangle of S (`whole`), or of S masked by m_mask with an identity row
    /// for each row outside it.
    void fill_lower(bool whole);
    bool refactor(Counters& cnt);

    int m_k;
    long m_max_updates;
    SpMatCol m_S;
    std::vector<char> m_mask;
    bool m_ok = false, m_factored = false;
    double m_factor_flops = 0.0, m_lnz = 0.0;  // of the whole S's analysis: bounds for any mask
    cholmod_common m_cm;
    cholmod_factor* m_L = nullptr;
    cholmod_sparse* m_masked = nullptr;  // lower triangle of the masked S (refactorisations)
    cholmod_sparse* m_column = nullptr;  // one masked column of S (row additions)
    cholmod_dense* m_b = nullptr;
    cholmod_dense *m_x = nullptr, *m_y = nullptr, *m_e = nullptr;  // cholmod_solve2's reused workspace
    MaskedFactorTally m_tally;
};

}  // namespace cb
