// d'Ad and g += A d over a correction's DOFs, from A's blocks or its CSR rows (coupled_touched_rows.hpp).
#include "solvers/mprgp/coupled_touched_rows.hpp"

#include <algorithm>
#include <cstddef>
#include <vector>

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

TouchedRowsOfA::TouchedRowsOfA(const AOperator& op, const Vec* u, const SpMat* rows) : m_A(op.csr()), m_u(u)
{
    if (op.format() == AFormat::BSR) m_blocks = &op.blocks();
    if (op.format() != AFormat::SBSR) return;
    m_blocks = &op.blocks();
    m_upper = true;
    if (op.blocks_scaled()) m_u = nullptr;  // the blocks are U A U
    // A block row's part left of the diagonal is stored in the rows above, as their blocks' transposes.
    const BlockRows& B = *m_blocks;
    const size_t nb = B.start.size() - 1;
    if (rows != nullptr) {
        m_indexed.assign(nb, 0);
        for (Eigen::Index i = 0; i < rows->outerSize(); ++i)
            for (SpMat::InnerIterator it(*rows, i); it; ++it)
                if (static_cast<size_t>(it.col() / 3) < nb) m_indexed[static_cast<size_t>(it.col() / 3)] = 1;
    }
    auto indexed = [&](size_t J) { return m_indexed.empty() || m_indexed[J]; };
    m_above_start.assign(nb + 1, 0);
    for (size_t I = 0; I < nb; ++I)
        for (int k = B.start[I]; k < B.start[I + 1]; ++k) {
            const size_t J = static_cast<size_t>(B.column[static_cast<size_t>(k)]);
            if (J != I && indexed(J)) ++m_above_start[J + 1];
        }
    for (size_t J = 0; J < nb; ++J) m_above_start[J + 1] += m_above_start[J];
    m_above_block.resize(static_cast<size_t>(m_above_start[nb]));
    m_above_row.resize(m_above_block.size());
    std::vector<int> next(m_above_start.begin(), m_above_start.end() - 1);
    for (size_t I = 0; I < nb; ++I)
        for (int k = B.start[I]; k < B.start[I + 1]; ++k) {
            const size_t J = static_cast<size_t>(B.column[static_cast<size_t>(k)]);
            if (J == I || !indexed(J)) continue;
            const size_t at = static_cast<size_t>(next[J]++);
            m_above_block[at] = k;
            m_above_row[at] = static_cast<int>(I);
        }
    m_row_flag.assign(nb, 0);
}

void TouchedRowsOfA::list_block_rows(const std::vector<int>& touched) const
{
    m_rows_of_d.clear();
    for (int j : touched) {
        const size_t I = static_cast<size_t>(j / 3);
        if (m_row_flag[I]) continue;
        m_row_flag[I] = 1;
        m_rows_of_d.push_back(static_cast<int>(I));
    }
}

void TouchedRowsOfA::clear_block_rows() const
{
    for (int I : m_rows_of_d) m_row_flag[static_cast<size_t>(I)] = 0;
    m_rows_of_d.clear();
}

double TouchedRowsOfA::upper_d_a_d(const Vec& d) const
{
    // d'Ad = sum over d's block rows I of d_I'A_II d_I + 2 d_I'A_IJ d_J over their blocks right of
    // the diagonal (d_J = 0 unless J is one of them too).
    const BlockRows& B = *m_blocks;
    const double* pd = d.data();
    const double* u = m_u != nullptr ? m_u->data() : nullptr;
    auto ud = [&](std::ptrdiff_t c) { return u != nullptr ? u[c] * pd[c] : pd[c]; };
    double dad = 0.0;
    for (int I : m_rows_of_d) {
        const std::ptrdiff_t r = 3 * static_cast<std::ptrdiff_t>(I);
        const double d0 = ud(r), d1 = ud(r + 1), d2 = ud(r + 2);
        for (int k = B.start[static_cast<size_t>(I)]; k < B.start[static_cast<size_t>(I) + 1]; ++k) {
            const int J = B.column[static_cast<size_t>(k)];
            if (!m_row_flag[static_cast<size_t>(J)]) continue;
            const std::ptrdiff_t c = 3 * static_cast<std::ptrdiff_t>(J);
            const double e0 = ud(c), e1 = ud(c + 1), e2 = ud(c + 2);
            const double* b = B.value.data() + 9 * static_cast<std::ptrdiff_t>(k);  // column by column
            const double t = d0 * (b[0] * e0 + b[3] * e1 + b[6] * e2) + d1 * (b[1] * e0 + b[4] * e1 + b[7] * e2) +
                             d2 * (b[2] * e0 + b[5] * e1 + b[8] * e2);
            dad += J == I ? t : 2.0 * t;
        }
    }
    return dad;
}

void TouchedRowsOfA::upper_add_a_d(const Vec& d, Vec& g) const
{
    // Every stored block (I, J), I <= J, with d_I or d_J nonzero: g_I += A_IJ d_J, g_J += A_IJ' d_I.
    // Those of d's block rows are read along the rows; those above them, in rows d does not touch,
    // through the column index.
    const BlockRows& B = *m_blocks;
    const double* pd = d.data();
    const double* u = m_u != nullptr ? m_u->data() : nullptr;
    double* pg = g.data();
    auto ud = [&](std::ptrdiff_t c) { return u != nullptr ? u[c] * pd[c] : pd[c]; };
    auto add = [&](std::ptrdiff_t c, double v) { pg[c] += u != nullptr ? u[c] * v : v; };
    for (int I : m_rows_of_d) {
        const std::ptrdiff_t r = 3 * static_cast<std::ptrdiff_t>(I);
        const double d0 = ud(r), d1 = ud(r + 1), d2 = ud(r + 2);
        for (int k = B.start[static_cast<size_t>(I)]; k < B.start[static_cast<size_t>(I) + 1]; ++k) {
            const int J = B.column[static_cast<size_t>(k)];
            const std::ptrdiff_t c = 3 * static_cast<std::ptrdiff_t>(J);
            const double* b = B.value.data() + 9 * static_cast<std::ptrdiff_t>(k);
            if (m_row_flag[static_cast<size_t>(J)]) {
                const double e0 = ud(c), e1 = ud(c + 1), e2 = ud(c + 2);
                add(r, b[0] * e0 + b[3] * e1 + b[6] * e2);
                add(r + 1, b[1] * e0 + b[4] * e1 + b[7] * e2);
                add(r + 2, b[2] * e0 + b[5] * e1 + b[8] * e2);
            }
            if (J == I) continue;
            add(c, b[0] * d0 + b[1] * d1 + b[2] * d2);
            add(c + 1, b[3] * d0 + b[4] * d1 + b[5] * d2);
            add(c + 2, b[6] * d0 + b[7] * d1 + b[8] * d2);
        }
        // Block (K, I) above d's block row I, in a row K that d does not touch: g_K += A_KI d_I.
        auto add_above = [&](int K, const double* b) {
            if (m_row_flag[static_cast<size_t>(K)]) return;  // done along row K
            const std::ptrdiff_t c = 3 * static_cast<std::ptrdiff_t>(K);
            add(c, b[0] * d0 + b[3] * d1 + b[6] * d2);
            add(c + 1, b[1] * d0 + b[4] * d1 + b[7] * d2);
            add(c + 2, b[2] * d0 + b[5] * d1 + b[8] * d2);
        };
        if (m_indexed.empty() || m_indexed[static_cast<size_t>(I)]) {
            for (int a = m_above_start[static_cast<size_t>(I)]; a < m_above_start[static_cast<size_t>(I) + 1]; ++a)
                add_above(m_above_row[static_cast<size_t>(a)],
                          B.value.data() + 9 * static_cast<std::ptrdiff_t>(m_above_block[static_cast<size_t>(a)]));
            continue;
        }
        // A column the index does not cover (d off the rows' DOFs): each block row K < I searched for
        // block column I, in the index's order (K ascending).
        for (int K = 0; K < I; ++K) {
            const int* first = B.column.data() + B.start[static_cast<size_t>(K)];
            const int* last = B.column.data() + B.start[static_cast<size_t>(K) + 1];
            const int* at = std::lower_bound(first, last, I);
            if (at != last && *at == I) add_above(K, B.value.data() + 9 * (at - B.column.data()));
        }
    }
}

double TouchedRowsOfA::d_a_d(const std::vector<int>& touched, const Vec& d) const
{
    if (m_upper) {
        list_block_rows(touched);
        const double dad = upper_d_a_d(d);
        clear_block_rows();
        return dad;
    }
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
    if (m_upper) {
        list_block_rows(touched);
        upper_add_a_d(d, g);
        clear_block_rows();
        return;
    }
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
