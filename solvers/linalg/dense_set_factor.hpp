#pragma once
/// A dense Cholesky factor L L' = S(set, set) of a symmetric positive definite k x k sparse S,
/// kept while the set moves by a few rows: a row entering appends a row to L (one triangular
/// solve, O(s^2) for a set of s rows), a row leaving deletes its row and column of L and restores
/// the trailing block by a rank-1 update (O(s^2)); a set that changes in more rows than it keeps is
/// factored afresh (O(s^3 / 3)). Sized for the small LCP sets of a large component in
/// mprgp-coupled (the projections' sets hold 10-100 of flank_press's 1152 rows), where a solve with
/// the component's masked sparse factor (masked_gram_factor.hpp) costs O(nnz(L)) of all k rows
/// whatever the set's size, and each of its row modifications O(the touched columns of L).
/// Ref: Golub and Van Loan, Matrix Computations, 4th ed., sec. 6.5.4 (Cholesky updating).
#include "solvers/core/solver.hpp"
#include "solvers/core/types.hpp"

#include <vector>

namespace cb {

class DenseSetFactor {
public:
    /// @param S         symmetric positive definite, both triangles stored; must outlive the factor
    /// @param capacity  largest set factored (larger sets are refused: the caller keeps a sparse factor)
    DenseSetFactor(const SpMatCol& S, int capacity);

    /// Makes the factor that of S(mask, mask) (mask of size k, nonzero = in).
    /// @return false when the set has more than `capacity` rows or a pivot is not positive (do not
    ///         solve until a call succeeds)
    bool set_mask(const std::vector<char>& mask, Counters& cnt);
    /// b = S(mask, mask)^-1 b in place (b of size k, zero outside the mask on entry and on exit).
    void solve(double* b, Counters& cnt);
    int capacity() const { return m_cap; }
    int size() const { return static_cast<int>(m_rows.size()); }
    long appends() const { return m_appends; }
    long removals() const { return m_removals; }
    long rebuilds() const { return m_rebuilds; }

private:
    double& at(int r, int c)
    {
        return m_L[static_cast<size_t>(r) * static_cast<size_t>(m_cap) + static_cast<size_t>(c)];
    }
    double at(int r, int c) const
    {
        return m_L[static_cast<size_t>(r) * static_cast<size_t>(m_cap) + static_cast<size_t>(c)];
    }
    bool append(int j, Counters& cnt);
    void remove(int position, Counters& cnt);
    void clear();

    const SpMatCol& m_S;
    int m_k, m_cap;
    bool m_ok = true;           ///< m_rows is factored (false after a failed append)
    std::vector<int> m_rows;    ///< the set's rows in factor order
    std::vector<int> m_pos;     ///< position of each row in m_rows, -1 when out
    std::vector<double> m_L;    ///< cap x cap, row-major, lower triangle
    std::vector<double> m_col;  ///< scatter of one column of S (size k, zero between uses)
    std::vector<double> m_v;    ///< work (size cap)
    std::vector<int> m_leaving, m_entering;
    long m_appends = 0, m_removals = 0, m_rebuilds = 0;
};

}  // namespace cb
