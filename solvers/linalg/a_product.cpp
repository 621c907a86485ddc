#include "solvers/linalg/a_product.hpp"

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <cstring>
#include <limits>

#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>
#endif

namespace cb {

namespace {

std::atomic<long> g_a_products{0};

/// Block entries stored per nonzero beyond which BSR is refused: at 1.25 it still reads about
/// 10.6 bytes per nonzero against CSR's 12.
constexpr double MAX_FILL = 1.25;

enum class Dots { NONE, ALL, MASKED };

/// Block row I's three sums with AVX2: lanes 0-2 of one register are rows 3I .. 3I + 2 (lane 3 is
/// unused). Each lane adds b(r, c) x_c one term at a time in column order, as the scalar loop does,
/// with separate multiplies and adds (the target has no FMA to contract them): the same y to the
/// last bit. A column's unaligned four-wide load reads one entry past the block (the storage keeps
/// a trailing zero).
#if defined(__x86_64__) && defined(__GNUC__)
#define CB_HAVE_AVX2_KERNEL 1
__attribute__((target("avx2"))) inline __m256d block_step(__m256d s, const double* __restrict b,
                                                          const double* __restrict xj)
{
    s = _mm256_add_pd(s, _mm256_mul_pd(_mm256_loadu_pd(b), _mm256_broadcast_sd(xj)));
    s = _mm256_add_pd(s, _mm256_mul_pd(_mm256_loadu_pd(b + 3), _mm256_broadcast_sd(xj + 1)));
    return _mm256_add_pd(s, _mm256_mul_pd(_mm256_loadu_pd(b + 6), _mm256_broadcast_sd(xj + 2)));
}

/// Stores block row I's three sums (with pu: each times u_i, as the scaled product's y).
__attribute__((target("avx2"))) inline void store_block_row(std::ptrdiff_t I, __m256d s, double* __restrict py,
                                                            const double* __restrict pu)
{
    alignas(32) double sum[4];
    _mm256_store_pd(sum, s);
    if (pu != nullptr) {
        py[3 * I] = sum[0] * pu[3 * I];
        py[3 * I + 1] = sum[1] * pu[3 * I + 1];
        py[3 * I + 2] = sum[2] * pu[3 * I + 2];
        return;
    }
    py[3 * I] = sum[0];
    py[3 * I + 1] = sum[1];
    py[3 * I + 2] = sum[2];
}

/// Block rows with this many block rows between the two read side by side (at 72 bytes a block and
/// 10-30 blocks a row, tens of kilobytes apart: two neighbouring rows read side by side ran at half
/// speed, the hardware's prefetch not following two streams in one page; docs/a_product.md).
constexpr std::ptrdiff_t PAIR_DISTANCE = 2048;

/// With SCALED: px holds U x, y is scaled by pu = u at each row's end and the dots read pd = x
/// (block_product).
template <Dots D, bool SCALED>
__attribute__((target("avx2"))) double block_product_avx2(const BlockRows& B, std::ptrdiff_t first, std::ptrdiff_t last,
                                                          const double* __restrict px, double* __restrict py,
                                                          const double* __restrict pw, const char* __restrict skip,
                                                          const double* __restrict pu, const double* __restrict pd,
                                                          double& xw)
{
    const int* __restrict start = B.start.data();
    const int* __restrict column = B.column.data();
    const double* __restrict val = B.value.data();
    const auto block = [val](int k) { return val + 9 * static_cast<std::ptrdiff_t>(k); };
    const auto x_of = [px, column](int k) { return px + 3 * static_cast<std::ptrdiff_t>(column[k]); };
    const double* __restrict scale_y = SCALED ? pu : nullptr;
    double xy = 0.0, dot_w = 0.0;
    // Block rows I and I + d side by side (two chains of additions in flight), chunk by chunk; then
    // the chunk's dots in row order, from y still in cache, so that x'y and x'w are summed as the
    // scalar loop sums them.
    for (std::ptrdiff_t c = first; c < last; c += 2 * PAIR_DISTANCE) {
        const std::ptrdiff_t d = std::min(PAIR_DISTANCE, (last - c) / 2);
        for (std::ptrdiff_t I = c; I < c + d; ++I) {
            const std::ptrdiff_t J = I + d;
            __m256d sa = _mm256_setzero_pd(), sb = _mm256_setzero_pd();
            int ka = start[I], kb = start[J];
            const int ea = start[I + 1], eb = start[J + 1];
            for (; ka < ea && kb < eb; ++ka, ++kb) {
                sa = block_step(sa, block(ka), x_of(ka));
                sb = block_step(sb, block(kb), x_of(kb));
            }
            for (; ka < ea; ++ka) sa = block_step(sa, block(ka), x_of(ka));
            for (; kb < eb; ++kb) sb = block_step(sb, block(kb), x_of(kb));
            store_block_row(I, sa, py, scale_y);
            store_block_row(J, sb, py, scale_y);
        }
        const std::ptrdiff_t end = std::min(last, c + 2 * PAIR_DISTANCE);
        if (c + 2 * d < end) {  // an odd row at the end of the range
            __m256d s = _mm256_setzero_pd();
            for (int k = start[end - 1]; k < start[end]; ++k) s = block_step(s, block(k), x_of(k));
            store_block_row(end - 1, s, py, scale_y);
        }
        if constexpr (D != Dots::NONE) {
            for (std::ptrdiff_t i = 3 * c; i < 3 * end; ++i) {
                xy += pd[i] * py[i];
                if (D == Dots::ALL || !skip[i]) dot_w += pd[i] * pw[i];
            }
        }
    }
    xw = dot_w;
    return xy;
}

#endif

std::atomic<bool> g_force_scalar{false};

bool simd_block_kernel()
{
#ifdef CB_HAVE_AVX2_KERNEL
    static const bool has_avx2 = __builtin_cpu_supports("avx2");
    return has_avx2 && !g_force_scalar.load(std::memory_order_relaxed);
#else
    return false;
#endif
}

/// y = A x on the block rows; with D != NONE also x'y and x'w (masked: where skip[i] == 0).
/// Each row's sum runs over its columns in increasing order, as the CSR loop's does, and the
/// stored zeros add exact zeros: y, x'y and x'w equal the CSR kernels' to the last bit (finite x).
/// Block rows first .. last - 1 only (a thread's range); their dots are that range's partial sums.
/// With SCALED, y = U A U x: px holds U x, each row's sum is multiplied by u_i (pu) before it is
/// stored, and the dots read x itself (pd), as the pass that scaled y after the product did.
template <Dots D, bool SCALED = false>
double block_product(const BlockRows& B, std::ptrdiff_t first, std::ptrdiff_t last, const double* __restrict px,
                     double* __restrict py, const double* __restrict pw, const char* __restrict skip, double& xw,
                     const double* __restrict pu = nullptr, const double* __restrict pd = nullptr)
{
    if constexpr (!SCALED) pd = px;
#ifdef CB_HAVE_AVX2_KERNEL
    if (simd_block_kernel()) return block_product_avx2<D, SCALED>(B, first, last, px, py, pw, skip, pu, pd, xw);
#endif
    const int* __restrict start = B.start.data();
    const int* __restrict column = B.column.data();
    const double* __restrict val = B.value.data();
    double xy = 0.0, dot_w = 0.0;
    for (std::ptrdiff_t I = first; I < last; ++I) {
        double s0 = 0.0, s1 = 0.0, s2 = 0.0;
        for (int k = start[I]; k < start[I + 1]; ++k) {
            const double* __restrict b = val + 9 * static_cast<std::ptrdiff_t>(k);
            const double* __restrict xj = px + 3 * static_cast<std::ptrdiff_t>(column[k]);
            const double x0 = xj[0], x1 = xj[1], x2 = xj[2];
            s0 += b[0] * x0;
            s1 += b[1] * x0;
            s2 += b[2] * x0;
            s0 += b[3] * x1;
            s1 += b[4] * x1;
            s2 += b[5] * x1;
            s0 += b[6] * x2;
            s1 += b[7] * x2;
            s2 += b[8] * x2;
        }
        const std::ptrdiff_t i = 3 * I;
        if constexpr (SCALED) {
            s0 *= pu[i];
            s1 *= pu[i + 1];
            s2 *= pu[i + 2];
        }
        py[i] = s0;
        py[i + 1] = s1;
        py[i + 2] = s2;
        if constexpr (D != Dots::NONE) {
            xy += pd[i] * s0;
            xy += pd[i + 1] * s1;
            xy += pd[i + 2] * s2;
            for (std::ptrdiff_t r = i; r < i + 3; ++r)
                if (D == Dots::ALL || !skip[r]) dot_w += pd[r] * pw[r];
        }
    }
    xw = dot_w;
    return xy;
}

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
double sym_block_product_scalar(const BlockRows& B, std::ptrdiff_t nb, const double* __restrict px,
                                double* __restrict py, const double* __restrict pw, const char* __restrict skip,
                                double& xw)
{
    const int* __restrict start = B.start.data();
    const int* __restrict column = B.column.data();
    const double* __restrict val = B.value.data();
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

/// sym_block_product_scalar() with AVX2, the same sums in the same order (y and the dots equal to
/// the last bit). y is zeroed just ahead of the rows the scatter reaches instead of in a pass of
/// its own: `zeroed` is the first block row not yet cleared.
template <Dots D>
__attribute__((target("avx2"))) double sym_block_product_avx2(const BlockRows& B, std::ptrdiff_t nb,
                                                              const double* __restrict px, double* __restrict py,
                                                              const double* __restrict pw, const char* __restrict skip,
                                                              double& xw)
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
            if (zeroed < reach) {
                std::fill(py + 3 * zeroed, py + 3 * reach, 0.0);
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
double sym_block_product(const BlockRows& B, std::ptrdiff_t nb, const double* __restrict px, double* __restrict py,
                         const double* __restrict pw, const char* __restrict skip, double& xw)
{
#ifdef CB_HAVE_AVX2_KERNEL
    if (simd_block_kernel()) return sym_block_product_avx2<D>(B, nb, px, py, pw, skip, xw);
#endif
    return sym_block_product_scalar<D>(B, nb, px, py, pw, skip, xw);
}

/// The CSR loop of the fused product (compressed A) over rows first .. last - 1: row i's sum, then
/// x_i y_i and x_i w_i (D == NONE: the sums only, as Eigen's row-major product does them).
template <Dots D>
double csr_product_dots(const SpMat& A, Eigen::Index first, Eigen::Index last, const double* __restrict px,
                        double* __restrict py, const double* __restrict pw, const char* __restrict skip, double& xw)
{
    const int* __restrict outer = A.outerIndexPtr();
    const int* __restrict inner = A.innerIndexPtr();
    const double* __restrict val = A.valuePtr();
    double xy = 0.0, dot_w = 0.0;
    for (Eigen::Index i = first; i < last; ++i) {
        double s = 0.0;
        for (int k = outer[i]; k < outer[i + 1]; ++k) s += val[k] * px[inner[k]];
        py[i] = s;
        if constexpr (D != Dots::NONE) {
            xy += px[i] * s;
            if (D == Dots::ALL || !skip[i]) dot_w += px[i] * pw[i];
        }
    }
    xw = dot_w;
    return xy;
}

/// Runs the product over the operator's row ranges, on up to parts() threads, and sums the ranges'
/// dots in range order: which thread runs a range changes nothing in y or the dots.
template <Dots D>
double product_by_parts(const AOperator& A, const double* px, double* py, const double* pw, const char* skip,
                        double& xw)
{
    const int parts = A.parts();
    const int* bound = A.part_start().data();
    std::vector<double> part_xy(static_cast<size_t>(parts), 0.0), part_xw(static_cast<size_t>(parts), 0.0);
    const bool blocks = A.format() == AFormat::BSR;
    const auto run = [&](int p) {
        double& w = part_xw[static_cast<size_t>(p)];
        part_xy[static_cast<size_t>(p)] =
            blocks ? block_product<D>(A.blocks(), bound[p], bound[p + 1], px, py, pw, skip, w)
                   : csr_product_dots<D>(A.csr(), bound[p], bound[p + 1], px, py, pw, skip, w);
    };
#ifdef CB_HAVE_OPENMP
#pragma omp parallel for num_threads(parts) schedule(static, 1)
    for (int p = 0; p < parts; ++p) run(p);
#else
    for (int p = 0; p < parts; ++p) run(p);
#endif
    double xy = 0.0, dot_w = 0.0;
    for (int p = 0; p < parts; ++p) {
        xy += part_xy[static_cast<size_t>(p)];
        dot_w += part_xw[static_cast<size_t>(p)];
    }
    xw = dot_w;
    return xy;
}

/// Bounds of `parts` ranges over the rows whose nonzeros (or blocks) start at start[0..rows]:
/// range p ends at the first row whose prefix reaches p/parts of the total, so each range holds
/// about the same work. Empty ranges are dropped.
std::vector<int> split_rows(const int* start, std::ptrdiff_t rows, int parts)
{
    std::vector<int> bound{0};
    const double total = static_cast<double>(start[rows] - start[0]);
    std::ptrdiff_t row = 0;
    for (int p = 1; p < parts; ++p) {
        const double target = total * p / parts;
        while (row < rows && static_cast<double>(start[row] - start[0]) < target) ++row;
        if (row > bound.back()) bound.push_back(static_cast<int>(row));
    }
    if (rows > bound.back()) bound.push_back(static_cast<int>(rows));
    if (bound.size() == 1) bound.push_back(0);
    return bound;
}

}  // namespace

AFormat AOperator::prepare(AFormat wanted, int threads)
{
    m_format = AFormat::CSR;
    m_blocks = BlockRows{};
    m_why_csr.clear();
    m_fill = 0.0;
    const SpMat& A = *m_csr;
    const long nnz = static_cast<long>(A.nonZeros());
    // AUTO: on one thread and a large A the upper blocks (half the bytes of a product that streams
    // A from memory); else, or when A is not symmetric to the bit, the blocks whose sums follow
    // CSR's order (SBSR's other order moved iteration counts on suites/ci.json; docs/a_product.md).
    std::vector<AFormat> tries{wanted};
    if (wanted == AFormat::AUTO) {
        tries = {AFormat::BSR};
        if (auto_prefers_upper_blocks(nnz, std::max(1, threads))) tries.insert(tries.begin(), AFormat::SBSR);
    }
    for (const AFormat asked : tries) {
        if (asked != AFormat::BSR && asked != AFormat::SBSR) break;
        double fill = 0.0;
        const bool upper = asked == AFormat::SBSR;
        m_why_csr.clear();
        const bool built = upper ? build_upper_block_rows(A, m_blocks, MAX_FILL, fill, m_why_csr) &&
                                       upper_blocks_mirror_a(A, m_blocks, m_why_csr)
                                 : build_block_rows(A, m_blocks, MAX_FILL, fill, m_why_csr);
        if (built) {
            m_format = asked;
            m_blocks_scaled = false;
            if (asked == AFormat::SBSR && m_scale != nullptr) scale_blocks();
            (void)fill;  // per nonzero of the stored part; fill() is per nonzero of A
            m_fill = 9.0 * static_cast<double>(m_blocks.column.size()) / static_cast<double>(std::max(1L, nnz));
            break;
        }
        m_blocks = BlockRows{};
    }
    // Threads only where the raw loops run (compressed A); each range keeps enough nonzeros to
    // repay waking its thread. The ranges depend on A and threads only, never on the machine.
    // The symmetric blocks run on one thread (their transposes scatter into other rows).
    int parts = std::max(1, threads);
    parts = static_cast<int>(std::min<long>(parts, std::max(1L, nnz / MIN_NONZEROS_PER_PART)));
    if (!A.isCompressed()) parts = 1;
    if (m_format == AFormat::SBSR)
        m_part_start = {0, static_cast<int>(m_blocks.start.size()) - 1};
    else if (m_format == AFormat::BSR)
        m_part_start = split_rows(m_blocks.start.data(), static_cast<std::ptrdiff_t>(m_blocks.start.size()) - 1, parts);
    else if (A.isCompressed())
        m_part_start = split_rows(A.outerIndexPtr(), A.rows(), parts);
    else
        m_part_start = {0, static_cast<int>(A.rows())};
    return m_format;
}

void AOperator::scale_blocks()
{
    const Vec& u = *m_scale;
    const std::ptrdiff_t nb = static_cast<std::ptrdiff_t>(m_blocks.start.size()) - 1;
    for (std::ptrdiff_t I = 0; I < nb; ++I)
        for (int k = m_blocks.start[static_cast<size_t>(I)]; k < m_blocks.start[static_cast<size_t>(I) + 1]; ++k) {
            const std::ptrdiff_t J = m_blocks.column[static_cast<size_t>(k)];
            double* b = m_blocks.value.data() + 9 * static_cast<std::ptrdiff_t>(k);
            for (int c = 0; c < 3; ++c)
                for (int r = 0; r < 3; ++r) b[3 * c + r] = u[3 * I + r] * b[3 * c + r] * u[3 * J + c];
        }
    m_blocks_scaled = true;
}

void AOperator::scale_by(const Vec* u)
{
    if (m_format == AFormat::SBSR && m_blocks_scaled) {  // back to A's own blocks first
        std::string why;
        double fill = 0.0;
        build_upper_block_rows(*m_csr, m_blocks, MAX_FILL, fill, why);
        m_blocks_scaled = false;
    }
    m_scale = u;
    if (m_format == AFormat::SBSR && m_scale != nullptr) scale_blocks();
}

bool a_product_parallel_build()
{
#ifdef CB_HAVE_OPENMP
    return true;
#else
    return false;
#endif
}

double AOperator::matrix_bytes() const
{
    if (m_format != AFormat::CSR)
        return static_cast<double>(m_blocks.column.size()) * 72.0 + static_cast<double>(m_blocks.column.size()) * 4.0 +
               static_cast<double>(m_blocks.start.size()) * 4.0;
    return static_cast<double>(m_csr->nonZeros()) * 12.0 + static_cast<double>(m_csr->rows() + 1) * 4.0;
}

// Out of line on purpose: one symbol that every counted product goes through.
void a_product(const SpMat& A, const Vec& x, Vec& y)
{
    y.noalias() = A * x;
    g_a_products.fetch_add(1, std::memory_order_relaxed);
}

double a_product_dots(const SpMat& A, const Vec& x, Vec& y, const Vec& w, double& xw)
{
    if (!A.isCompressed()) {  // the raw loop reads a compressed row-major matrix
        a_product(A, x, y);
        xw = x.dot(w);
        return x.dot(y);
    }
    y.resize(A.rows());
    const double xy = csr_product_dots<Dots::ALL>(A, 0, A.rows(), x.data(), y.data(), w.data(), nullptr, xw);
    g_a_products.fetch_add(1, std::memory_order_relaxed);
    return xy;
}

Vec a_product(const SpMat& A, const Vec& x)
{
    Vec y;
    a_product(A, x, y);
    return y;
}

namespace {

/// y = A x on the storage prepare() chose, counted (the operator's scaling aside).
void stored_product(const AOperator& A, const Vec& x, Vec& y)
{
    if (A.format() == AFormat::SBSR) {
        y.resize(A.rows());
        double unused = 0.0;
        sym_block_product<Dots::NONE>(A.blocks(), A.rows() / 3, x.data(), y.data(), nullptr, nullptr, unused);
        g_a_products.fetch_add(1, std::memory_order_relaxed);
        return;
    }
    if (A.parts() > 1) {  // threads: the raw loops by row range
        y.resize(A.rows());
        double unused = 0.0;
        product_by_parts<Dots::NONE>(A, x.data(), y.data(), nullptr, nullptr, unused);
        g_a_products.fetch_add(1, std::memory_order_relaxed);
        return;
    }
    if (A.format() != AFormat::BSR) return a_product(A.csr(), x, y);
    y.resize(A.rows());
    double unused = 0.0;
    block_product<Dots::NONE>(A.blocks(), 0, A.rows() / 3, x.data(), y.data(), nullptr, nullptr, unused);
    g_a_products.fetch_add(1, std::memory_order_relaxed);
}

/// y = U A U x: U x into the operator's buffer, the stored product, then y's scaling and the
/// dots in one pass (x'y and x'w in index order, as the one-thread kernels sum them).
template <Dots D>
double scaled_product(const AOperator& A, const Vec& x, Vec& y, const Vec* w, const char* skip, double& xw)
{
    const Vec& u = *A.scaling();
    Vec& ux = A.scaled_input();
    if (!A.blocks_scaled()) ux = u.cwiseProduct(x);
    if (A.format() == AFormat::BSR && A.parts() == 1) {
        // One thread on blocks: y scaled and the dots summed inside the kernel, no pass after it
        // (the same y and dots as that pass, below, to the last bit).
        y.resize(A.rows());
        const double xy = block_product<D, true>(A.blocks(), 0, A.rows() / 3, ux.data(), y.data(),
                                                 w != nullptr ? w->data() : nullptr, skip, xw, u.data(), x.data());
        g_a_products.fetch_add(1, std::memory_order_relaxed);
        return xy;
    }
    if (A.blocks_scaled()) {  // SBSR's blocks hold U A U: x itself in, y out, the dots in the pass
        y.resize(A.rows());
        const double xy = sym_block_product<D>(A.blocks(), A.rows() / 3, x.data(), y.data(),
                                               w != nullptr ? w->data() : nullptr, skip, xw);
        g_a_products.fetch_add(1, std::memory_order_relaxed);
        return xy;
    }
    stored_product(A, ux, y);
    double xy = 0.0, dot_w = 0.0;
    for (Eigen::Index i = 0; i < y.size(); ++i) {
        y[i] *= u[i];
        if constexpr (D != Dots::NONE) {
            xy += x[i] * y[i];
            if (D == Dots::ALL || !skip[i]) dot_w += x[i] * (*w)[i];
        }
    }
    xw = dot_w;
    return xy;
}

}  // namespace

void a_product(const AOperator& A, const Vec& x, Vec& y)
{
    if (A.scaling() == nullptr) return stored_product(A, x, y);
    double unused = 0.0;
    scaled_product<Dots::NONE>(A, x, y, nullptr, nullptr, unused);
}

double a_product_dots(const AOperator& A, const Vec& x, Vec& y, const Vec& w, double& xw)
{
    if (A.scaling() != nullptr) return scaled_product<Dots::ALL>(A, x, y, &w, nullptr, xw);
    if (A.format() == AFormat::SBSR) {
        y.resize(A.rows());
        const double xy =
            sym_block_product<Dots::ALL>(A.blocks(), A.rows() / 3, x.data(), y.data(), w.data(), nullptr, xw);
        g_a_products.fetch_add(1, std::memory_order_relaxed);
        return xy;
    }
    if (A.parts() > 1) {
        y.resize(A.rows());
        const double xy = product_by_parts<Dots::ALL>(A, x.data(), y.data(), w.data(), nullptr, xw);
        g_a_products.fetch_add(1, std::memory_order_relaxed);
        return xy;
    }
    if (A.format() != AFormat::BSR) return a_product_dots(A.csr(), x, y, w, xw);
    y.resize(A.rows());
    const double xy = block_product<Dots::ALL>(A.blocks(), 0, A.rows() / 3, x.data(), y.data(), w.data(), nullptr, xw);
    g_a_products.fetch_add(1, std::memory_order_relaxed);
    return xy;
}

double a_product_dots(const AOperator& A, const Vec& x, Vec& y, const Vec& w, const char* skip, double& xw)
{
    if (A.scaling() != nullptr) return scaled_product<Dots::MASKED>(A, x, y, &w, skip, xw);
    y.resize(A.rows());
    double xy = 0.0;
    if (A.format() == AFormat::SBSR)
        xy = sym_block_product<Dots::MASKED>(A.blocks(), A.rows() / 3, x.data(), y.data(), w.data(), skip, xw);
    else if (A.parts() > 1)
        xy = product_by_parts<Dots::MASKED>(A, x.data(), y.data(), w.data(), skip, xw);
    else if (A.format() == AFormat::BSR)
        xy = block_product<Dots::MASKED>(A.blocks(), 0, A.rows() / 3, x.data(), y.data(), w.data(), skip, xw);
    else if (A.csr().isCompressed())
        xy = csr_product_dots<Dots::MASKED>(A.csr(), 0, A.rows(), x.data(), y.data(), w.data(), skip, xw);
    else {
        y.noalias() = A.csr() * x;
        xy = x.dot(y);
        double dot_w = 0.0;
        for (Eigen::Index i = 0; i < x.size(); ++i)
            if (!skip[i]) dot_w += x[i] * w[i];
        xw = dot_w;
    }
    g_a_products.fetch_add(1, std::memory_order_relaxed);
    return xy;
}

Vec a_product(const AOperator& A, const Vec& x)
{
    Vec y;
    a_product(A, x, y);
    return y;
}

long a_product_count() { return g_a_products.load(std::memory_order_relaxed); }

bool block_kernel_is_simd() { return simd_block_kernel(); }

void force_scalar_block_kernel(bool scalar) { g_force_scalar.store(scalar, std::memory_order_relaxed); }

}  // namespace cb
