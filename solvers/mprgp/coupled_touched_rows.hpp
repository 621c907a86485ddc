#pragma once
/// `mprgp-coupled`'s products of A with a correction d that is nonzero on a few DOFs only (a
/// projection's or a proportioning step's J'lam): d'Ad and g += A d over the rows of A at d's DOFs
/// (A symmetric: row j is column j). With precond = scaled both are of U A U (U = diag(u)).
/// They read A's 3x3 blocks when the operator's products do (BSR): the blocks stream through the
/// cache at every product anyway, while A's CSR rows are a second copy of the same entries whose
/// reads push the blocks out between products (flank_press frame 0: the contact patch's rows are
/// about a sixth of A). Each row is summed in column order as the CSR loop sums it; the blocks'
/// stored zeros add exact zeros, so the results equal the CSR loop's (but for the sign of a zero).
#include "solvers/core/types.hpp"
#include "solvers/linalg/a_product.hpp"

#include <vector>

namespace cb {

class TouchedRowsOfA {
public:
    /// @param op  the run's operator, prepared (its format decides the storage read); must outlive this
    /// @param u   the scaling U (precond = scaled), or nullptr
    TouchedRowsOfA(const AOperator& op, const Vec* u);
    /// d'Ad over the DOFs `touched` (d zero elsewhere).
    double d_a_d(const std::vector<int>& touched, const Vec& d) const;
    /// g += A d over the DOFs `touched` (d zero elsewhere).
    void add_a_d(const std::vector<int>& touched, const Vec& d, Vec& g) const;
    /// Whether the block rows are read (else the CSR rows).
    bool reads_blocks() const { return m_blocks != nullptr; }

private:
    const SpMat& m_A;
    const BlockRows* m_blocks = nullptr;
    const Vec* m_u;
};

}  // namespace cb
