// A's 3x3 block rows built from its CSR (the storage of the block products in a_product.cpp): the
// three-way merge of a block row's CSR rows, a straight copy for FEM rows, and the symmetry check of
// the upper blocks.
#include "solvers/linalg/a_product.hpp"
#include "solvers/linalg/prefault.hpp"

#include <algorithm>
#include <limits>
#include <string>

namespace cb {

namespace {

/// Block row I's distinct block columns, in increasing order, from its three CSR rows (each
/// sorted), row r read from entry lo[r] on: a three-way merge of the rows' columns / 3, starting at
/// block column `from`. `visit(J, k[3], end[3])` is called per block column with each row's first
/// entry in it (entries up to end[r] belong to J). Returns false when a row's columns do not increase.
template <typename Visit>
bool merge_block_columns(const int* outer, const int* inner, std::ptrdiff_t I, const int* lo, int from, Visit&& visit)
{
    int k[3], stop[3];
    for (int r = 0; r < 3; ++r) {
        const std::ptrdiff_t i = 3 * I + r;
        k[r] = lo[r];
        stop[r] = outer[i + 1];
        for (int q = k[r] + 1; q < stop[r]; ++q)
            if (inner[q] <= inner[q - 1]) return false;
        while (k[r] < stop[r] && inner[k[r]] / 3 < from) ++k[r];  // the lower triangle, when skipped
    }
    for (;;) {
        int J = std::numeric_limits<int>::max();
        for (int r = 0; r < 3; ++r)
            if (k[r] < stop[r]) J = std::min(J, inner[k[r]] / 3);
        if (J == std::numeric_limits<int>::max()) return true;
        int end[3];
        for (int r = 0; r < 3; ++r) {
            end[r] = k[r];
            while (end[r] < stop[r] && inner[end[r]] / 3 == J) ++end[r];
        }
        visit(J, k, end);
        for (int r = 0; r < 3; ++r) k[r] = end[r];
    }
}

/// Whether block row I's three CSR rows, row r read from entry lo[r] on, hold the same columns, in
/// whole increasing groups 3J, 3J + 1, 3J + 2 (a FEM matrix's vertex blocks): then its blocks are
/// those groups, and their values are copied straight in, without the merge (the same blocks as
/// the merge's). `groups` receives the part's group count and `first` the first group whose block
/// column is >= `from`.
bool whole_groups(const int* outer, const int* inner, std::ptrdiff_t I, const int* lo, int from, int& groups,
                  int& first)
{
    const int len = outer[3 * I + 1] - lo[0];
    if (len % 3 != 0 || outer[3 * I + 2] - lo[1] != len || outer[3 * I + 3] - lo[2] != len) return false;
    const int* c0 = inner + lo[0];
    const int* c1 = inner + lo[1];
    const int* c2 = inner + lo[2];
    groups = len / 3;
    first = groups;
    int previous = -1;
    for (std::ptrdiff_t g = 0; g < groups; ++g) {
        const int col = c0[3 * g];
        if (col % 3 != 0 || col / 3 <= previous || c0[3 * g + 1] != col + 1 || c0[3 * g + 2] != col + 2) return false;
        for (std::ptrdiff_t e = 3 * g; e < 3 * g + 3; ++e)
            if (c1[e] != c0[e] || c2[e] != c0[e]) return false;
        previous = col / 3;
        if (first == groups && previous >= from) first = static_cast<int>(g);
    }
    return true;
}

/// How build_blocks reads A and what it stores.
struct BlockBuild {
    bool upper = false;  ///< only the blocks of block column >= block row
    /// A's rows are known to have increasing columns (Qp::a_symmetric: the readers checked them):
    /// with `upper` each row is read from its block diagonal on (a binary search finds it), the
    /// part left of it is neither read nor checked.
    bool rows_known_sorted = false;
    const Vec* scale = nullptr;  ///< store U A U: entry (r, c) of block (I, J) is (u_r a_rc) u_c
};

/// Block row I's first entry read in each of its rows (lo[3]): the row's start, or with
/// `rows_known_sorted` and `upper` its first entry of block column >= I (a binary search).
void read_from(const int* outer, const int* inner, std::ptrdiff_t I, const BlockBuild& how, int* lo)
{
    for (int r = 0; r < 3; ++r) {
        const std::ptrdiff_t i = 3 * I + r;
        lo[r] = outer[i];
        if (how.upper && how.rows_known_sorted)
            lo[r] = static_cast<int>(std::lower_bound(inner + outer[i], inner + outer[i + 1], static_cast<int>(3 * I)) -
                                     inner);
    }
}

/// Block row I's blocks from its whole groups g = first .. groups - 1 (row r's group g at lo[r] + 3 g),
/// written from block q on; SCALED: entry (r, c) of block (I, J) is u_r a_rc u_c, as scale_blocks forms it.
template <bool SCALED>
void copy_groups(const int* inner, const double* val, std::ptrdiff_t I, const int* lo, int first, int groups,
                 const double* u, std::ptrdiff_t q, int* column, double* value)
{
    const double* v0 = val + lo[0];
    const double* v1 = val + lo[1];
    const double* v2 = val + lo[2];
    for (std::ptrdiff_t g = first; g < groups; ++g, ++q) {
        const int J = inner[lo[0] + 3 * g] / 3;
        column[q] = J;
        double* b = value + 9 * q;
        for (std::ptrdiff_t c = 0; c < 3; ++c) {
            if constexpr (SCALED) {
                const double uc = u[3 * static_cast<std::ptrdiff_t>(J) + c];
                b[3 * c] = u[3 * I] * v0[3 * g + c] * uc;
                b[3 * c + 1] = u[3 * I + 1] * v1[3 * g + c] * uc;
                b[3 * c + 2] = u[3 * I + 2] * v2[3 * g + c] * uc;
            } else {
                b[3 * c] = v0[3 * g + c];
                b[3 * c + 1] = v1[3 * g + c];
                b[3 * c + 2] = v2[3 * g + c];
            }
        }
    }
}

/// A's 3x3 blocks (all, or with how.upper those of block column >= block row only).
bool build_blocks(const SpMat& A, const BlockBuild& how, BlockRows& out, double max_fill, double& fill,
                  std::string& why)
{
    out = BlockRows{};
    fill = 0.0;
    const bool upper = how.upper;
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
    const double* val = A.valuePtr();
    // Pass 1: how many blocks each block row has (columns must increase along a row, or the block
    // sums would not follow the CSR sums' order).
    std::vector<int> start(static_cast<size_t>(nb) + 1, 0);
    // Each block row's first group at or past `from` when its rows are whole groups, else -1:
    // pass 2 copies those rows without checking their columns again.
    std::vector<int> group_first(static_cast<size_t>(nb), -1);
    long long blocks = 0;
    long long lower_nonzeros = 0;  // entries left out by `upper`
    for (std::ptrdiff_t I = 0; I < nb; ++I) {
        const int from = upper ? static_cast<int>(I) : 0;
        int lo[3];
        read_from(outer, inner, I, how, lo);
        for (int r = 0; r < 3; ++r) lower_nonzeros += lo[r] - outer[3 * I + r];
        int groups = 0, first = 0;
        if (whole_groups(outer, inner, I, lo, from, groups, first)) {
            group_first[static_cast<size_t>(I)] = first;
            blocks += groups - first;
            lower_nonzeros += 9LL * first;
            if (blocks > std::numeric_limits<int>::max() / 9) {
                why = "A has too many blocks for 32-bit block offsets";
                return false;
            }
            start[static_cast<size_t>(I) + 1] = static_cast<int>(blocks);
            continue;
        }
        const bool sorted =
            merge_block_columns(outer, inner, I, lo, from, [&](int, const int*, const int*) { ++blocks; });
        if (!sorted) {
            for (std::ptrdiff_t i = 3 * I; i < 3 * I + 3; ++i)
                for (int k = lo[i - 3 * I] + 1; k < outer[i + 1]; ++k)
                    if (inner[k] <= inner[k - 1]) {
                        why = "A's columns are not increasing in row " + std::to_string(i);
                        return false;
                    }
        }
        if (upper)
            for (std::ptrdiff_t i = 3 * I; i < 3 * I + 3; ++i)
                for (int k = lo[i - 3 * I]; k < outer[i + 1] && inner[k] < 3 * I; ++k) ++lower_nonzeros;
        if (blocks > std::numeric_limits<int>::max() / 9) {
            why = "A has too many blocks for 32-bit block offsets";
            return false;
        }
        start[static_cast<size_t>(I) + 1] = static_cast<int>(blocks);
    }
    // Fill: stored entries per nonzero of the part of A they stand for.
    const double nnz = static_cast<double>(A.nonZeros() - lower_nonzeros);
    fill = nnz > 0.0 ? 9.0 * static_cast<double>(blocks) / nnz : 1.0;
    if (fill > max_fill) {
        why = "A's nonzeros do not form 3x3 blocks (" + std::to_string(fill) + " stored entries per nonzero)";
        return false;
    }
    // Pass 2: block columns and values (absent entries stay zero), block by block in storage order.
    out.start = std::move(start);
    out.column.resize(static_cast<size_t>(blocks));
    out.value.resize(static_cast<size_t>(blocks) * 9 + 1);  // unwritten: every entry is set below
    out.value.back() = 0.0;                                 // see block_step
    // On 2 MB pages: the products stream the values and gather across them (docs/a_product.md).
    prefault_huge_for_writing(out.value.data(), out.value.size() * sizeof(double));
    prefault_huge_for_writing(out.column.data(), out.column.size() * sizeof(int));
    int* column = out.column.data();
    double* value = out.value.data();
    const double* u = how.scale ? how.scale->data() : nullptr;
    for (std::ptrdiff_t I = 0; I < nb; ++I) {
        std::ptrdiff_t q = out.start[static_cast<size_t>(I)];
        int lo[3];
        read_from(outer, inner, I, how, lo);
        const int first = group_first[static_cast<size_t>(I)];
        if (first >= 0) {
            const int groups = first + (out.start[static_cast<size_t>(I) + 1] - out.start[static_cast<size_t>(I)]);
            if (u)
                copy_groups<true>(inner, val, I, lo, first, groups, u, q, column, value);
            else
                copy_groups<false>(inner, val, I, lo, first, groups, u, q, column, value);
            continue;
        }
        merge_block_columns(outer, inner, I, lo, upper ? static_cast<int>(I) : 0,
                            [&](int J, const int* k, const int* end) {
                                column[q] = J;
                                double* b = value + 9 * q;
                                std::fill(b, b + 9, 0.0);  // entries absent from A
                                for (int r = 0; r < 3; ++r)
                                    for (int e = k[r]; e < end[r]; ++e) b[3 * (inner[e] - 3 * J) + r] = val[e];
                                if (u)
                                    for (int c = 0; c < 3; ++c)
                                        for (int r = 0; r < 3; ++r)
                                            b[3 * c + r] = u[3 * I + r] * b[3 * c + r] * u[3 * J + c];
                                ++q;
                            });
    }
    why.clear();
    return true;
}

}  // namespace

/// Whether the upper blocks U of A (build_blocks with `upper`) stand for all of A, i.e. A is
/// symmetric to the bit: every nonzero below the block diagonal equals its mirror in U, U holds no
/// other nonzero off its diagonal blocks, and each diagonal block is symmetric. Each block row's
/// blocks are met in increasing block column, so a cursor per block row finds the mirrors in one
/// pass. `why` names the first entry that differs.
bool upper_blocks_mirror_a(const SpMat& A, const BlockRows& U, std::string& why)
{
    const std::ptrdiff_t nb = A.rows() / 3;
    const int* outer = A.outerIndexPtr();
    const int* inner = A.innerIndexPtr();
    const double* val = A.valuePtr();
    std::vector<int> cursor(U.start.begin(), U.start.end() - 1);
    long long lower = 0, upper = 0;
    const auto differs = [&](std::ptrdiff_t i, std::ptrdiff_t j) {
        why = "A is not symmetric (entry (" + std::to_string(i) + ", " + std::to_string(j) + ") differs from (" +
              std::to_string(j) + ", " + std::to_string(i) + "))";
        return false;
    };
    for (std::ptrdiff_t I = 0; I < nb; ++I) {
        for (int k = U.start[static_cast<size_t>(I)]; k < U.start[static_cast<size_t>(I) + 1]; ++k) {
            const double* b = U.value.data() + 9 * static_cast<std::ptrdiff_t>(k);
            if (U.column[static_cast<size_t>(k)] != I) {
                for (int e = 0; e < 9; ++e) upper += b[e] != 0.0;
                continue;
            }
            for (int r = 0; r < 3; ++r)
                for (int c = r + 1; c < 3; ++c)
                    if (b[3 * c + r] != b[3 * r + c]) return differs(3 * I + r, 3 * I + c);
        }
        for (std::ptrdiff_t i = 3 * I; i < 3 * I + 3; ++i)
            for (int k = outer[i]; k < outer[i + 1] && inner[k] < 3 * I; ++k) {
                if (val[k] == 0.0) continue;
                ++lower;
                const int J = inner[k] / 3;  // the mirror (inner[k], i) is in block (J, I)
                int& q = cursor[static_cast<size_t>(J)];
                while (q < U.start[static_cast<size_t>(J) + 1] && U.column[static_cast<size_t>(q)] < I) ++q;
                if (q == U.start[static_cast<size_t>(J) + 1] || U.column[static_cast<size_t>(q)] != I)
                    return differs(i, inner[k]);
                const std::ptrdiff_t r = inner[k] - 3 * J, c = i - 3 * I;
                if (U.value[9 * static_cast<size_t>(q) + static_cast<size_t>(3 * c + r)] != val[k])
                    return differs(i, inner[k]);
            }
    }
    if (lower != upper) {
        why = "A is not symmetric (" + std::to_string(upper) + " nonzeros above its block diagonal, " +
              std::to_string(lower) + " below)";
        return false;
    }
    return true;
}

bool build_block_rows(const SpMat& A, BlockRows& out, double max_fill, double& fill, std::string& why)
{
    return build_blocks(A, BlockBuild{}, out, max_fill, fill, why);
}

bool build_upper_block_rows(const SpMat& A, BlockRows& out, double max_fill, double& fill, std::string& why)
{
    return build_blocks(A, BlockBuild{true, false, nullptr}, out, max_fill, fill, why);
}

bool build_symmetric_upper_block_rows(const SpMat& A, const Vec* scale, BlockRows& out, double max_fill, double& fill,
                                      std::string& why)
{
    return build_blocks(A, BlockBuild{true, true, scale}, out, max_fill, fill, why);
}

}  // namespace cb
