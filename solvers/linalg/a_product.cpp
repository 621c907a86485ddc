#include "solvers/linalg/a_product.hpp"
#include "solvers/linalg/block_kernels.hpp"
#include "solvers/linalg/sym_block_product.hpp"

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <limits>

namespace cb {

namespace {

std::atomic<long> g_a_products{0};
std::atomic<long> g_mirror_checks{0};

/// Block entries stored per nonzero beyond which BSR is refused: at 1.25 it still reads about
/// 10.6 bytes per nonzero against CSR's 12.
constexpr double MAX_FILL = 1.25;

/// Block row I's three sums with AVX2: lanes 0-2 of one register are rows 3I .. 3I + 2 (lane 3 is
/// unused). Each lane adds b(r, c) x_c one term at a time in column order, as the scalar loop does,
/// with separate multiplies and adds (the target has no FMA to contract them): the same y to the
/// last bit. A column's unaligned four-wide load reads one entry past the block (the storage keeps
/// a trailing zero).
#ifdef CB_HAVE_AVX2_KERNEL
__attribute__((target("avx2"))) inline __m256d block_step(__m256d s, const double* __restrict b,
                                                          const double* __restrict xj)
{
    s = _mm256_add_pd(s, _mm256_mul_pd(_mm256_loadu_pd(b), _mm256_broadcast_sd(xj)));
    s = _mm256_add_pd(s, _mm256_mul_pd(_mm256_loadu_pd(b + 3), _mm256_broadcast_sd(xj + 1)));
    return _mm256_add_pd(s, _mm256_mul_pd(_mm256_loadu_pd(b + 6), _mm256_broadcast_sd(xj + 2)));
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
    m_mirror_checked = false;
    m_blocks_scaled = false;
    for (const AFormat asked : tries) {
        if (asked != AFormat::BSR && asked != AFormat::SBSR) break;
        double fill = 0.0;
        const bool upper = asked == AFormat::SBSR;
        m_why_csr.clear();
        // An A its reader made symmetric to the bit is not checked again, and its blocks are scaled
        // as they are built; otherwise the mirror is checked on A's own blocks, then scaled.
        const bool trusted = upper && m_a_symmetric;
        bool built = false;
        if (trusted) {
            built = build_symmetric_upper_block_rows(A, m_scale, m_blocks, MAX_FILL, fill, m_why_csr);
        } else if (upper) {
            built = build_upper_block_rows(A, m_blocks, MAX_FILL, fill, m_why_csr);
            if (built) {
                m_mirror_checked = true;
                g_mirror_checks.fetch_add(1, std::memory_order_relaxed);
                built = upper_blocks_mirror_a(A, m_blocks, m_why_csr);
            }
        } else
            built = build_block_rows(A, m_blocks, MAX_FILL, fill, m_why_csr);
        if (built) {
            m_format = asked;
            m_blocks_scaled = trusted && m_scale != nullptr;
            if (asked == AFormat::SBSR && m_scale != nullptr && !m_blocks_scaled) scale_blocks();
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
        if (m_a_symmetric)
            build_symmetric_upper_block_rows(*m_csr, nullptr, m_blocks, MAX_FILL, fill, why);
        else
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
        sym_block_product(Dots::NONE, A.blocks(), A.rows() / 3, x.data(), y.data(), nullptr, nullptr, unused);
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
    if (A.blocks_scaled()) {  // SBSR's blocks hold U A U: x itself in, y out, the dots in the pass
        y.resize(A.rows());
        const double xy = sym_block_product(D, A.blocks(), A.rows() / 3, x.data(), y.data(),
                                            w != nullptr ? w->data() : nullptr, skip, xw);
        g_a_products.fetch_add(1, std::memory_order_relaxed);
        return xy;
    }
    const Vec& u = *A.scaling();
    Vec& ux = A.scaled_input();
    ux = u.cwiseProduct(x);
    if (A.format() == AFormat::BSR && A.parts() == 1) {
        // One thread on blocks: y scaled and the dots summed inside the kernel, no pass after it
        // (the same y and dots as that pass, below, to the last bit).
        y.resize(A.rows());
        const double xy = block_product<D, true>(A.blocks(), 0, A.rows() / 3, ux.data(), y.data(),
                                                 w != nullptr ? w->data() : nullptr, skip, xw, u.data(), x.data());
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
            sym_block_product(Dots::ALL, A.blocks(), A.rows() / 3, x.data(), y.data(), w.data(), nullptr, xw);
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

double a_product_dots_next_direction(const AOperator& A, Vec& p, const Vec& z, double beta, Vec& y, const Vec& w,
                                     const char* skip, double& pw)
{
    const bool in_pass = A.format() == AFormat::SBSR && (A.scaling() == nullptr || A.blocks_scaled());
    if (!in_pass) {
        p = z - beta * p;
        return skip != nullptr ? a_product_dots(A, p, y, w, skip, pw) : a_product_dots(A, p, y, w, pw);
    }
    y.resize(A.rows());
    const double py = sym_block_product(skip != nullptr ? Dots::MASKED : Dots::ALL, A.blocks(), A.rows() / 3, p.data(),
                                        y.data(), w.data(), skip, pw, DirectionUpdate{p.data(), z.data(), beta});
    g_a_products.fetch_add(1, std::memory_order_relaxed);
    return py;
}

double a_product_dots(const AOperator& A, const Vec& x, Vec& y, const Vec& w, const char* skip, double& xw)
{
    if (A.scaling() != nullptr) return scaled_product<Dots::MASKED>(A, x, y, &w, skip, xw);
    y.resize(A.rows());
    double xy = 0.0;
    if (A.format() == AFormat::SBSR)
        xy = sym_block_product(Dots::MASKED, A.blocks(), A.rows() / 3, x.data(), y.data(), w.data(), skip, xw);
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

long mirror_check_count() { return g_mirror_checks.load(std::memory_order_relaxed); }

bool block_kernel_is_simd() { return simd_block_kernel(); }

void force_scalar_block_kernel(bool scalar) { g_force_scalar.store(scalar, std::memory_order_relaxed); }

}  // namespace cb
