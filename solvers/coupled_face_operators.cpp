// The face operators of the coupled MPRGP, per component of J's row graph (ALGORITHMS.md §4).
// Ref: Li et al., "Deformable Objects Collision Handling with Fast Convergence", CGF 2015,
//      eq. (15)-(16) free gradient, (17)-(18) chopped gradient, (19)-(20) projection.
// LCPs: block principal pivoting (Judice and Pires 1994) with Murty's single pivot when the
// infeasible count stops dropping, warm-started from the last set; projected Gauss-Seidel fallback.
#include "solvers/coupled_face_operators.hpp"

#include "solvers/dense_set_factor.hpp"
#include "solvers/masked_gram_factor.hpp"
#include "solvers/work_units.hpp"

#include <Eigen/CholmodSupport>
#include <Eigen/OrderingMethods>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numeric>

namespace cb {

namespace {

// The Gram matrices are scaled to unit diagonal, then shifted by this: relative to each row's
// own norm, so rows scaled by 1e-3 and 1e3 in one J are not regularised away, while a duplicated
// or parallel row still gets a (split) multiplier.
constexpr double GRAM_SHIFT = 1e-12;

// Large components' projection LCP sets of up to this many rows use a dense Cholesky factor kept by
// row appends and deletions (dense_set_factor.hpp): at 128 rows an append or deletion costs ~16k
// flops, about what one of CHOLMOD's row modifications costs on flank_press's 1152-row factor.
constexpr int DENSE_SET_MAX_ROWS = 128;

struct LcpTally {
    long& pgs_fallbacks;
    long& solves;
};

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

}  // namespace

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

namespace {

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
            const long count = static_cast<long>(m_bad.size());
            if (count < best) {
                best = count;
                chances = 3;
                for (int r : m_bad) set[static_cast<size_t>(r)] ^= 1;
            } else if (chances > 0) {
                --chances;
                for (int r : m_bad) set[static_cast<size_t>(r)] ^= 1;
            } else {
                set[static_cast<size_t>(m_bad.back())] ^= 1;  // Murty: finite for P-matrices
            }
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

// ---------------------------------------------------------------------------------------------
// Sparse blocks on CHOLMOD: all rows (the global oracle) or a component too large for dense work.

using Cholmod = Eigen::CholmodDecomposition<SpMatCol, Eigen::Lower>;

/// The principal submatrix M(idx, idx).
SpMatCol submatrix(const SpMatCol& M, const std::vector<int>& idx)
{
    std::vector<int> local(static_cast<size_t>(M.rows()), -1);
    for (size_t k = 0; k < idx.size(); ++k) local[static_cast<size_t>(idx[k])] = static_cast<int>(k);
    std::vector<Triplet> t;
    for (size_t k = 0; k < idx.size(); ++k)
        for (SpMatCol::InnerIterator it(M, idx[k]); it; ++it)
            if (local[static_cast<size_t>(it.row())] >= 0)
                t.emplace_back(local[static_cast<size_t>(it.row())], static_cast<int>(k), it.value());
    SpMatCol S(static_cast<Eigen::Index>(idx.size()), static_cast<Eigen::Index>(idx.size()));
    S.setFromTriplets(t.begin(), t.end());
    return S;
}

/// The rows `rows` of J, in that order.
SpMat block_rows(const SpMat& J, const std::vector<int>& rows)
{
    std::vector<Triplet> t;
    for (size_t r = 0; r < rows.size(); ++r)
        for (SpMat::InnerIterator it(J, rows[r]); it; ++it)
            t.emplace_back(static_cast<int>(r), static_cast<int>(it.col()), it.value());
    SpMat JB(static_cast<Eigen::Index>(rows.size()), J.cols());
    JB.setFromTriplets(t.begin(), t.end());
    return JB;
}

/// A CHOLMOD factor of a Gram matrix scaled to unit diagonal and shifted by GRAM_SHIFT (the global
/// oracle's operators, as before issue 31: analysis and factorisation on every face and LCP set).
struct SparseFactor {
    std::unique_ptr<Cholmod> chol;
    Vec scale;  ///< 1 / sqrt(diag)
    bool ok = false;
    bool compute(const SpMatCol& S, Counters& cnt)
    {
        scale.resize(S.rows());
        for (Eigen::Index i = 0; i < S.rows(); ++i) {
            const double d = S.coeff(i, i);
            scale[i] = d > 0.0 ? 1.0 / std::sqrt(d) : 1.0;
        }
        const SpMatCol scaled = SpMatCol(scale.asDiagonal() * S * scale.asDiagonal());
        chol = std::make_unique<Cholmod>();
        chol->setShift(GRAM_SHIFT);
        chol->compute(scaled);
        ++cnt.cholmod_analyses;
        ++cnt.cholmod_factorizations;
        cnt.work_flops += cholmod_factor_flops(chol->cholmod());
        ok = chol->info() == Eigen::Success;
        return ok;
    }
    Vec solve(const Vec& rhs, Counters& cnt)
    {
        ++cnt.cholmod_solves;
        cnt.work_flops += cholmod_solve_flops(chol->cholmod());
        return scale.cwiseProduct(Vec(chol->solve(Vec(scale.cwiseProduct(rhs)))));
    }
};

/// Projected Gauss-Seidel on 0 <= lambda perp M lambda - q >= 0 from lambda (clipped), the
/// fallback of the principal pivoting; `set` becomes the rows with lambda > 0 (and the fixed ones).
bool projected_gauss_seidel(const SpMatCol& M, const Vec& q, const char* fixed, std::vector<char>& set, Vec& lambda,
                            Counters& cnt, long max_sweeps)
{
    const Eigen::Index k = q.size();
    auto is_fixed = [&](Eigen::Index i) { return fixed != nullptr && fixed[i] != 0; };
    for (Eigen::Index i = 0; i < k; ++i)
        if (!is_fixed(i)) lambda[i] = std::max(0.0, lambda[i]);
    const Vec diag = M.diagonal();
    for (long sweep = 0; sweep < max_sweeps; ++sweep) {
        double change = 0.0;
        for (Eigen::Index i = 0; i < k; ++i) {
            if (!(diag[i] > 0.0)) continue;
            double mi = 0.0;
            for (SpMatCol::InnerIterator it(M, i); it; ++it) mi += it.value() * lambda[it.row()];  // symmetric
            const double step = lambda[i] - (mi - q[i]) / diag[i];
            const double next = is_fixed(i) ? step : std::max(0.0, step);
            change = std::max(change, std::abs(next - lambda[i]));
            lambda[i] = next;
        }
        ++cnt.pgs_sweeps;
        ++cnt.lcp_iterations;
        cnt.work_flops += sparse_product_flops(static_cast<double>(M.nonZeros()));
        if (change <= 1e-14 * std::max(1.0, lambda.lpNorm<Eigen::Infinity>())) break;
    }
    Vec w = M * lambda - q;
    for (Eigen::Index i = 0; i < k; ++i) {
        set[static_cast<size_t>(i)] = lambda[i] > 0.0 || is_fixed(i);
        if (is_fixed(i)) w[i] = -std::abs(w[i]);
    }
    return w.minCoeff() >= -1e-8 * std::max(1.0, q.lpNorm<Eigen::Infinity>());
}

/// The principal pivoting's set update (Judice and Pires 1994): flip every infeasible row while
/// their count drops (three more chances otherwise), then Murty's single flip of the last one.
void flip_infeasible(const std::vector<int>& bad, std::vector<char>& set, long& best, int& chances)
{
    const long count = static_cast<long>(bad.size());
    if (count < best) {
        best = count;
        chances = 3;
        for (int i : bad) set[static_cast<size_t>(i)] ^= 1;
    } else if (chances > 0) {
        --chances;
        for (int i : bad) set[static_cast<size_t>(i)] ^= 1;
    } else {
        set[static_cast<size_t>(bad.back())] ^= 1;  // Murty: finite for P-matrices
    }
}

/// Solves 0 <= lambda  perp  M lambda - q >= 0 by block principal pivoting, warm-started from
/// `set` (in/out); falls back to projected Gauss-Seidel. @return false when neither met the tolerance.
bool sparse_lcp(const SpMatCol& M, const Vec& q, const char* fixed, std::vector<char>& set, Vec& lambda, Counters& cnt,
                long max_pivots, long max_sweeps, long& pgs_fallbacks)
{
    const Eigen::Index k = q.size();
    lambda = Vec::Zero(k);
    if (k == 0) return true;
    if (static_cast<Eigen::Index>(set.size()) != k) set.assign(static_cast<size_t>(k), 0);
    auto is_fixed = [&](Eigen::Index i) { return fixed != nullptr && fixed[i] != 0; };
    for (Eigen::Index i = 0; i < k; ++i)
        if (is_fixed(i)) set[static_cast<size_t>(i)] = 1;
    const double tol_w = 1e-12 * std::max(1.0, q.lpNorm<Eigen::Infinity>());
    long best = std::numeric_limits<long>::max();
    int chances = 3;
    for (long it = 0; it < max_pivots; ++it) {
        std::vector<int> idx;
        for (Eigen::Index i = 0; i < k; ++i)
            if (set[static_cast<size_t>(i)]) idx.push_back(static_cast<int>(i));
        lambda.setZero();
        if (!idx.empty()) {
            SparseFactor f;
            if (!f.compute(submatrix(M, idx), cnt)) break;
            Vec rhs(static_cast<Eigen::Index>(idx.size()));
            for (size_t r = 0; r < idx.size(); ++r) rhs[static_cast<Eigen::Index>(r)] = q[idx[r]];
            const Vec sol = f.solve(rhs, cnt);
            for (size_t r = 0; r < idx.size(); ++r) lambda[idx[r]] = sol[static_cast<Eigen::Index>(r)];
        }
        ++cnt.lcp_iterations;
        const Vec w = M * lambda - q;
        cnt.work_flops += sparse_product_flops(static_cast<double>(M.nonZeros()));
        const double tol_l = 1e-12 * std::max(1e-300, lambda.lpNorm<Eigen::Infinity>());
        std::vector<int> bad;
        for (Eigen::Index i = 0; i < k; ++i) {
            if (!is_fixed(i) && (set[static_cast<size_t>(i)] ? lambda[i] < -tol_l : w[i] < -tol_w))
                bad.push_back(static_cast<int>(i));
        }
        if (bad.empty()) {
            for (Eigen::Index i = 0; i < k; ++i)
                if (!is_fixed(i)) lambda[i] = std::max(0.0, lambda[i]);
            return true;
        }
        flip_infeasible(bad, set, best, chances);
    }
    ++pgs_fallbacks;
    return projected_gauss_seidel(M, q, fixed, set, lambda, cnt, max_sweeps);
}

/// All rows on CHOLMOD (operators=global, the test oracle): every face and LCP set analysed and
/// factored afresh, as before issue 31.
class SparseBlock final : public RowBlock {
public:
    SparseBlock(const SpMat& J, std::vector<int> rows, const Vec& dinv, const CoupledOperatorOptions& opt)
        : RowBlock(std::move(rows)), m_jacobi(opt.jacobi), m_max_pivots(opt.lcp_max_pivots),
          m_max_sweeps(opt.pgs_max_sweeps)
    {
        const SpMat JB = block_rows(J, m_rows);
        m_gram = SpMatCol(JB * JB.transpose());
        if (m_jacobi) m_gram_d = SpMatCol(JB * dinv.asDiagonal() * JB.transpose());
    }

    void face_solve(const double* rhs, double* out, bool weighted, Counters& cnt) override
    {
        const Eigen::Index q = static_cast<Eigen::Index>(m_face.size());
        SparseFactor& f = weighted ? m_face_factor_d : m_face_factor;
        Eigen::Map<Vec> o(out, q);
        if (!f.ok) {
            o.setZero();
            return;
        }
        o = f.solve(Eigen::Map<const Vec>(rhs, q), cnt);
    }
    bool face_lcp(const double* q, double* mu, Counters& cnt, LcpTally& tally) override
    {
        ++tally.solves;
        const Eigen::Index k = static_cast<Eigen::Index>(m_face.size());
        Vec sol;
        const bool ok = sparse_lcp(m_face_gram, Eigen::Map<const Vec>(q, k), nullptr, m_face_set, sol, cnt,
                                   m_max_pivots, m_max_sweeps, tally.pgs_fallbacks);
        Eigen::Map<Vec>(mu, k) = sol;
        return ok;
    }
    bool block_lcp(const double* q, double* lam, const char* fixed, int /*use*/, Counters& cnt,
                   LcpTally& tally) override
    {
        ++tally.solves;
        const Eigen::Index k = static_cast<Eigen::Index>(m_rows.size());
        Vec sol;
        const bool ok = sparse_lcp(m_gram, Eigen::Map<const Vec>(q, k), fixed, m_proj_set, sol, cnt, m_max_pivots,
                                   m_max_sweeps, tally.pgs_fallbacks);
        Eigen::Map<Vec>(lam, k) = sol;
        return ok;
    }

private:
    void refactor(Counters& cnt) override
    {
        m_face_gram = submatrix(m_gram, m_face);
        m_face_factor.compute(m_face_gram, cnt);
        if (m_jacobi) m_face_factor_d.compute(submatrix(m_gram_d, m_face), cnt);
    }

    bool m_jacobi;
    long m_max_pivots, m_max_sweeps;
    SpMatCol m_gram, m_gram_d, m_face_gram;
    SparseFactor m_face_factor, m_face_factor_d;
};

/// A component too large for dense factors: its rows in AMD order of J_B J_B' (once per solve),
/// its Gram matrices scaled and shifted once, and one masked sparse factor per use (the face,
/// the face's Jacobi Gram, the chopped LCP's set, the projection LCP's set), each modified by
/// row additions and deletions as its set moves (solvers/masked_gram_factor.hpp). Measured on
/// flank_press frame 0 (1152 rows, one component, 101 iterations): 994 LCP steps, 6332 row
/// modifications, 73 refactorisations, 355 solves on an unchanged set; before (a fresh Eigen
/// simplicial factor per face and per pivot) 945 factorisations with their symbolic analyses.
class LargeBlock final : public RowBlock {
public:
    LargeBlock(const SpMat& J, std::vector<int> rows, const Vec& dinv, const CoupledOperatorOptions& opt)
        : RowBlock(std::move(rows)), m_jacobi(opt.jacobi), m_max_pivots(opt.lcp_max_pivots),
          m_max_sweeps(opt.pgs_max_sweeps)
    {
        {
            const SpMat JB = block_rows(J, m_rows);
            const SpMatCol pattern = SpMatCol(JB * JB.transpose());
            Eigen::AMDOrdering<int> amd;
            Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> order;  // order.indices()[new] = old
            amd(pattern, order);
            std::vector<int> reordered(m_rows.size());
            for (size_t k = 0; k < m_rows.size(); ++k)
                reordered[k] = m_rows[static_cast<size_t>(order.indices()[static_cast<Eigen::Index>(k)])];
            m_rows = std::move(reordered);
        }
        const SpMat JB = block_rows(J, m_rows);
        m_gram = SpMatCol(JB * JB.transpose());
        m_gram.makeCompressed();
        const long max_updates = std::max(1L, opt.sparse_max_updates);
        // Rows that join the face join the chopped LCP's start set (RowBlock::set_face): the first
        // face's start is then the whole face, whose solve is nu on the face factor's mask (copied,
        // MaskedGramFactor::set_mask), and the negative rows leave, where an empty start added the
        // rows in blocks of hundreds, each refactored. Rows that stay keep their last state (flank_press
        // frame 0: chopped LCP steps 60 -> 49, row modifications 510 -> 404).
        m_fresh_face_set = 1;
        m_scale = unit_diagonal_scale(m_gram);
        m_face_factor = std::make_unique<MaskedGramFactor>(scaled_shifted(m_gram, m_scale), max_updates);
        m_chopped_factor = std::make_unique<MaskedGramFactor>(scaled_shifted(m_gram, m_scale), max_updates);
        for (auto& f : m_projection_factors)
            f = std::make_unique<MaskedGramFactor>(scaled_shifted(m_gram, m_scale), max_updates);
        for (auto& set : m_use_sets) set.assign(m_rows.size(), 0);
        if (m_jacobi) {
            const SpMatCol gram_d = SpMatCol(JB * dinv.asDiagonal() * JB.transpose());
            m_scale_d = unit_diagonal_scale(gram_d);
            m_face_factor_d = std::make_unique<MaskedGramFactor>(scaled_shifted(gram_d, m_scale_d), max_updates);
        }
        // The factors of the scaled, shifted J_B J_B' are donors to each other (MaskedGramFactor::set_mask):
        // an expansion's projection set nearly equals the next face, the face the chopped set.
        m_donors = {m_face_factor.get(), m_chopped_factor.get(), m_projection_factors[0].get(),
                    m_projection_factors[1].get(), m_projection_factors[2].get()};
        m_scaled = scaled_shifted(m_gram, m_scale);
        for (auto& d : m_dense_sets) d = std::make_unique<DenseSetFactor>(m_scaled, DENSE_SET_MAX_ROWS);
        const size_t k = m_rows.size();
        m_all.resize(k);
        std::iota(m_all.begin(), m_all.end(), 0);
        m_mask.assign(k, 0);
        m_b.setZero(static_cast<Eigen::Index>(k));
        m_z.setZero(static_cast<Eigen::Index>(k));
        m_cur.setZero(static_cast<Eigen::Index>(k));
        m_w.setZero(static_cast<Eigen::Index>(k));
        m_bad.reserve(k);
    }

    void face_solve(const double* rhs, double* out, bool weighted, Counters& cnt) override
    {
        MaskedGramFactor& f = weighted ? *m_face_factor_d : *m_face_factor;
        const Vec& sc = weighted ? m_scale_d : m_scale;
        const size_t q = m_face.size();
        if (weighted && m_face_d_stale) {
            std::fill(m_mask.begin(), m_mask.end(), 0);
            for (int r : m_face) m_mask[static_cast<size_t>(r)] = 1;
            f.set_mask(m_mask, cnt);
            m_face_d_stale = false;
        }
        if (!f.ok()) {
            for (size_t r = 0; r < q; ++r) out[r] = 0.0;
            return;
        }
        m_b.setZero();
        for (size_t r = 0; r < q; ++r) m_b[m_face[r]] = sc[m_face[r]] * rhs[r];
        f.solve(m_b.data(), cnt);
        for (size_t r = 0; r < q; ++r) out[r] = sc[m_face[r]] * m_b[m_face[r]];
    }
    bool face_lcp(const double* q, double* mu, Counters& cnt, LcpTally& tally) override
    {
        return lcp(m_face, q, nullptr, m_face_set, *m_chopped_factor, nullptr, mu, cnt, tally);
    }
    bool block_lcp(const double* q, double* lam, const char* fixed, int use, Counters& cnt, LcpTally& tally) override
    {
        const size_t u = static_cast<size_t>(use);
        return lcp(m_all, q, fixed, m_use_sets[u], *m_projection_factors[u], m_dense_sets[u].get(), lam, cnt, tally);
    }
    void add_tally(MaskedFactorTally& t) const override
    {
        for (const MaskedGramFactor* f :
             {m_face_factor.get(), m_face_factor_d.get(), m_chopped_factor.get(), m_projection_factors[0].get(),
              m_projection_factors[1].get(), m_projection_factors[2].get()}) {
            if (f == nullptr) continue;
            t.refactorizations += f->tally().refactorizations;
            t.row_additions += f->tally().row_additions;
            t.row_deletions += f->tally().row_deletions;
            t.reuses += f->tally().reuses;
            t.copies += f->tally().copies;
        }
        t.dense_set_solves += m_dense_solves;
        for (const auto& d : m_dense_sets) {
            t.dense_set_appends += d->appends();
            t.dense_set_removals += d->removals();
            t.dense_set_rebuilds += d->rebuilds();
        }
    }

private:
    static Vec unit_diagonal_scale(const SpMatCol& G)
    {
        Vec sc(G.rows());
        for (Eigen::Index i = 0; i < G.rows(); ++i) {
            const double d = G.coeff(i, i);
            sc[i] = d > 0.0 ? 1.0 / std::sqrt(d) : 1.0;
        }
        return sc;
    }
    static SpMatCol scaled_shifted(const SpMatCol& G, const Vec& sc)
    {
        SpMatCol S = SpMatCol(sc.asDiagonal() * G * sc.asDiagonal());
        for (Eigen::Index i = 0; i < S.rows(); ++i) S.coeffRef(i, i) += GRAM_SHIFT;
        return S;
    }

    void refactor(Counters& cnt) override
    {
        std::fill(m_mask.begin(), m_mask.end(), 0);
        for (int r : m_face) m_mask[static_cast<size_t>(r)] = 1;
        m_face_factor->set_mask(m_mask, cnt, &m_donors);
        // The weighted factor follows on its first solve: a face that only passes through (the
        // expansion's intermediate face, which needs phi but no z) is never factored weighted.
        m_face_d_stale = m_jacobi;
    }

    /// m_z = G(S, S)^-1 q_S on the set S (zero off it), with the set's factor modified to S.
    bool solve_on_set(const std::vector<int>& universe, const double* q, const std::vector<char>& set,
                      MaskedGramFactor& f, DenseSetFactor* dense, Counters& cnt)
    {
        std::fill(m_mask.begin(), m_mask.end(), 0);
        int in = 0;
        for (size_t r = 0; r < universe.size(); ++r)
            if (set[r]) {
                m_mask[static_cast<size_t>(universe[r])] = 1;
                ++in;
            }
        if (in == 0) {
            // Nothing to factor: z = 0, and the factor stays warm for the next set (flank_press
            // frame 0: 5 refactorisations to the identity before).
            m_z.setZero();
            ++cnt.lcp_iterations;
            return true;
        }
        // A small set on its dense factor; else (or when that factor refuses) the masked sparse one.
        const bool on_dense = dense != nullptr && in <= dense->capacity() && dense->set_mask(m_mask, cnt);
        if (!on_dense && !f.set_mask(m_mask, cnt, &m_donors)) return false;
        m_b.setZero();
        for (size_t r = 0; r < universe.size(); ++r)
            if (set[r]) m_b[universe[r]] = m_scale[universe[r]] * q[r];
        if (on_dense) {
            dense->solve(m_b.data(), cnt);
            ++m_dense_solves;
        } else {
            f.solve(m_b.data(), cnt);
        }
        m_z = m_scale.cwiseProduct(m_b);
        ++cnt.lcp_iterations;
        return true;
    }

    /// 0 <= lam perp G(U, U) lam - q >= 0 over the block rows U = `universe`, warm-started from
    /// `set` (per U row): a primal active-set method (Lawson and Hanson's NNLS loop on the convex
    /// QP min 1/2 lam'G lam - q'lam, lam >= 0) that keeps lam feasible and F decreasing, so a
    /// set moves by the rows that really enter or leave and each move is a row modification
    /// of the set's factor. Block principal pivoting, which flips every infeasible row at once,
    /// cycled here: on flank_press frame 0 it took 946 pivots and 8933 row flips (Murty's single
    /// flips ran up to 71 pivots in one LCP). Rows flagged in `fixed` are equalities (lam of
    /// either sign, never leave). At most lcp_max_pivots + 2 |U| steps, then PGS.
    /// `dense` (may be null): the set's dense factor, used while the set has at most its capacity rows.
    bool lcp(const std::vector<int>& universe, const double* q, const char* fixed, std::vector<char>& set,
             MaskedGramFactor& f, DenseSetFactor* dense, double* lam, Counters& cnt, LcpTally& tally)
    {
        ++tally.solves;
        const size_t ku = universe.size();
        for (size_t r = 0; r < ku; ++r) lam[r] = 0.0;
        if (ku == 0) return true;
        if (set.size() != ku) set.assign(ku, 0);
        auto is_fixed = [&](size_t r) { return fixed != nullptr && fixed[r] != 0; };
        double qinf = 0.0;
        for (size_t r = 0; r < ku; ++r) {
            if (is_fixed(r)) set[r] = 1;
            qinf = std::max(qinf, std::abs(q[r]));
        }
        const double tol_w = 1e-12 * std::max(1.0, qinf);
        m_added.assign(ku, 0);
        // A feasible start from the warm set: the set's solution with its negative rows dropped.
        m_cur.setZero();
        bool solved = solve_on_set(universe, q, set, f, dense, cnt);
        bool dropped = false;  // else m_z is already the first step's solve on the same set
        if (solved) {
            for (size_t r = 0; r < ku; ++r) {
                if (!set[r]) continue;
                const int j = universe[r];
                if (is_fixed(r) || m_z[j] > 0.0) {
                    m_cur[j] = m_z[j];
                } else {
                    set[r] = 0;
                    dropped = true;
                }
            }
        }
        // Blocks of rows leave (every negative one) and enter (every one with w < 0) while the
        // objective at the set minimisers decreases; after a step that did not, or an addition undone
        // at once, the method goes careful: ratio tests and one entering row at a time (finite).
        bool careful = false;
        double best_f = std::numeric_limits<double>::infinity();
        const long max_steps = m_max_pivots + 2 * static_cast<long>(ku);
        for (long step = 0; solved && step < max_steps; ++step) {
            if ((step > 0 || dropped) && !(solved = solve_on_set(universe, q, set, f, dense, cnt))) break;
            double zinf = 0.0;
            for (size_t r = 0; r < ku; ++r)
                if (set[r]) zinf = std::max(zinf, std::abs(m_z[universe[r]]));
            const double tol_l = 1e-12 * std::max(1e-300, zinf);
            // Ratio test: the longest step from m_cur towards z that keeps lam >= 0.
            double alpha = 1.0;
            bool blocked = false;
            for (size_t r = 0; r < ku; ++r) {
                const int j = universe[r];
                if (!set[r] || is_fixed(r) || !(m_z[j] < -tol_l)) continue;
                alpha = std::min(alpha, m_cur[j] / (m_cur[j] - m_z[j]));
                blocked = true;
            }
            if (blocked && !careful) {
                for (size_t r = 0; r < ku; ++r) {
                    if (!set[r]) continue;
                    const int j = universe[r];
                    if (!is_fixed(r) && m_z[j] < -tol_l) {
                        set[r] = 0;
                        m_cur[j] = 0.0;
                    } else {
                        m_cur[j] = is_fixed(r) ? m_z[j] : std::max(0.0, m_z[j]);
                    }
                }
                continue;
            }
            if (blocked) {
                bool undid_addition = false;
                for (size_t r = 0; r < ku; ++r) {
                    if (!set[r]) continue;
                    const int j = universe[r];
                    m_cur[j] += alpha * (m_z[j] - m_cur[j]);
                    if (!is_fixed(r) && m_z[j] < -tol_l && m_cur[j] <= tol_l) {
                        set[r] = 0;
                        m_cur[j] = 0.0;
                        undid_addition = undid_addition || (m_added[r] && alpha == 0.0);
                    }
                }
                careful = careful || undid_addition;
                continue;
            }
            // z >= 0 on the set: the minimiser there. Rows off the set with w < 0 enter.
            for (size_t r = 0; r < ku; ++r)
                if (set[r]) m_cur[universe[r]] = is_fixed(r) ? m_z[universe[r]] : std::max(0.0, m_z[universe[r]]);
            // w = G cur over the columns of the set only (projection sets hold 10-100 of flank_press's
            // 1152 rows); the same sums in the same order as the full product.
            m_w.setZero();
            long touched = 0;
            for (Eigen::Index j = 0; j < m_gram.outerSize(); ++j) {
                const double cj = m_cur[j];
                if (cj == 0.0) continue;
                for (SpMatCol::InnerIterator it(m_gram, j); it; ++it) m_w[it.index()] += it.value() * cj;
                touched += m_gram.outerIndexPtr()[j + 1] - m_gram.outerIndexPtr()[j];
            }
            cnt.work_flops += sparse_product_flops(static_cast<double>(touched));
            double f_set = 0.0;  // 1/2 lam'G lam - q'lam
            for (size_t r = 0; r < ku; ++r)
                if (set[r]) f_set += m_cur[universe[r]] * (0.5 * m_w[universe[r]] - q[r]);
            careful = careful || !(f_set < best_f);
            best_f = std::min(best_f, f_set);
            const bool single = careful;
            std::fill(m_added.begin(), m_added.end(), 0);
            size_t worst = ku;
            double worst_w = -tol_w;
            bool entered = false;
            for (size_t r = 0; r < ku; ++r) {
                if (set[r]) continue;
                const double w = m_w[universe[r]] - q[r];
                if (!(w < -tol_w)) continue;
                if (!single) {
                    set[r] = m_added[r] = 1;
                    entered = true;
                } else if (w < worst_w) {
                    worst_w = w;
                    worst = r;
                }
            }
            if (single && worst < ku) {
                set[worst] = m_added[worst] = 1;
                entered = true;
            }
            if (!entered) {
                for (size_t r = 0; r < ku; ++r) lam[r] = m_cur[universe[r]];
                return true;
            }
        }
        ++tally.pgs_fallbacks;
        const SpMatCol M = submatrix(m_gram, universe);
        Vec lambda(static_cast<Eigen::Index>(ku));
        for (size_t r = 0; r < ku; ++r) lambda[static_cast<Eigen::Index>(r)] = m_cur[universe[r]];
        const bool ok = projected_gauss_seidel(M, Eigen::Map<const Vec>(q, static_cast<Eigen::Index>(ku)), fixed, set,
                                               lambda, cnt, m_max_sweeps);
        Eigen::Map<Vec>(lam, static_cast<Eigen::Index>(ku)) = lambda;
        return ok;
    }

    bool m_jacobi;
    long m_max_pivots, m_max_sweeps;
    SpMatCol m_gram;  // J_B J_B' in block order, unscaled
    Vec m_scale, m_scale_d;
    std::unique_ptr<MaskedGramFactor> m_face_factor, m_face_factor_d, m_chopped_factor;
    std::array<std::unique_ptr<MaskedGramFactor>, PROJECTION_USES> m_projection_factors;
    std::array<std::vector<char>, PROJECTION_USES> m_use_sets;
    std::vector<const MaskedGramFactor*> m_donors;
    SpMatCol m_scaled;  // the scaled, shifted J_B J_B' (the dense set factors read it)
    bool m_face_d_stale = false;  // m_face_factor_d not yet on the current face
    std::array<std::unique_ptr<DenseSetFactor>, PROJECTION_USES> m_dense_sets;
    long m_dense_solves = 0;
    std::vector<int> m_all, m_bad;
    std::vector<char> m_mask, m_added;
    Vec m_b, m_z, m_cur, m_w;
};

}  // namespace

CoupledFaceOperators::CoupledFaceOperators(const SpMat& J, const Vec& dinv, const CoupledOperatorOptions& options)
    : CoupledFaceOperators(J, dinv, options, find_row_components(J))
{
}

CoupledFaceOperators::CoupledFaceOperators(const SpMat& J, const Vec& dinv, const CoupledOperatorOptions& options,
                                           RowComponents components)
    : m_opt(options), m_comp(std::move(components))
{
    const Eigen::Index m = J.rows();
    m_s.resize(m);
    for (Eigen::Index i = 0; i < m; ++i) {
        double s = 0.0;
        for (SpMat::InnerIterator it(J, i); it; ++it) s += it.value() * it.value();
        m_s[i] = s;
    }
    m_block_of_component.assign(static_cast<size_t>(m_comp.count()), 0);
    if (m_opt.global) {
        std::vector<int> all(static_cast<size_t>(m));
        std::iota(all.begin(), all.end(), 0);
        if (m > 0) {
            m_blocks.push_back(std::make_unique<SparseBlock>(J, std::move(all), dinv, m_opt));
            ++m_sparse_blocks;
        }
    } else {
        std::vector<double> scatter(static_cast<size_t>(J.cols()), 0.0);
        for (int k = 0; k < m_comp.count(); ++k) {
            std::vector<int> rows(m_comp.rows.begin() + m_comp.start[static_cast<size_t>(k)],
                                  m_comp.rows.begin() + m_comp.start[static_cast<size_t>(k) + 1]);
            m_block_of_component[static_cast<size_t>(k)] = static_cast<int>(m_blocks.size());
            if (static_cast<long>(rows.size()) <= m_opt.dense_max_rows) {
                m_blocks.push_back(std::make_unique<DenseBlock>(J, std::move(rows), dinv, m_opt, scatter));
                ++m_dense_blocks;
            } else {
                m_blocks.push_back(std::make_unique<LargeBlock>(J, std::move(rows), dinv, m_opt));
                ++m_sparse_blocks;
            }
        }
    }
    m_block_violated.assign(m_blocks.size(), 0);
}

CoupledFaceOperators::~CoupledFaceOperators() = default;

void CoupledFaceOperators::set_face(const std::vector<char>& active, Counters& cnt)
{
    for (auto& b : m_blocks)
        if (b->set_face(active, m_s, cnt) && !b->face().empty()) ++m_face_refactorizations;
}

namespace {

/// Gathers v on the block's face rows into buf (face order).
void gather_face(const RowBlock& b, const Vec& v, std::vector<double>& buf)
{
    const std::vector<int>& face = b.face();
    for (size_t r = 0; r < face.size(); ++r) buf[r] = v[b.rows()[static_cast<size_t>(face[r])]];
}

void scatter_face(const RowBlock& b, const std::vector<double>& buf, Vec& v)
{
    const std::vector<int>& face = b.face();
    for (size_t r = 0; r < face.size(); ++r) v[b.rows()[static_cast<size_t>(face[r])]] = buf[r];
}

// Per-thread workspace sized on first use (the largest block), so the loop does not allocate.
std::vector<double>& workspace(size_t size, int which)
{
    thread_local std::vector<double> buf[3];
    if (buf[which].size() < size) buf[which].resize(size);
    return buf[which];
}

}  // namespace

void CoupledFaceOperators::face_multipliers(const Vec& jg, Vec& nu, Counters& cnt)
{
    nu.setZero();
    for (auto& b : m_blocks) {
        const size_t q = b->face().size();
        if (q == 0) continue;
        std::vector<double>& in = workspace(q, 0);
        std::vector<double>& out = workspace(q, 1);
        gather_face(*b, jg, in);
        b->face_solve(in.data(), out.data(), false, cnt);
        scatter_face(*b, out, nu);
    }
}

void CoupledFaceOperators::jacobi_multipliers(const Vec& jdg, Vec& eta, Counters& cnt)
{
    eta.setZero();
    for (auto& b : m_blocks) {
        const size_t q = b->face().size();
        if (q == 0) continue;
        std::vector<double>& in = workspace(q, 0);
        std::vector<double>& out = workspace(q, 1);
        gather_face(*b, jdg, in);
        b->face_solve(in.data(), out.data(), true, cnt);
        scatter_face(*b, out, eta);
    }
}

void CoupledFaceOperators::chopped_multipliers(const Vec& q, const Vec& nu, Vec& mu, Counters& cnt)
{
    mu.setZero();
    LcpTally tally{m_pgs_fallbacks, m_lcp_solves};
    for (auto& b : m_blocks) {
        const size_t k = b->face().size();
        if (k == 0) continue;
        if (!m_opt.global) {
            // nu >= 0 on the face solves the LCP (q = G_AA nu up to rounding): beta = 0 here.
            bool nonnegative = true;
            for (int r : b->face()) nonnegative = nonnegative && nu[b->rows()[static_cast<size_t>(r)]] >= 0.0;
            if (nonnegative) {
                for (int r : b->face()) mu[b->rows()[static_cast<size_t>(r)]] = nu[b->rows()[static_cast<size_t>(r)]];
                ++m_fast_paths;
                continue;
            }
        }
        std::vector<double>& in = workspace(k, 0);
        std::vector<double>& out = workspace(k, 1);
        gather_face(*b, q, in);
        if (!b->face_lcp(in.data(), out.data(), cnt, tally)) ++m_lcp_failures;
        scatter_face(*b, out, mu);
    }
}

long CoupledFaceOperators::projection_multipliers(Vec& q, const std::vector<char>& violated, Vec& lam, Counters& cnt,
                                                  const std::vector<char>* keep, ProjectionUse use)
{
    lam.setZero();
    const Eigen::Index m = q.size();
    // A component with no violated row keeps lam = 0: clip its q to <= 0 so that the global LCP
    // gives the same answer as the per-component ones.
    std::vector<char>& comp_violated = m_block_violated;  // reused, sized to blocks; components below
    thread_local std::vector<char> by_component;
    by_component.assign(static_cast<size_t>(m_comp.count()), 0);
    for (Eigen::Index i = 0; i < m; ++i)
        if (violated[static_cast<size_t>(i)])
            by_component[static_cast<size_t>(m_comp.of_row[static_cast<size_t>(i)])] = 1;
    std::fill(comp_violated.begin(), comp_violated.end(), 0);
    long solved = 0;
    for (int k = 0; k < m_comp.count(); ++k) {
        if (by_component[static_cast<size_t>(k)]) {
            comp_violated[static_cast<size_t>(m_block_of_component[static_cast<size_t>(k)])] = 1;
            ++solved;
        } else {
            for (int r = m_comp.start[static_cast<size_t>(k)]; r < m_comp.start[static_cast<size_t>(k) + 1]; ++r)
                q[m_comp.rows[static_cast<size_t>(r)]] = std::min(0.0, q[m_comp.rows[static_cast<size_t>(r)]]);
        }
    }
    if (solved == 0) return 0;
    LcpTally tally{m_pgs_fallbacks, m_lcp_solves};
    for (size_t bi = 0; bi < m_blocks.size(); ++bi) {
        if (!comp_violated[bi]) continue;
        RowBlock& b = *m_blocks[bi];
        const size_t k = b.rows().size();
        std::vector<double>& in = workspace(k, 0);
        std::vector<double>& out = workspace(k, 1);
        for (size_t r = 0; r < k; ++r) in[r] = q[b.rows()[r]];
        const char* fixed = nullptr;
        if (keep != nullptr) {
            m_fixed.resize(k);
            for (size_t r = 0; r < k; ++r) m_fixed[r] = (*keep)[static_cast<size_t>(b.rows()[r])];
            fixed = m_fixed.data();
        }
        if (!b.block_lcp(in.data(), out.data(), fixed, static_cast<int>(use), cnt, tally)) ++m_lcp_failures;
        for (size_t r = 0; r < k; ++r) lam[b.rows()[r]] = out[r];
    }
    return solved;
}

nlohmann::json CoupledFaceOperators::stats() const
{
    MaskedFactorTally t;
    for (const auto& b : m_blocks) b->add_tally(t);
    return {{"operators", m_opt.global ? "global" : "components"},
            {"components", m_comp.count()},
            {"largest_component", m_comp.largest()},
            {"singleton_components", m_comp.singletons()},
            {"dense_blocks", m_dense_blocks},
            {"sparse_blocks", m_sparse_blocks},
            {"dense_max_rows", m_opt.dense_max_rows},
            {"face_refactorizations", m_face_refactorizations},
            {"chopped_fast_paths", m_fast_paths},
            {"lcp_solves", m_lcp_solves},
            {"pgs_fallbacks", m_pgs_fallbacks},
            {"lcp_failures", m_lcp_failures},
            {"sparse_refactorizations", t.refactorizations},
            {"sparse_row_additions", t.row_additions},
            {"sparse_row_deletions", t.row_deletions},
            {"sparse_factor_reuses", t.reuses},
            {"sparse_factor_copies", t.copies},
            {"dense_set_solves", t.dense_set_solves},
            {"dense_set_appends", t.dense_set_appends},
            {"dense_set_removals", t.dense_set_removals},
            {"dense_set_rebuilds", t.dense_set_rebuilds}};
}

}  // namespace cb
