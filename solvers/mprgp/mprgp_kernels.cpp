// Closed-form MPRGP operators for decoupled J (ALGORITHMS.md §2) and the power method.
// Ref: Li et al., "Deformable Objects Collision Handling with Fast Convergence", CGF 2015,
//      eq. (13), (15)-(20); Alg. 1-3. With JJ' diagonal every subproblem is row-separable.
#include "solvers/mprgp/mprgp_kernels.hpp"

#include "solvers/linalg/a_product.hpp"
#include "solvers/linalg/avx2_lanes.hpp"
#include "solvers/measure/accuracy.hpp"

#include <algorithm>
#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>
#endif
#include <cmath>
#include <cstring>
#include <random>

namespace cb {

DecoupledRows make_decoupled_rows(const SpMat& J, const Vec& dinv)
{
    DecoupledRows rows;
    const Eigen::Index m = J.rows();
    rows.s.resize(m);
    rows.inv_s.resize(m);
    rows.r.resize(m);
    rows.dof_in_row.assign(static_cast<size_t>(J.cols()), 0);
    for (Eigen::Index i = 0; i < m; ++i) {
        double s = 0.0, w = 0.0;
        for (SpMat::InnerIterator it(J, i); it; ++it) {
            s += it.value() * it.value();
            w += it.value() * it.value() * dinv[it.col()];
            if (it.value() != 0.0) rows.dof_in_row[static_cast<size_t>(it.col())] = 1;  // explicit zeros do not count
        }
        rows.s[i] = s;
        rows.inv_s[i] = s > 0.0 ? 1.0 / s : 0.0;
        rows.r[i] = w > 0.0 ? 1.0 / w : 0.0;
    }
    return rows;
}

void active_rows(const SpMat& J, const Vec& c, const DecoupledRows& rows, const Vec& x, std::vector<char>& active)
{
    active.assign(static_cast<size_t>(J.rows()), 0);
    for (Eigen::Index i = 0; i < J.rows(); ++i) {
        if (rows.s[i] <= 0.0) continue;
        active[static_cast<size_t>(i)] = std::abs(row_dot(J, i, x) - c[i]) <= active_tolerance(c[i]);
    }
}

long project_decoupled(const SpMat& J, const Vec& c, const DecoupledRows& rows, const Vec& x, Vec& y, Vec* lambda)
{
    if (&y != &x) y = x;
    if (lambda) lambda->setZero(J.rows());
    long moved = 0;
    for (Eigen::Index i = 0; i < J.rows(); ++i) {
        if (rows.s[i] <= 0.0) continue;
        // Rows share no DOF, so each row's correction leaves the others' J_k y unchanged.
        const double l = (c[i] - row_dot(J, i, y)) * rows.inv_s[i];
        if (l > 0.0) {
            row_axpy(J, i, l, y);
            ++moved;
            if (lambda) (*lambda)[i] = l;
        }
    }
    return moved;
}

void free_gradient(const SpMat& J, const DecoupledRows& rows, const std::vector<char>& active, const Vec& g, Vec& phi)
{
    phi = g;
    for (Eigen::Index i = 0; i < J.rows(); ++i)
        if (active[static_cast<size_t>(i)]) row_axpy(J, i, -row_dot(J, i, g) * rows.inv_s[i], phi);
}

void chopped_gradient(const SpMat& J, const DecoupledRows& rows, const std::vector<char>& active, const Vec& g,
                      Vec& beta)
{
    beta.setZero(g.size());
    for (Eigen::Index i = 0; i < J.rows(); ++i) {
        if (!active[static_cast<size_t>(i)]) continue;
        const double t = row_dot(J, i, g) * rows.inv_s[i];
        if (t < 0.0) row_axpy(J, i, t, beta);
    }
}

double reduced_free_gradient_dot(const SpMat& J, const Vec& c, const DecoupledRows& rows, const Vec& x, const Vec& phi,
                                 double alpha_bar)
{
    const Vec trial = x - alpha_bar * phi;
    Vec projected;
    project_decoupled(J, c, rows, trial, projected);
    return (x - projected).dot(phi) / alpha_bar;
}

void decoupled_multipliers(const SpMat& J, const DecoupledRows& rows, const std::vector<char>& active, const Vec& g,
                           Vec& lambda)
{
    lambda.setZero(J.rows());
    for (Eigen::Index i = 0; i < J.rows(); ++i)
        if (active[static_cast<size_t>(i)]) lambda[i] = std::max(0.0, row_dot(J, i, g) * rows.inv_s[i]);
}

void jacobi_face_precondition(const SpMat& J, const DecoupledRows& rows, const std::vector<char>& active,
                              const Vec& dinv, const Vec& g, Vec& z)
{
    z = dinv.cwiseProduct(g);
    const int* outer = J.outerIndexPtr();
    const int* inner = J.innerIndexPtr();
    const double* val = J.valuePtr();
    for (Eigen::Index i = 0; i < J.rows(); ++i) {
        if (!active[static_cast<size_t>(i)]) continue;
        double wg = 0.0;  // (W g)_i = J_i D^-1 g = J_i z before the correction
        for (int k = outer[i]; k < outer[i + 1]; ++k) wg += val[k] * z[inner[k]];
        const double mu = rows.r[i] * wg;
        for (int k = outer[i]; k < outer[i + 1]; ++k) z[inner[k]] -= mu * val[k] * dinv[inner[k]];
    }
}

PowerResult power_method(const AOperator& A, Vec& v, PowerRule rule, long max_products, double tol, bool warm,
                         std::uint64_t seed, bool (*deadline_check)(void*), void* deadline_data)
{
    PowerResult result;
    const Eigen::Index n = A.rows();
    if (n == 0) return result;
    const bool use_warm = warm && rule == PowerRule::POWER && v.size() == n && v.allFinite() && v.norm() > 0.0;
    if (use_warm) {
        v.normalize();
        result.warm = true;
    } else {
        // Seeded, strictly positive start: never orthogonal to the Perron-like top eigenvector
        // of a mass-dominated A, and reproducible.
        std::mt19937_64 rng(seed ^ 0x9e3779b97f4a7c15ULL);
        std::uniform_real_distribution<double> unit(0.5, 1.5);
        v.resize(n);
        for (Eigen::Index i = 0; i < n; ++i) v[i] = unit(rng);
        v.normalize();
    }
    Vec w(n);
    double previous = 0.0;
    for (long k = 0; k < max_products; ++k) {
        a_product(A, v, w);
        ++result.products;
        const double norm_w = w.norm();
        if (!(norm_w > 0.0) || !std::isfinite(norm_w)) break;
        result.estimate = norm_w;
        w /= norm_w;
        if (rule == PowerRule::AUTHORS) {
            const double change = (w - v).norm();
            v.swap(w);
            if (change <= tol) break;
        } else {
            v.swap(w);
            if (k > 0 && std::abs(norm_w - previous) <= 1e-3 * norm_w) break;
        }
        previous = norm_w;
        if (deadline_check && deadline_check(deadline_data)) break;
    }
    return result;
}

namespace {

/// An accepted CG step on entry j: x_j -= alpha p_j and g_j -= alpha ap_j, each a product, then a
/// difference; returns the new g_j. Shared by both step passes below and their AVX2 forms.
inline double step_entry(double alpha, const double* p, const double* ap, double* x, double* g, Eigen::Index j)
{
    x[j] -= alpha * p[j];
    const double gj = g[j] - alpha * ap[j];
    g[j] = gj;
    return gj;
}

#if defined(__x86_64__) && defined(__GNUC__)
/// step_entry on entries j .. j + 3 (apj: ap's four entries there); returns the new g's.
__attribute__((target("avx2"))) inline __m256d step_packet(__m256d alpha, const double* p, __m256d apj, double* x,
                                                           double* g, Eigen::Index j)
{
    _mm256_storeu_pd(x + j, _mm256_sub_pd(_mm256_loadu_pd(x + j), _mm256_mul_pd(alpha, _mm256_loadu_pd(p + j))));
    const __m256d gj = _mm256_sub_pd(_mm256_loadu_pd(g + j), _mm256_mul_pd(alpha, apj));
    _mm256_storeu_pd(g + j, gj);
    return gj;
}
#endif

double cg_step_pass_scalar(double alpha, const double* __restrict p, const double* __restrict ap,
                           const double* __restrict w, double* __restrict x, double* __restrict g,
                           double* __restrict phi, Eigen::Index n)
{
    double widest = 0.0;
    for (Eigen::Index j = 0; j < n; ++j) {
        const double gj = step_entry(alpha, p, ap, x, g, j);
        phi[j] = gj;
        widest = std::max(widest, std::abs(gj) * w[j]);
    }
    return widest;
}

#if defined(__x86_64__) && defined(__GNUC__)
__attribute__((target("avx2"))) double cg_step_pass_avx2(double alpha, const double* __restrict p,
                                                         const double* __restrict ap, const double* __restrict w,
                                                         double* __restrict x, double* __restrict g,
                                                         double* __restrict phi, Eigen::Index n)
{
    const __m256d a = _mm256_set1_pd(alpha);
    const __m256d sign = _mm256_set1_pd(-0.0);
    __m256d widest = _mm256_setzero_pd();
    Eigen::Index j = 0;
    for (; j + 4 <= n; j += 4) {
        const __m256d gj = step_packet(a, p, _mm256_loadu_pd(ap + j), x, g, j);
        _mm256_storeu_pd(phi + j, gj);
        // max(term, widest): a NaN term keeps widest, as std::max(widest, term) does.
        widest = _mm256_max_pd(_mm256_mul_pd(_mm256_andnot_pd(sign, gj), _mm256_loadu_pd(w + j)), widest);
    }
    const double lanes = max_lane_clearing_upper(widest);
    return std::max(lanes, cg_step_pass_scalar(alpha, p + j, ap + j, w + j, x + j, g + j, phi + j, n - j));
}
#endif

}  // namespace

double cg_step_pass(double alpha, const Vec& p, const Vec& ap, const Vec& w, Vec& x, Vec& g, Vec& phi)
{
#if defined(__x86_64__) && defined(__GNUC__)
    static const bool avx2 = __builtin_cpu_supports("avx2");
    if (avx2) return cg_step_pass_avx2(alpha, p.data(), ap.data(), w.data(), x.data(), g.data(), phi.data(), x.size());
#endif
    return cg_step_pass_scalar(alpha, p.data(), ap.data(), w.data(), x.data(), g.data(), phi.data(), x.size());
}

namespace {

/// cg_update_pass from entry `first` on, the sums continued from `sums`.
void cg_update_scalar(double alpha, const double* __restrict p, const double* __restrict ap,
                      const double* __restrict dinv, const double* __restrict w, const char* __restrict in_row,
                      double* __restrict x, double* __restrict g, double* __restrict z, Eigen::Index first,
                      Eigen::Index n, CgUpdateSums& sums)
{
    for (Eigen::Index j = first; j < n; ++j) {
        const double gj = step_entry(alpha, p, ap, x, g, j);
        const double zj = dinv[j] * gj;
        z[j] = zj;
        if (!in_row[j]) {
            sums.zg += zj * gj;
            sums.zap += zj * ap[j];
            sums.ginf = std::max(sums.ginf, std::abs(gj) * w[j]);
            sums.gg += gj * gj;
        }
    }
}

#if defined(__x86_64__) && defined(__GNUC__)
/// sum + v[0] + v[1] + v[2] + v[3], one addition after another (the plain loop's order). Through
/// memory, not lane shuffles: valgrind 3.19, which the perf gate counts instructions with, cannot
/// decode the register form of vmovq that the shuffles compiled to.
__attribute__((target("avx2"))) inline double add_lanes_in_order(double sum, __m256d v)
{
    alignas(32) double lane[4];
    _mm256_store_pd(lane, v);
    sum += lane[0];
    sum += lane[1];
    sum += lane[2];
    sum += lane[3];
    return sum;
}

__attribute__((target("avx2"))) CgUpdateSums cg_update_avx2(double alpha, const double* __restrict p,
                                                            const double* __restrict ap, const double* __restrict dinv,
                                                            const double* __restrict w, const char* __restrict in_row,
                                                            double* __restrict x, double* __restrict g,
                                                            double* __restrict z, Eigen::Index n)
{
    const __m256d a = _mm256_set1_pd(alpha);
    const __m256d sign = _mm256_set1_pd(-0.0);
    __m256d widest = _mm256_setzero_pd();
    CgUpdateSums sums;
    Eigen::Index j = 0;
    for (; j + 4 <= n; j += 4) {
        const __m256d apj = _mm256_loadu_pd(ap + j);
        const __m256d gj = step_packet(a, p, apj, x, g, j);
        const __m256d zj = _mm256_mul_pd(_mm256_loadu_pd(dinv + j), gj);
        _mm256_storeu_pd(z + j, zj);
        int flags;
        std::memcpy(&flags, in_row + j, sizeof flags);
        // All ones on the DOFs in no row: their terms pass the mask, the others become +0.0.
        const __m256d keep = _mm256_castsi256_pd(
            _mm256_cmpeq_epi64(_mm256_cvtepi8_epi64(_mm_cvtsi32_si128(flags)), _mm256_setzero_si256()));
        sums.zg = add_lanes_in_order(sums.zg, _mm256_and_pd(keep, _mm256_mul_pd(zj, gj)));
        sums.zap = add_lanes_in_order(sums.zap, _mm256_and_pd(keep, _mm256_mul_pd(zj, apj)));
        sums.gg = add_lanes_in_order(sums.gg, _mm256_and_pd(keep, _mm256_mul_pd(gj, gj)));
        // max(term, widest): a NaN term keeps widest, as std::max(widest, term) does.
        const __m256d term = _mm256_and_pd(keep, _mm256_mul_pd(_mm256_andnot_pd(sign, gj), _mm256_loadu_pd(w + j)));
        widest = _mm256_max_pd(term, widest);
    }
    sums.ginf = max_lane_clearing_upper(widest);
    cg_update_scalar(alpha, p, ap, dinv, w, in_row, x, g, z, j, n, sums);
    return sums;
}
#endif

}  // namespace

CgUpdateSums cg_update_pass(double alpha, const Vec& p, const Vec& ap, const Vec& dinv, const Vec& w,
                            const char* in_row, Vec& x, Vec& g, Vec& z)
{
    const Eigen::Index n = x.size();
#if defined(__x86_64__) && defined(__GNUC__)
    static const bool avx2 = __builtin_cpu_supports("avx2");
    if (avx2)
        return cg_update_avx2(alpha, p.data(), ap.data(), dinv.data(), w.data(), in_row, x.data(), g.data(), z.data(),
                              n);
#endif
    CgUpdateSums sums;
    cg_update_scalar(alpha, p.data(), ap.data(), dinv.data(), w.data(), in_row, x.data(), g.data(), z.data(), 0, n,
                     sums);
    return sums;
}

void two_dots(const Vec& a, const Vec& b, const Vec& c, double& ab, double& ac)
{
    // Eigen 3.4's redux of a.cwiseProduct(b) for a dynamic vector (Redux.h, LinearVectorizedTraversal):
    // packets from entry 0 (Vec's data are aligned), two running packet sums over pairs of packets,
    // their sum, one more packet when an odd one is left, the packet's lanes summed, then the tail.
    using Packet = Eigen::internal::packet_traits<double>::type;
    constexpr Eigen::Index P = Eigen::internal::packet_traits<double>::size;
    const Eigen::Index n = a.size();
    const double* pa = a.data();
    const double* pb = b.data();
    const double* pc = c.data();
    const Eigen::Index whole = (n / P) * P, pairs = (n / (2 * P)) * (2 * P);
    if (n == 0 || whole == 0) {  // Eigen's plain loop (or 0 for no entry)
        ab = a.dot(b);
        ac = a.dot(c);
        return;
    }
    using Eigen::internal::padd;
    using Eigen::internal::pload;
    using Eigen::internal::pmul;
    Packet b0 = pmul(pload<Packet>(pa), pload<Packet>(pb));
    Packet c0 = pmul(pload<Packet>(pa), pload<Packet>(pc));
    if (whole > P) {
        Packet b1 = pmul(pload<Packet>(pa + P), pload<Packet>(pb + P));
        Packet c1 = pmul(pload<Packet>(pa + P), pload<Packet>(pc + P));
        for (Eigen::Index i = 2 * P; i < pairs; i += 2 * P) {
            const Packet a0 = pload<Packet>(pa + i), a1 = pload<Packet>(pa + i + P);
            b0 = padd(b0, pmul(a0, pload<Packet>(pb + i)));
            b1 = padd(b1, pmul(a1, pload<Packet>(pb + i + P)));
            c0 = padd(c0, pmul(a0, pload<Packet>(pc + i)));
            c1 = padd(c1, pmul(a1, pload<Packet>(pc + i + P)));
        }
        b0 = padd(b0, b1);
        c0 = padd(c0, c1);
        if (whole > pairs) {
            b0 = padd(b0, pmul(pload<Packet>(pa + pairs), pload<Packet>(pb + pairs)));
            c0 = padd(c0, pmul(pload<Packet>(pa + pairs), pload<Packet>(pc + pairs)));
        }
    }
    ab = Eigen::internal::predux(b0);
    ac = Eigen::internal::predux(c0);
    for (Eigen::Index i = whole; i < n; ++i) {
        ab += pa[i] * pb[i];
        ac += pa[i] * pc[i];
    }
}

}  // namespace cb
