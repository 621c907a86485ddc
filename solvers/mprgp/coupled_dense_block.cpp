// Dense blocks of the coupled face operators: a component's Gram matrices formed once per solve,
// Cholesky factors per face, the LCPs by principal pivoting on dense factors.
#include "solvers/mprgp/coupled_row_block.hpp"
#include "solvers/mprgp/coupled_sparse_lcp.hpp"

#include "solvers/measure/work_units.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

namespace cb {

namespace {

/// Lower Cholesky factor in place, row-major with leading dimension ld (the strict upper part is
/// not read). @return false when the matrix is not positive definite.
bool cholesky_in_place(double* a, int q, int ld)
{
    for (int j = 0; j < q; ++j) {
        double* rj = a + static_cast<size_t>(j) * static_cast<size_t>(ld);
        double d = rj[j];
        for (int p = 0; p < j; ++p) d -= rj[p] * rj[p];
        if (!(d > 0.0) || !std::isfinite(d)) return false;
        d = std::sqrt(d);
        rj[j] = d;
        const double inv = 1.0 / d;
        for (int i = j + 1; i < q; ++i) {
            double* ri = a + static_cast<size_t>(i) * static_cast<size_t>(ld);
            double s = ri[j];
            for (int p = 0; p < j; ++p) s -= ri[p] * rj[p];
            ri[j] = s * inv;
        }
    }
    return true;
}

/// Solves L L' x = b in place (b overwritten by x).
void cholesky_solve(const double* L, int q, int ld, double* b)
{
    for (int i = 0; i < q; ++i) {
        const double* ri = L + static_cast<size_t>(i) * static_cast<size_t>(ld);
        double s = b[i];
        for (int p = 0; p < i; ++p) s -= ri[p] * b[p];
        b[i] = s / ri[i];
    }
    for (int i = q - 1; i >= 0; --i) {
        double s = b[i];
        for (int p = i + 1; p < q; ++p)
            s -= L[static_cast<size_t>(p) * static_cast<size_t>(ld) + static_cast<size_t>(i)] * b[p];
        b[i] = s / L[static_cast<size_t>(i) * static_cast<size_t>(ld) + static_cast<size_t>(i)];
    }
}

double dense_factor_flops(double q) { return q * q * q / 3.0; }

// ---------------------------------------------------------------------------------------------
// Dense blocks: a component's Gram matrices formed once per solve, Cholesky factors per face.

class DenseBlock final : public RowBlock {
public:
    DenseBlock(const SpMat& J, std::vector<int> rows, const Vec& dinv, const CoupledOperatorOptions& opt,
               std::vector<double>& scatter)
        : RowBlock(std::move(rows)), m_k(static_cast<int>(m_rows.size())), m_jacobi(opt.jacobi),
          m_max_pivots(opt.lcp_max_pivots), m_max_sweeps(opt.pgs_max_sweeps)
    {
        const size_t kk = static_cast<size_t>(m_k) * static_cast<size_t>(m_k);
        m_G.assign(kk, 0.0);
        gram(J, dinv, false, scatter, m_G, m_scale);
        if (m_jacobi) {
            m_Gd.assign(kk, 0.0);
            gram(J, dinv, true, scatter, m_Gd, m_scale_d);
            m_Lfd.assign(kk, 0.0);
        }
        m_Lf.assign(kk, 0.0);
        m_Lw.assign(kk, 0.0);
        m_all.resize(static_cast<size_t>(m_k));
        std::iota(m_all.begin(), m_all.end(), 0);
        m_idx.reserve(static_cast<size_t>(m_k));
        m_bad.reserve(static_cast<size_t>(m_k));
        m_map_set.reserve(static_cast<size_t>(m_k));
        m_rhs.assign(static_cast<size_t>(m_k), 0.0);
        m_w.assign(static_cast<size_t>(m_k), 0.0);
    }

    void face_solve(const double* rhs, double* out, bool weighted, Counters& cnt) override
    {
        const int q = static_cast<int>(m_face.size());
        const std::vector<double>& sc = weighted ? m_scale_d : m_scale;
        const bool ok = weighted ? m_fd_ok : m_f_ok;
        for (int r = 0; r < q; ++r) out[r] = 0.0;
        if (!ok) return;
        for (int r = 0; r < q; ++r) out[r] = sc[static_cast<size_t>(m_face[static_cast<size_t>(r)])] * rhs[r];
        cholesky_solve(weighted ? m_Lfd.data() : m_Lf.data(), q, q, out);
        for (int r = 0; r < q; ++r) out[r] *= sc[static_cast<size_t>(m_face[static_cast<size_t>(r)])];
        cnt.work_flops += 2.0 * dense_triangular_solve_flops(q);
    }

    bool face_lcp(const double* q, double* mu, Counters& cnt, LcpTally& tally) override
    {
        return lcp(m_face.data(), static_cast<int>(m_face.size()), q, nullptr, m_face_set, mu, cnt, tally);
    }
    bool block_lcp(const double* q, double* lam, const char* fixed, int /*use*/, Counters& cnt,
                   LcpTally& tally) override
    {
        return lcp(m_all.data(), m_k, q, fixed, m_proj_set, lam, cnt, tally);
    }

private:
    double g(const std::vector<double>& M, int a, int b) const
    {
        return M[static_cast<size_t>(a) * static_cast<size_t>(m_k) + static_cast<size_t>(b)];
    }

    /// M = J_B W J_B' (W = D^-1 when `weighted`, else I), both triangles; sc = 1 / sqrt(diag).
    void gram(const SpMat& J, const Vec& dinv, bool weighted, std::vector<double>& scatter, std::vector<double>& M,
              std::vector<double>& sc) const
    {
        for (int a = 0; a < m_k; ++a) {
            const int ia = m_rows[static_cast<size_t>(a)];
            for (SpMat::InnerIterator it(J, ia); it; ++it)
                scatter[static_cast<size_t>(it.col())] += it.value() * (weighted ? dinv[it.col()] : 1.0);
            for (int b = 0; b <= a; ++b) {
                double s = 0.0;
                for (SpMat::InnerIterator it(J, m_rows[static_cast<size_t>(b)]); it; ++it)
                    s += it.value() * scatter[static_cast<size_t>(it.col())];
                M[static_cast<size_t>(a) * static_cast<size_t>(m_k) + static_cast<size_t>(b)] = s;
                M[static_cast<size_t>(b) * static_cast<size_t>(m_k) + static_cast<size_t>(a)] = s;
            }
            for (SpMat::InnerIterator it(J, ia); it; ++it) scatter[static_cast<size_t>(it.col())] = 0.0;
        }
        sc.resize(static_cast<size_t>(m_k));
        for (int a = 0; a < m_k; ++a) {
            const double d = g(M, a, a);
            sc[static_cast<size_t>(a)] = d > 0.0 ? 1.0 / std::sqrt(d) : 1.0;
        }
    }

    /// Factors the scaled, shifted principal submatrix M(map, map) into L (leading dimension q).
    bool factor(const std::vector<double>& M, const std::vector<double>& sc, const int* map, int q,
                std::vector<double>& L, Counters& cnt) const
    {
        for (int r = 0; r < q; ++r) {
            const int a = map[r];
            for (int c = 0; c <= r; ++c) {
                const int b = map[c];
                L[static_cast<size_t>(r) * static_cast<size_t>(q) + static_cast<size_t>(c)] =
                    sc[static_cast<size_t>(a)] * g(M, a, b) * sc[static_cast<size_t>(b)] + (r == c ? GRAM_SHIFT : 0.0);
            }
        }
        cnt.work_flops += dense_factor_flops(q);
        return cholesky_in_place(L.data(), q, q);
    }

    void refactor(Counters& cnt) override
    {
        const int q = static_cast<int>(m_face.size());
        m_f_ok = factor(m_G, m_scale, m_face.data(), q, m_Lf, cnt);
        if (m_jacobi) m_fd_ok = factor(m_Gd, m_scale_d, m_face.data(), q, m_Lfd, cnt);
    }

    /// 0 <= lam perp M(map, map) lam - q >= 0 (sizes kk), warm-started from `set` (in/out); rows
    /// flagged in `fixed` (may be null) are equalities M lam = q with lam of either sign.
    bool lcp(const int* map, int kk, const double* q, const char* fixed, std::vector<char>& set, double* lam,
             Counters& cnt, LcpTally& tally)
    {
        ++tally.solves;
        for (int r = 0; r < kk; ++r) lam[r] = 0.0;
        if (kk == 0) return true;
        if (static_cast<int>(set.size()) != kk) set.assign(static_cast<size_t>(kk), 0);
        auto is_fixed = [&](int r) { return fixed != nullptr && fixed[r] != 0; };
        for (int r = 0; r < kk; ++r)
            if (is_fixed(r)) set[static_cast<size_t>(r)] = 1;
        double qinf = 0.0;
        for (int r = 0; r < kk; ++r) qinf = std::max(qinf, std::abs(q[r]));
        const double tol_w = 1e-12 * std::max(1.0, qinf);
        if (kk == 1) {
            // Closed form (the decoupled rows' lambda = max(0, q / s)), with the same shift.
            const double s = g(m_G, map[0], map[0]);
            const double lam0 = (q[0] > 0.0 || is_fixed(0)) && s > 0.0 ? q[0] / (s * (1.0 + GRAM_SHIFT)) : 0.0;
            lam[0] = lam0;
            set[0] = lam0 > 0.0 || is_fixed(0);
            ++cnt.lcp_iterations;
            return true;
        }
        long best = std::numeric_limits<long>::max();
        int chances = 3;
        for (long it = 0; it < m_max_pivots; ++it) {
            m_idx.clear();
            for (int r = 0; r < kk; ++r)
                if (set[static_cast<size_t>(r)]) m_idx.push_back(r);
            const int ns = static_cast<int>(m_idx.size());
            for (int r = 0; r < kk; ++r) lam[r] = 0.0;
            if (ns > 0) {
                m_map_set.resize(static_cast<size_t>(ns));  // within the capacity reserved in the constructor
                for (int r = 0; r < ns; ++r) m_map_set[static_cast<size_t>(r)] = map[m_idx[static_cast<size_t>(r)]];
                if (!factor(m_G, m_scale, m_map_set.data(), ns, m_Lw, cnt)) break;
                for (int r = 0; r < ns; ++r)
                    m_rhs[static_cast<size_t>(r)] = m_scale[static_cast<size_t>(m_map_set[static_cast<size_t>(r)])] *
                                                    q[m_idx[static_cast<size_t>(r)]];
                cholesky_solve(m_Lw.data(), ns, ns, m_rhs.data());
                cnt.work_flops += 2.0 * dense_triangular_solve_flops(ns);
                for (int r = 0; r < ns; ++r)
                    lam[m_idx[static_cast<size_t>(r)]] =
                        m_scale[static_cast<size_t>(m_map_set[static_cast<size_t>(r)])] * m_rhs[static_cast<size_t>(r)];
            }
            ++cnt.lcp_iterations;
            double laminf = 0.0;
            for (int r = 0; r < kk; ++r) {
                double w = -q[r];
                for (int t = 0; t < ns; ++t)
                    w += g(m_G, map[r], m_map_set[static_cast<size_t>(t)]) * lam[m_idx[static_cast<size_t>(t)]];
                m_w[static_cast<size_t>(r)] = w;
                laminf = std::max(laminf, std::abs(lam[r]));
            }
            cnt.work_flops += dense_matvec_flops(kk, ns);
            const double tol_l = 1e-12 * std::max(1e-300, laminf);
            m_bad.clear();
            for (int r = 0; r < kk; ++r)
                if (!is_fixed(r) &&
                    (set[static_cast<size_t>(r)] ? lam[r] < -tol_l : m_w[static_cast<size_t>(r)] < -tol_w))
                    m_bad.push_back(r);
            if (m_bad.empty()) {
                for (int r = 0; r < kk; ++r)
                    if (!is_fixed(r)) lam[r] = std::max(0.0, lam[r]);
                return true;
            }
            flip_infeasible(m_bad, set, best, chances);
        }
        // Projected Gauss-Seidel fallback.
        ++tally.pgs_fallbacks;
        for (int r = 0; r < kk; ++r)
            if (!is_fixed(r)) lam[r] = std::max(0.0, lam[r]);
        for (long sweep = 0; sweep < m_max_sweeps; ++sweep) {
            double change = 0.0, laminf = 0.0;
            for (int r = 0; r < kk; ++r) {
                const double d = g(m_G, map[r], map[r]);
                if (!(d > 0.0)) continue;
                double mi = 0.0;
                for (int t = 0; t < kk; ++t) mi += g(m_G, map[r], map[t]) * lam[t];
                const double step = lam[r] - (mi - q[r]) / d;
                const double next = is_fixed(r) ? step : std::max(0.0, step);
                change = std::max(change, std::abs(next - lam[r]));
                lam[r] = next;
                laminf = std::max(laminf, std::abs(next));
            }
            ++cnt.pgs_sweeps;
            ++cnt.lcp_iterations;
            cnt.work_flops += dense_matvec_flops(kk, kk);
            if (change <= 1e-14 * std::max(1.0, laminf)) break;
        }
        double wmin = 0.0;
        for (int r = 0; r < kk; ++r) {
            double w = -q[r];
            for (int t = 0; t < kk; ++t) w += g(m_G, map[r], map[t]) * lam[t];
            wmin = std::min(wmin, is_fixed(r) ? -std::abs(w) : w);
            set[static_cast<size_t>(r)] = lam[r] > 0.0 || is_fixed(r);
        }
        return wmin >= -1e-8 * std::max(1.0, qinf);
    }

    int m_k;
    bool m_jacobi;
    long m_max_pivots, m_max_sweeps;
    std::vector<double> m_G, m_Gd, m_scale, m_scale_d;  // Gram matrices (row-major k x k), 1/sqrt(diag)
    std::vector<double> m_Lf, m_Lfd, m_Lw;              // face factors; the LCP's set factor
    bool m_f_ok = false, m_fd_ok = false;
    std::vector<int> m_all, m_idx, m_bad, m_map_set;
    std::vector<double> m_rhs, m_w;
};

}  // namespace

std::unique_ptr<RowBlock> make_dense_block(const SpMat& J, std::vector<int> rows, const Vec& dinv,
                                           const CoupledOperatorOptions& opt, std::vector<double>& scatter)
{
    return std::make_unique<DenseBlock>(J, std::move(rows), dinv, opt, scatter);
}

}  // namespace cb
