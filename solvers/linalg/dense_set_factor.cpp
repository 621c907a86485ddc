// A dense Cholesky factor of S(set, set) kept by row appends and deletions (dense_set_factor.hpp).
// Ref: Golub and Van Loan, Matrix Computations, 4th ed., sec. 6.5.4.
#include "solvers/linalg/dense_set_factor.hpp"

#include <algorithm>
#include <cmath>

namespace cb {

namespace {

/// sum over p < n of row[p] v[p] in four partial sums (entry p into sum p mod 4): L's rows are
/// contiguous, and a single sum waits on every addition.
double row_dot(const double* row, const double* v, int n)
{
    double s0 = 0.0, s1 = 0.0, s2 = 0.0, s3 = 0.0;
    int p = 0;
    for (; p + 4 <= n; p += 4) {
        s0 += row[p] * v[p];
        s1 += row[p + 1] * v[p + 1];
        s2 += row[p + 2] * v[p + 2];
        s3 += row[p + 3] * v[p + 3];
    }
    if (p < n) s0 += row[p] * v[p];
    if (p + 1 < n) s1 += row[p + 1] * v[p + 1];
    if (p + 2 < n) s2 += row[p + 2] * v[p + 2];
    return (s0 + s1) + (s2 + s3);
}

}  // namespace

DenseSetFactor::DenseSetFactor(const SpMatCol& S, int capacity)
    : m_S(S), m_k(static_cast<int>(S.rows())), m_cap(std::max(1, capacity))
{
    m_pos.assign(static_cast<size_t>(m_k), -1);
    m_L.assign(static_cast<size_t>(m_cap) * static_cast<size_t>(m_cap), 0.0);
    m_col.assign(static_cast<size_t>(m_k), 0.0);
    m_v.assign(static_cast<size_t>(m_cap), 0.0);
    m_rows.reserve(static_cast<size_t>(m_cap));
    m_leaving.reserve(static_cast<size_t>(m_cap));
    m_entering.reserve(static_cast<size_t>(m_k));
}

void DenseSetFactor::clear()
{
    for (int j : m_rows) m_pos[static_cast<size_t>(j)] = -1;
    m_rows.clear();
    m_ok = true;
}

bool DenseSetFactor::set_mask(const std::vector<char>& mask, Counters& cnt)
{
    int in = 0;
    for (int j = 0; j < m_k; ++j) in += mask[static_cast<size_t>(j)] != 0;
    if (in > m_cap) return false;
    if (!m_ok) clear();
    m_leaving.clear();
    m_entering.clear();
    for (size_t p = 0; p < m_rows.size(); ++p)
        if (!mask[static_cast<size_t>(m_rows[p])]) m_leaving.push_back(static_cast<int>(p));
    for (int j = 0; j < m_k; ++j)
        if (mask[static_cast<size_t>(j)] && m_pos[static_cast<size_t>(j)] < 0) m_entering.push_back(j);
    const size_t kept = m_rows.size() - m_leaving.size();
    if (m_leaving.size() + m_entering.size() > kept) {
        // More change than what stays: a fresh factor costs no more than the updates.
        clear();
        ++m_rebuilds;
        m_entering.clear();
        for (int j = 0; j < m_k; ++j)
            if (mask[static_cast<size_t>(j)]) m_entering.push_back(j);
    } else {
        for (auto p = m_leaving.rbegin(); p != m_leaving.rend(); ++p) remove(*p, cnt);  // last first: positions hold
    }
    for (int j : m_entering) {
        if (!append(j, cnt)) {
            m_ok = false;
            return false;
        }
    }
    return true;
}

bool DenseSetFactor::append(int j, Counters& cnt)
{
    // Row s of L: l = L^-1 S(set, j), then L(s, s) = sqrt(S(j, j) - l'l).
    const int s = size();
    for (SpMatCol::InnerIterator it(m_S, j); it; ++it) m_col[static_cast<size_t>(it.row())] = it.value();
    for (int r = 0; r < s; ++r) {
        const double v = m_col[static_cast<size_t>(m_rows[static_cast<size_t>(r)])] - row_dot(&at(r, 0), m_v.data(), r);
        m_v[static_cast<size_t>(r)] = v / at(r, r);
    }
    double d = m_col[static_cast<size_t>(j)];
    for (SpMatCol::InnerIterator it(m_S, j); it; ++it) m_col[static_cast<size_t>(it.row())] = 0.0;
    for (int r = 0; r < s; ++r) {
        d -= m_v[static_cast<size_t>(r)] * m_v[static_cast<size_t>(r)];
        at(s, r) = m_v[static_cast<size_t>(r)];
    }
    cnt.work_flops += static_cast<double>(s) * static_cast<double>(s + 2);
    if (!(d > 0.0) || !std::isfinite(d)) return false;
    at(s, s) = std::sqrt(d);
    m_pos[static_cast<size_t>(j)] = s;
    m_rows.push_back(j);
    ++m_appends;
    return true;
}

void DenseSetFactor::remove(int position, Counters& cnt)
{
    // Deleting row and column p of S leaves L11 and L21 (rows below p, columns before p) as they
    // are; the trailing block becomes the factor of L33 L33' + x x', x = L(p+1:, p): a rank-1
    // update by Givens-like rotations (Golub and Van Loan, alg. 6.5.4's update form).
    const int s = size();
    const int p = position;
    const int t = s - p - 1;  // rows after p
    for (int r = 0; r < t; ++r) m_v[static_cast<size_t>(r)] = at(p + 1 + r, p);
    for (int r = p + 1; r < s; ++r) {
        for (int c = 0; c < p; ++c) at(r - 1, c) = at(r, c);
        for (int c = p + 1; c <= r; ++c) at(r - 1, c - 1) = at(r, c);
    }
    for (int c = 0; c < t; ++c) {
        const int kk = p + c;  // the trailing block's column c in the shrunk L
        const double lkk = at(kk, kk), xk = m_v[static_cast<size_t>(c)];
        const double rr = std::hypot(lkk, xk);
        const double cs = rr / lkk, sn = xk / lkk;
        at(kk, kk) = rr;
        for (int r = c + 1; r < t; ++r) {
            const double lik = (at(p + r, kk) + sn * m_v[static_cast<size_t>(r)]) / cs;
            at(p + r, kk) = lik;
            m_v[static_cast<size_t>(r)] = cs * m_v[static_cast<size_t>(r)] - sn * lik;
        }
    }
    cnt.work_flops += 4.0 * static_cast<double>(t) * static_cast<double>(t) + static_cast<double>(s) * p;
    m_pos[static_cast<size_t>(m_rows[static_cast<size_t>(p)])] = -1;
    m_rows.erase(m_rows.begin() + p);
    for (int r = p; r < s - 1; ++r) m_pos[static_cast<size_t>(m_rows[static_cast<size_t>(r)])] = r;
    ++m_removals;
}

void DenseSetFactor::solve(double* b, Counters& cnt)
{
    const int s = size();
    double* v = m_v.data();
    for (int r = 0; r < s; ++r) v[r] = (b[m_rows[static_cast<size_t>(r)]] - row_dot(&at(r, 0), v, r)) / at(r, r);
    // L'x = y by rows of L (contiguous): x_r final, then its column's terms leave the rows above.
    for (int r = s - 1; r >= 0; --r) {
        const double xr = v[r] / at(r, r);
        v[r] = xr;
        const double* row = &at(r, 0);
        for (int p = 0; p < r; ++p) v[p] -= row[p] * xr;
    }
    for (int r = 0; r < s; ++r) b[m_rows[static_cast<size_t>(r)]] = m_v[static_cast<size_t>(r)];
    cnt.work_flops += 2.0 * static_cast<double>(s) * static_cast<double>(s);
}

}  // namespace cb
