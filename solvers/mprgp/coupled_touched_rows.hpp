#pragma once
/// `mprgp-coupled`'s products of A with a correction d that is nonzero on a few DOFs only (a
/// projection's or a proportioning step's J'lam): d'Ad and g += A d over the rows of A at d's DOFs
/// (A symmetric: row j is column j). With precond = scaled both are of U A U (U = diag(u)).
/// They read A's 3x3 blocks when the operator's products do (BSR): the blocks stream through the
/// cache at every product anyway, while A's CSR rows are a second copy of the same entries whose
/// reads push the blocks out between products (flank_press frame 0: the contact patch's rows are
/// about a sixth of A). Each row is summed in column order as the CSR loop sums it; the blocks'
/// stored zeros add exact zeros, so the results equal the CSR loop's (but for the sign of a zero).
/// On SBSR (A's upper block triangle, scaled in place with precond = scaled) they read those blocks
/// too: d'Ad over the upper blocks of d's block rows, A d with the blocks above a block row found
/// through an index of the upper blocks by column (built here); the sums come in another order, so
/// the results equal the CSR loop's to rounding. The CSR rows, read otherwise, are not in the cache
/// that the products keep warm (docs/preconditioners.md).
#include "solvers/core/types.hpp"
#include "solvers/linalg/a_product.hpp"

#include <vector>

namespace cb {

class TouchedRowsOfA {
public:
    /// @param op  the run's operator, prepared (its format decides the storage read); must outlive this
    /// @param u   the scaling U (precond = scaled), or nullptr
    /// @param rows  the constraint rows whose DOFs d lives on (d = J'lam), or nullptr for any DOF: on
    ///              SBSR the column index then covers their block columns only (not a copy of A's
    ///              block pattern, 20 MB on press_1m); a d outside them is still right, slowly
    TouchedRowsOfA(const AOperator& op, const Vec* u, const SpMat* rows = nullptr);
    /// d'Ad over the DOFs `touched` (d zero elsewhere).
    double d_a_d(const std::vector<int>& touched, const Vec& d) const;
    /// g += A d over the DOFs `touched` (d zero elsewhere).
    void add_a_d(const std::vector<int>& touched, const Vec& d, Vec& g) const;
    /// Whether the block rows are read (else the CSR rows).
    bool reads_blocks() const { return m_blocks != nullptr; }
    /// Whether they are SBSR's upper blocks.
    bool reads_upper_blocks() const { return m_upper; }

private:
    /// m_rows_of_d = the block rows of the DOFs `touched`, once each, flagged in m_row_flag.
    void list_block_rows(const std::vector<int>& touched) const;
    void clear_block_rows() const;
    double upper_d_a_d(const Vec& d) const;
    void upper_add_a_d(const Vec& d, Vec& g) const;

    const SpMat& m_A;
    const BlockRows* m_blocks = nullptr;
    const Vec* m_u;                        // applied here unless the blocks hold U A U already
    bool m_upper = false;                  // m_blocks: SBSR's upper block triangle
    std::vector<int> m_above_start;        // SBSR: block column J's blocks above the diagonal are
    std::vector<int> m_above_block;        //   m_above_block[m_above_start[J] .. m_above_start[J + 1] - 1]
    std::vector<int> m_above_row;          //   in the block rows m_above_row[same range]
    std::vector<char> m_indexed;           // SBSR: block column J is in the index (empty: every one)
    mutable std::vector<char> m_row_flag;  // per block row: d has a DOF there
    mutable std::vector<int> m_rows_of_d;
};

}  // namespace cb
