#include "solvers/a_product.hpp"

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <limits>

namespace cb {

namespace {

std::atomic<long> g_a_products{0};

/// Block entries stored per nonzero beyond which BSR is refused: at 1.25 it still reads about
/// 10.6 bytes per nonzero against CSR's 12.
constexpr double MAX_FILL = 1.25;

enum class Dots { NONE, ALL, MASKED };

/// y = A x on the block rows; with D != NONE also x'y and x'w (masked: where skip[i] == 0).
/// Each row's sum runs over its columns in increasing order, as the CSR loop's does, and the
/// stored zeros add exact zeros: y, x'y and x'w equal the CSR kernels' to the last bit (finite x).
/// Block rows first .. last - 1 only (a thread's range); their dots are that range's partial sums.
template <Dots D>
double block_product(const BlockRows& B, std::ptrdiff_t first, std::ptrdiff_t last, const double* __restrict px,
                     double* __restrict py, const double* __restrict pw, const char* __restrict skip, double& xw)
{
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
        py[i] = s0;
        py[i + 1] = s1;
        py[i + 2] = s2;
        if constexpr (D != Dots::NONE) {
            xy += px[i] * s0;
            xy += px[i + 1] * s1;
            xy += px[i + 2] * s2;
            for (std::ptrdiff_t r = i; r < i + 3; ++r)
                if (D == Dots::ALL || !skip[r]) dot_w += px[r] * pw[r];
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

bool build_block_rows(const SpMat& A, BlockRows& out, double max_fill, double& fill, std::string& why)
{
    out = BlockRows{};
    fill = 0.0;
    const Eigen::Index n = A.rows();
    if (n == 0 || n % 3 != 0 || A.cols() != n) {
        why = "the DOF count " + std::to_string(n) + " is not a positive multiple of 3";
        return false;
    }
    if (!A.isCompressed()) {
        why = "A is not compressed";
        return false;
    }
    const std::ptrdiff_t nb = n / 3;
    const int* outer = A.outerIndexPtr();
    const int* inner = A.innerIndexPtr();
    // Pass 1: the distinct block columns of each block row (columns must increase along a row,
    // or the block sums would not follow the CSR sums' order).
    std::vector<std::ptrdiff_t> seen(static_cast<size_t>(nb), -1);
    std::vector<int> start(static_cast<size_t>(nb) + 1, 0);
    long long blocks = 0;
    for (std::ptrdiff_t I = 0; I < nb; ++I) {
        for (std::ptrdiff_t i = 3 * I; i < 3 * I + 3; ++i) {
            for (int k = outer[i]; k < outer[i + 1]; ++k) {
                if (k > outer[i] && inner[k] <= inner[k - 1]) {
                    why = "A's columns are not increasing in row " + std::to_string(i);
                    return false;
                }
                const std::ptrdiff_t J = inner[k] / 3;
                if (seen[static_cast<size_t>(J)] != I) {
                    seen[static_cast<size_t>(J)] = I;
                    ++blocks;
                }
            }
        }
        if (blocks > std::numeric_limits<int>::max() / 9) {
            why = "A has too many blocks for 32-bit block offsets";
            return false;
        }
        start[static_cast<size_t>(I) + 1] = static_cast<int>(blocks);
    }
    const double nnz = static_cast<double>(A.nonZeros());
    fill = nnz > 0.0 ? 9.0 * static_cast<double>(blocks) / nnz : 1.0;
    if (fill > max_fill) {
        why = "A's nonzeros do not form 3x3 blocks (" + std::to_string(fill) + " stored entries per nonzero)";
        return false;
    }
    // Pass 2: block columns in increasing order, then the values (absent entries stay zero).
    out.start = std::move(start);
    out.column.resize(static_cast<size_t>(blocks));
    out.value.assign(static_cast<size_t>(blocks) * 9, 0.0);
    std::vector<int> slot(static_cast<size_t>(nb), -1);
    const double* val = A.valuePtr();
    for (std::ptrdiff_t I = 0; I < nb; ++I) {
        int* cols = out.column.data() + out.start[static_cast<size_t>(I)];
        int count = 0;
        for (std::ptrdiff_t i = 3 * I; i < 3 * I + 3; ++i)
            for (int k = outer[i]; k < outer[i + 1]; ++k) {
                const int J = inner[k] / 3;
                if (slot[static_cast<size_t>(J)] != -2) {
                    slot[static_cast<size_t>(J)] = -2;
                    cols[count++] = J;
                }
            }
        std::sort(cols, cols + count);
        const int base = out.start[static_cast<size_t>(I)];
        for (int q = 0; q < count; ++q) slot[static_cast<size_t>(cols[q])] = base + q;
        for (std::ptrdiff_t i = 3 * I; i < 3 * I + 3; ++i) {
            const std::ptrdiff_t r = i - 3 * I;
            for (int k = outer[i]; k < outer[i + 1]; ++k) {
                const int J = inner[k] / 3;
                const std::ptrdiff_t c = inner[k] - 3 * J;
                out.value[9 * static_cast<size_t>(slot[static_cast<size_t>(J)]) + static_cast<size_t>(3 * c + r)] =
                    val[k];
            }
        }
        for (int q = 0; q < count; ++q) slot[static_cast<size_t>(cols[q])] = -1;
    }
    why.clear();
    return true;
}

AFormat AOperator::prepare(AFormat wanted, int threads)
{
    m_format = AFormat::CSR;
    m_blocks = BlockRows{};
    m_why_csr.clear();
    m_fill = 0.0;
    if (wanted == AFormat::BSR) {
        double fill = 0.0;
        if (build_block_rows(*m_csr, m_blocks, MAX_FILL, fill, m_why_csr)) {
            m_format = AFormat::BSR;
            m_fill = fill;
        } else {
            m_blocks = BlockRows{};
        }
    }
    // Threads only where the raw loops run (compressed A); each range keeps enough nonzeros to
    // repay waking its thread. The ranges depend on A and threads only, never on the machine.
    const SpMat& A = *m_csr;
    const long nnz = static_cast<long>(A.nonZeros());
    int parts = std::max(1, threads);
    parts = static_cast<int>(std::min<long>(parts, std::max(1L, nnz / MIN_NONZEROS_PER_PART)));
    if (!A.isCompressed()) parts = 1;
    if (m_format == AFormat::BSR)
        m_part_start = split_rows(m_blocks.start.data(), static_cast<std::ptrdiff_t>(m_blocks.start.size()) - 1, parts);
    else if (A.isCompressed())
        m_part_start = split_rows(A.outerIndexPtr(), A.rows(), parts);
    else
        m_part_start = {0, static_cast<int>(A.rows())};
    return m_format;
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
    if (m_format == AFormat::BSR)
        return static_cast<double>(m_blocks.value.size()) * 8.0 + static_cast<double>(m_blocks.column.size()) * 4.0 +
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

void a_product(const AOperator& A, const Vec& x, Vec& y)
{
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

double a_product_dots(const AOperator& A, const Vec& x, Vec& y, const Vec& w, double& xw)
{
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
    y.resize(A.rows());
    double xy = 0.0;
    if (A.parts() > 1)
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

}  // namespace cb
