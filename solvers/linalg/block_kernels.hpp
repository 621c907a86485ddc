#pragma once
/// What the block kernels of the A-product share (solvers/linalg/a_product.cpp: BSR;
/// solvers/linalg/sym_block_product.cpp: SBSR): which dots a fused product sums, whether the AVX2
/// kernels are compiled in, and how a block row's three lanes are stored.
#include <cstddef>

#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>
#define CB_HAVE_AVX2_KERNEL 1
#endif

namespace cb {

/// The dots a fused product sums beside y = A x: none, x'y and x'w, or x'y and x'w where skip[i] == 0.
enum class Dots { NONE, ALL, MASKED };

#ifdef CB_HAVE_AVX2_KERNEL
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
#endif

}  // namespace cb
