// d'Ad and g += A d over a correction's DOFs, from A's blocks or its CSR rows (coupled_touched_rows.hpp).
#include "solvers/mprgp/coupled_touched_rows.hpp"

#include <cstddef>

namespace cb {

namespace {

/// f(c, b) for each block of row j's block row in B: c = 3J, the block's first column, and b row j's
/// entries there (b[0], b[3], b[6] for columns c, c + 1, c + 2; blocks are stored column by column).
template <class F> void for_row_blocks(const BlockRows& B, int j, F&& f)
{
    const int I = j / 3;
    const double* row = B.value.data() + (j - 3 * I);
    for (int k = B.start[static_cast<size_t>(I)]; k < B.start[static_cast<size_t>(I) + 1]; ++k)
        f(3 * static_cast<std::ptrdiff_t>(B.column[static_cast<size_t>(k)]), row + 9 * static_cast<std::ptrdiff_t>(k));
}

}  // namespace

TouchedRowsOfA::TouchedRowsOfA(const AOperator& op, const Vec* u) : m_A(op.csr()), m_u(u)
{
    // SBSR keeps the upper blocks only: a row's left part is not stored there.
    if (op.format() == AFormat::BSR) m_blocks = &op.blocks();
}

double TouchedRowsOfA::d_a_d(const std::vector<int>& touched, const Vec& d) const
{
    const double* pd = d.data();
    const double* u = m_u != nullptr ? m_u->data() : nullptr;
    double dad = 0.0;
    if (m_blocks != nullptr) {
        for (int j : touched) {
            double s = 0.0;
            for_row_blocks(*m_blocks, j, [&](std::ptrdiff_t c, const double* b) {
                if (u != nullptr) {
                    s += b[0] * (u[c] * pd[c]);
                    s += b[3] * (u[c + 1] * pd[c + 1]);
                    s += b[6] * (u[c + 2] * pd[c + 2]);
                } else {
                    s += b[0] * pd[c];
                    s += b[3] * pd[c + 1];
                    s += b[6] * pd[c + 2];
                }
            });
            dad += (u != nullptr ? u[j] * pd[j] : pd[j]) * s;
        }
        return dad;
    }
    const int* outer = m_A.outerIndexPtr();
    const int* inner = m_A.innerIndexPtr();
    const double* val = m_A.valuePtr();
    for (int j : touched) {
        double s = 0.0;
        if (u != nullptr) {
            for (int k = outer[j]; k < outer[j + 1]; ++k) s += val[k] * (u[inner[k]] * pd[inner[k]]);
            dad += (u[j] * pd[j]) * s;
        } else {
            for (int k = outer[j]; k < outer[j + 1]; ++k) s += val[k] * pd[inner[k]];
            dad += pd[j] * s;
        }
    }
    return dad;
}

void TouchedRowsOfA::add_a_d(const std::vector<int>& touched, const Vec& d, Vec& g) const
{
    const double* pd = d.data();
    const double* u = m_u != nullptr ? m_u->data() : nullptr;
    double* pg = g.data();
    if (m_blocks != nullptr) {
        for (int j : touched) {
            const double dj = u != nullptr ? u[j] * pd[j] : pd[j];
            for_row_blocks(*m_blocks, j, [&](std::ptrdiff_t c, const double* b) {
                if (u != nullptr) {
                    pg[c] += u[c] * (b[0] * dj);
                    pg[c + 1] += u[c + 1] * (b[3] * dj);
                    pg[c + 2] += u[c + 2] * (b[6] * dj);
                } else {
                    pg[c] += b[0] * dj;
                    pg[c + 1] += b[3] * dj;
                    pg[c + 2] += b[6] * dj;
                }
            });
        }
        return;
    }
    const int* outer = m_A.outerIndexPtr();
    const int* inner = m_A.innerIndexPtr();
    const double* val = m_A.valuePtr();
    for (int j : touched) {
        if (u != nullptr) {
            const double ud = u[j] * pd[j];
            for (int k = outer[j]; k < outer[j + 1]; ++k) pg[inner[k]] += u[inner[k]] * (val[k] * ud);
        } else {
            for (int k = outer[j]; k < outer[j + 1]; ++k) pg[inner[k]] += val[k] * pd[j];
        }
    }
}

}  // namespace cb
