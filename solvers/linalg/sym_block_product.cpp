// The product with the upper block triangle of a symmetric A (AFormat::SBSR; docs/a_product.md).
#include "solvers/linalg/sym_block_product.hpp"

#include <algorithm>
#include <cstring>

namespace cb {

namespace {

/// y = A x on the upper block triangle of a symmetric A (block (I, J), J >= I, stands for itself
/// and, when J > I, for its transpose at (J, I)); with D != NONE also x'y and x'w as above. Block
/// row I adds B x_J to y_I and scatters B' x_I into y_J (J > I): when row I is reached, every
/// block row before it has added its part to y_I, so y_I is complete there and its dots are
/// summed in the same pass. y_I's terms come in another order than the CSR row's, so y equals
/// CSR's to rounding, not to the bit. One thread: the scatter writes rows other threads would own.
/// Each block's three products are summed before they meet the row's sum (one dependent addition
/// per block, not three), and the dots in four partial sums (entry i into sum i mod 4, added
/// pairwise at the end: no chain of one addition per entry); the AVX2 kernel below sums in exactly
/// this order. (precond = scaled scales the stored blocks instead: AOperator::scale_by.)
template <Dots D>
double sym_block_product_scalar(const BlockRows& B, std::ptrdiff_t nb, const double* px, double* __restrict py,
                                const double* __restrict pw, const char* __restrict skip, double& xw,
                                DirectionUpdate update)
{
    const int* __restrict start = B.start.data();
    const int* __restrict column = B.column.data();
    const double* __restrict val = B.value.data();
    if (update.x != nullptr)
        for (std::ptrdiff_t i = 0; i < 3 * nb; ++i) update.x[i] = update.z[i] - update.beta * update.x[i];
    std::fill(py, py + 3 * nb, 0.0);
    double xy[4] = {0.0, 0.0, 0.0, 0.0}, dot_w[4] = {0.0, 0.0, 0.0, 0.0};  // entry i into lane i % 4
    for (std::ptrdiff_t I = 0; I < nb; ++I) {
        const std::ptrdiff_t i = 3 * I;
        const double xi0 = px[i], xi1 = px[i + 1], xi2 = px[i + 2];
        double s0 = py[i], s1 = py[i + 1], s2 = py[i + 2];
        int k = start[I];
        const int end = start[I + 1];
        if (k < end && column[k] == I) {  // the diagonal block: no transpose to scatter
            const double* __restrict b = val + 9 * static_cast<std::ptrdiff_t>(k);
            s0 += b[0] * xi0 + b[3] * xi1 + b[6] * xi2;
            s1 += b[1] * xi0 + b[4] * xi1 + b[7] * xi2;
            s2 += b[2] * xi0 + b[5] * xi1 + b[8] * xi2;
            ++k;
        }
        for (; k < end; ++k) {
            const double* __restrict b = val + 9 * static_cast<std::ptrdiff_t>(k);
            const std::ptrdiff_t j = 3 * static_cast<std::ptrdiff_t>(column[k]);
            const double x0 = px[j], x1 = px[j + 1], x2 = px[j + 2];
            s0 += b[0] * x0 + b[3] * x1 + b[6] * x2;
            s1 += b[1] * x0 + b[4] * x1 + b[7] * x2;
            s2 += b[2] * x0 + b[5] * x1 + b[8] * x2;
            py[j] += b[0] * xi0 + b[1] * xi1 + b[2] * xi2;  // column c of B is row c of B'
            py[j + 1] += b[3] * xi0 + b[4] * xi1 + b[5] * xi2;
            py[j + 2] += b[6] * xi0 + b[7] * xi1 + b[8] * xi2;
        }
        py[i] = s0;
        py[i + 1] = s1;
        py[i + 2] = s2;
        if constexpr (D != Dots::NONE) {
            for (std::ptrdiff_t r = i; r < i + 3; ++r) {
                xy[r % 4] += px[r] * py[r];
                if (D == Dots::ALL || !skip[r]) dot_w[r % 4] += px[r] * pw[r];
            }
        }
    }
    xw = (dot_w[0] + dot_w[1]) + (dot_w[2] + dot_w[3]);
    return (xy[0] + xy[1]) + (xy[2] + xy[3]);
}

#ifdef CB_HAVE_AVX2_KERNEL
/// Block row I's part of the product: (B x)_I summed as the scalar loop sums it (the three column
/// products added pairwise first, then to the row's sum).
__attribute__((target("avx2"))) inline __m256d sym_block_terms(const double* __restrict b, const double* __restrict xj)
{
    const __m256d m0 = _mm256_mul_pd(_mm256_loadu_pd(b), _mm256_broadcast_sd(xj));
    const __m256d m1 = _mm256_mul_pd(_mm256_loadu_pd(b + 3), _mm256_broadcast_sd(xj + 1));
    const __m256d m2 = _mm256_mul_pd(_mm256_loadu_pd(b + 6), _mm256_broadcast_sd(xj + 2));
    return _mm256_add_pd(_mm256_add_pd(m0, m1), m2);
}

/// y_J += B' x_I: B's rows r (lanes c = B(r, c), lane 3 zero) out of its stored columns, each times
/// x_I[r], summed as the scalar loop sums column c of B times x_I; y_J's three entries are read
/// and written alone (the fourth belongs to another block row, and y may end there).
__attribute__((target("avx2"))) inline void sym_block_scatter(const double* __restrict b, __m256d xi0, __m256d xi1,
                                                              __m256d xi2, double* __restrict yj)
{
    const __m256d c0 = _mm256_loadu_pd(b), c1 = _mm256_loadu_pd(b + 3), c2 = _mm256_loadu_pd(b + 6);
    const __m256d zero = _mm256_setzero_pd();
    const __m256d lo01 = _mm256_unpacklo_pd(c0, c1);             // b00 b01 b20 b21
    const __m256d hi01 = _mm256_unpackhi_pd(c0, c1);             // b10 b11 .   .
    const __m256d lo2 = _mm256_unpacklo_pd(c2, zero);            // b02 0   b22 0
    const __m256d hi2 = _mm256_unpackhi_pd(c2, zero);            // b12 0   .   0
    const __m256d r0 = _mm256_permute2f128_pd(lo01, lo2, 0x20);  // b00 b01 b02 0
    const __m256d r1 = _mm256_permute2f128_pd(hi01, hi2, 0x20);  // b10 b11 b12 0
    const __m256d r2 = _mm256_permute2f128_pd(lo01, lo2, 0x31);  // b20 b21 b22 0
    const __m256d t =
        _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(r0, xi0), _mm256_mul_pd(r1, xi1)), _mm256_mul_pd(r2, xi2));
    _mm_storeu_pd(yj, _mm_add_pd(_mm_loadu_pd(yj), _mm256_castpd256_pd128(t)));
    _mm_store_sd(yj + 2, _mm_add_sd(_mm_load_sd(yj + 2), _mm256_extractf128_pd(t, 1)));
}

/// Block rows per chunk of the AVX2 symmetric kernel: its dots are summed from y still in cache.
constexpr std::ptrdiff_t SYM_CHUNK = 1024;
/// Doubles ahead of the block in hand that the symmetric kernel asks the cache for (32 blocks):
/// one stream of blocks outran the hardware's prefetch (docs/a_product.md).
constexpr std::ptrdiff_t SYM_PREFETCH = std::ptrdiff_t{9} * 32;

/// The fused dots of entries first .. last - 1 (first a multiple of 4) into the lanes of vxy and
/// vxw, entry i into lane i % 4, as the scalar loop sums them; a skipped entry leaves its lane as
/// it is (a blend, not an added zero, so even a zero's sign is the scalar loop's).
template <Dots D>
__attribute__((target("avx2"))) inline void sym_chunk_dots(std::ptrdiff_t first, std::ptrdiff_t last,
                                                           const double* __restrict px, const double* __restrict py,
                                                           const double* __restrict pw, const char* __restrict skip,
                                                           __m256d& vxy, __m256d& vxw)
{
    std::ptrdiff_t i = first;
    for (; i + 4 <= last; i += 4) {
        const __m256d x = _mm256_loadu_pd(px + i);
        vxy = _mm256_add_pd(vxy, _mm256_mul_pd(x, _mm256_loadu_pd(py + i)));
        const __m256d with_w = _mm256_add_pd(vxw, _mm256_mul_pd(x, _mm256_loadu_pd(pw + i)));
        if constexpr (D == Dots::ALL) {
            vxw = with_w;
        } else {
            int bytes;
            std::memcpy(&bytes, skip + i, sizeof bytes);
            const __m256i flags = _mm256_cvtepi8_epi64(_mm_cvtsi32_si128(bytes));
            const __m256d skipped = _mm256_castsi256_pd(_mm256_cmpeq_epi64(flags, _mm256_setzero_si256()));
            vxw = _mm256_blendv_pd(vxw, with_w, skipped);  // lanes whose flag is 0 take the sum
        }
    }
    if (i == last) return;
    alignas(32) double lane_xy[4], lane_xw[4];  // the tail (at most 3 entries), lane by lane
    _mm256_store_pd(lane_xy, vxy);
    _mm256_store_pd(lane_xw, vxw);
    for (; i < last; ++i) {
        lane_xy[i % 4] += px[i] * py[i];
        if (D == Dots::ALL || !skip[i]) lane_xw[i % 4] += px[i] * pw[i];
    }
    vxy = _mm256_load_pd(lane_xy);
    vxw = _mm256_load_pd(lane_xw);
}

/// x = z - beta x on entries first .. last - 1 (the update's own rounding: a product, then a difference).
__attribute__((target("avx2"))) inline void update_direction(const DirectionUpdate& u, std::ptrdiff_t first,
                                                             std::ptrdiff_t last)
{
    const __m256d beta = _mm256_set1_pd(u.beta);
    std::ptrdiff_t i = first;
    for (; i + 4 <= last; i += 4)
        _mm256_storeu_pd(u.x + i,
                         _mm256_sub_pd(_mm256_loadu_pd(u.z + i), _mm256_mul_pd(beta, _mm256_loadu_pd(u.x + i))));
    for (; i < last; ++i) u.x[i] = u.z[i] - u.beta * u.x[i];
}

/// sym_block_product_scalar() with AVX2, the same sums in the same order (y and the dots equal to
/// the last bit). y is zeroed (and x updated) just ahead of the rows the scatter reaches instead of
/// in a pass of its own: `zeroed` is the first block row not yet cleared.
template <Dots D>
__attribute__((target("avx2"))) double sym_block_product_avx2(const BlockRows& B, std::ptrdiff_t nb, const double* px,
                                                              double* __restrict py, const double* __restrict pw,
                                                              const char* __restrict skip, double& xw,
                                                              DirectionUpdate update)
{
    const int* __restrict start = B.start.data();
    const int* __restrict column = B.column.data();
    const double* __restrict val = B.value.data();
    std::ptrdiff_t zeroed = 0;
    __m256d vxy = _mm256_setzero_pd(), vxw = _mm256_setzero_pd();  // lane l: the entries i with i % 4 == l
    for (std::ptrdiff_t c = 0; c < nb; c += SYM_CHUNK) {
        const std::ptrdiff_t end = std::min(nb, c + SYM_CHUNK);
        for (std::ptrdiff_t I = c; I < end; ++I) {
            int k = start[I];
            const int last = start[I + 1];
            const std::ptrdiff_t reach = 1 + (k < last ? std::max<std::ptrdiff_t>(I, column[last - 1]) : I);
            if (zeroed < reach) {  // every row I reads lies below reach
                std::fill(py + 3 * zeroed, py + 3 * reach, 0.0);
                if (update.x != nullptr) update_direction(update, 3 * zeroed, 3 * reach);
                zeroed = reach;
            }
            const double* xi = px + 3 * I;
            const double* yi = py + 3 * I;
            __m256d s = _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_loadu_pd(yi)), _mm_load_sd(yi + 2), 1);
            if (k < last && column[k] == I) {  // the diagonal block: no transpose to scatter
                s = _mm256_add_pd(s, sym_block_terms(val + 9 * static_cast<std::ptrdiff_t>(k), xi));
                ++k;
            }
            const __m256d xi0 = _mm256_broadcast_sd(xi), xi1 = _mm256_broadcast_sd(xi + 1),
                          xi2 = _mm256_broadcast_sd(xi + 2);
            for (; k < last; ++k) {
                const double* b = val + 9 * static_cast<std::ptrdiff_t>(k);
                const std::ptrdiff_t j = 3 * static_cast<std::ptrdiff_t>(column[k]);
                _mm_prefetch(reinterpret_cast<const char*>(b + SYM_PREFETCH), _MM_HINT_T0);
                s = _mm256_add_pd(s, sym_block_terms(b, px + j));
                sym_block_scatter(b, xi0, xi1, xi2, py + j);
            }
            store_block_row(I, s, py, nullptr);
        }
        if constexpr (D != Dots::NONE) sym_chunk_dots<D>(3 * c, 3 * end, px, py, pw, skip, vxy, vxw);
    }
    alignas(32) double lane_xy[4], lane_xw[4];
    _mm256_store_pd(lane_xy, vxy);
    _mm256_store_pd(lane_xw, vxw);
    xw = (lane_xw[0] + lane_xw[1]) + (lane_xw[2] + lane_xw[3]);
    return (lane_xy[0] + lane_xy[1]) + (lane_xy[2] + lane_xy[3]);
}
#endif

/// The symmetric product on the CPU's kernel (AVX2 or the scalar loop: the same y and dots).
template <Dots D>
double sym_kernel(const BlockRows& B, std::ptrdiff_t nb, const double* px, double* __restrict py,
                  const double* __restrict pw, const char* __restrict skip, double& xw, DirectionUpdate update)
{
#ifdef CB_HAVE_AVX2_KERNEL
    if (block_kernel_is_simd()) return sym_block_product_avx2<D>(B, nb, px, py, pw, skip, xw, update);
#endif
    return sym_block_product_scalar<D>(B, nb, px, py, pw, skip, xw, update);
}

}  // namespace

double sym_block_product(Dots dots, const BlockRows& B, std::ptrdiff_t nb, const double* px, double* py,
                         const double* pw, const char* skip, double& xw, DirectionUpdate update)
{
    switch (dots) {
    case Dots::NONE:
        return sym_kernel<Dots::NONE>(B, nb, px, py, pw, skip, xw, update);
    case Dots::ALL:
        return sym_kernel<Dots::ALL>(B, nb, px, py, pw, skip, xw, update);
    case Dots::MASKED:
        break;
    }
    return sym_kernel<Dots::MASKED>(B, nb, px, py, pw, skip, xw, update);
}

}  // namespace cb
