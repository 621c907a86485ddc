#pragma once
/// How an AVX2 kernel of this project hands its result to the code after it. The project is built
/// for plain x86-64, so the code around the kernels is SSE; a kernel that leaves the upper halves
/// of the ymm registers dirty makes that code run up to 1.5x slower on this project's machine, and
/// GCC 12 emitted no vzeroupper before a call out of two kernels (docs/a_product.md, "The passes
/// around the product, once more"; tests/python/test_avx_upper_state.py checks the binary).
#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>

namespace cb {

/// The largest of v's four lanes, with the upper register halves cleared: call it after the
/// kernel's last 256-bit operation, before its scalar tail and its return. The lanes must hold no
/// NaN (a kernel's max(term, widest) keeps a NaN term out), so the order they are compared in is free.
__attribute__((target("avx2"))) inline double max_lane_clearing_upper(__m256d v)
{
    const __m128d pair = _mm_max_pd(_mm256_castpd256_pd128(v), _mm256_extractf128_pd(v, 1));
    _mm256_zeroupper();
    return _mm_cvtsd_f64(_mm_max_sd(pair, _mm_unpackhi_pd(pair, pair)));
}

}  // namespace cb
#endif
