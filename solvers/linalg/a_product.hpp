#pragma once
/// The counted product with A: y = A x through one non-inline function that also bumps a
/// process-wide counter. Solvers multiply by A through an AOperator, prepared once in their setup,
/// so the harness can count A-products itself (around each solve) instead of trusting the
/// solver's own count, and so A's storage for the product is chosen in one place.
/// Work that bypasses it (CHOLMOD, sparse partial products) shows up in instruction counts instead.
#include "solvers/core/qp.hpp"
#include "solvers/core/types.hpp"
#include "solvers/linalg/a_format.hpp"

#include <memory>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

namespace cb {

/// An allocator whose resize() leaves doubles unwritten: the block build writes every entry itself,
/// and on a million DOFs zeroing the values first was a whole extra pass over them.
template <typename T> struct UninitializedAllocator : std::allocator<T> {
    template <typename U> struct rebind {  // NOLINT(readability-identifier-naming): the allocator interface names it
        using other = UninitializedAllocator<U>;
    };
    UninitializedAllocator() = default;
    template <typename U> UninitializedAllocator(const UninitializedAllocator<U>&) noexcept {}
    template <typename U> void construct(U* p) noexcept(std::is_nothrow_default_constructible<U>::value)
    {
        ::new (static_cast<void*>(p)) U;  // default-initialised: no write for a double
    }
    template <typename U, typename... Args> void construct(U* p, Args&&... args)
    {
        ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
    }
};

/// A's 3x3 block rows: block row I holds rows 3I, 3I+1, 3I+2. A block is stored column by column
/// (value (r, c) at 9k + 3c + r) so that a column's three entries meet three partial sums at once.
/// Entries absent from A are stored as zeros.
struct BlockRows {
    std::vector<int> start;   ///< block row I's blocks are start[I] .. start[I + 1] - 1
    std::vector<int> column;  ///< block column per block, increasing within a block row
    /// 9 per block, and one trailing zero (the AVX2 kernel reads past the last)
    std::vector<double, UninitializedAllocator<double>> value;
};

/// The operator x -> A x that a solver multiplies by. It refers to A (no copy of the CSR); A must
/// outlive it. prepare() may build a block copy; products then read it instead of A.
class AOperator {
public:
    /// An A of no known symmetry: SBSR checks that A equals A' before it reads the upper blocks.
    explicit AOperator(const SpMat& A) : m_csr(&A) {}
    /// The QP's A, with what its reader established: when qp.a_symmetric (A equals A' to the bit,
    /// rows sorted) SBSR reads the upper blocks without checking their mirror again.
    explicit AOperator(const QpView& qp) : m_csr(&qp.A), m_a_symmetric(qp.a_symmetric) {}
    /// Chooses the storage of the products: BSR (or SBSR) when asked and A has the block structure
    /// (n a multiple of 3, compressed, sorted columns, at most 25% stored zeros), else CSR;
    /// why_csr() says why. BSR and CSR sum each row in column order, so y is the same to the last
    /// bit; SBSR, which reads A's upper block triangle (A must be symmetric, as a QP's is), sums in
    /// another order (y equal to rounding) and runs on one thread whatever `threads` says.
    /// `threads` (the common setting, >= 1) splits the products into that many fixed row ranges of
    /// about equal nonzeros (fewer when A is small: at least MIN_NONZEROS_PER_PART each); the same
    /// A and threads give the same ranges, so y is the same to the last bit and the fused dots,
    /// summed range by range in range order, the same on every run (docs/a_product.md).
    /// AUTO (the common setting `a_format`'s default): on one thread and an A of at least
    /// AUTO_SYMMETRIC_MIN_NONZEROS, SBSR when A is symmetric to the bit; else BSR, which keeps the
    /// iterates bit-equal to CSR's (SBSR's order moved iteration counts on suites/ci.json, whose
    /// QPs are all far smaller). The choice depends on A and threads only, never on the machine.
    AFormat prepare(AFormat wanted, int threads = 1);
    /// Row ranges the products are split into (1: one thread, today's loops).
    int parts() const { return static_cast<int>(m_part_start.size()) - 1; }
    /// Range p covers rows (BSR: block rows) part_start()[p] .. part_start()[p + 1] - 1.
    const std::vector<int>& part_start() const { return m_part_start; }
    AFormat format() const { return m_format; }
    /// Whether the last prepare() checked that A equals A' (SBSR asked of an A not known symmetric).
    bool mirror_checked() const { return m_mirror_checked; }
    /// Why the products read CSR (empty when blocks, or when blocks were not asked for).
    const std::string& why_csr() const { return m_why_csr; }
    /// Stored block entries per nonzero of A (BSR >= 1, SBSR about half that; 0 when CSR).
    double fill() const { return m_fill; }
    /// Bytes one product streams from A's storage (values, indices, row starts).
    double matrix_bytes() const;
    /// A itself (CSR): for sparse partial products, diagonals and factorizations.
    const SpMat& csr() const { return *m_csr; }
    /// The blocks the products read (BSR: all; SBSR: the upper block triangle; empty when CSR).
    const BlockRows& blocks() const { return m_blocks; }
    Eigen::Index rows() const { return m_csr->rows(); }
    /// From now on the products give U A U x (U = diag(u)) instead of A x, without a scaled copy
    /// of A (mprgp-coupled's precond = scaled: the QP in y = U^-1 x). On BSR and CSR x is scaled
    /// into a buffer before the product; on BSR with one thread the block kernels scale each row's
    /// sum before storing it and sum the dots with it, else y is scaled in a pass on the way out.
    /// Both give the same y and dots to the last bit. On SBSR, whose blocks are a copy already,
    /// the blocks themselves are scaled (entry (r, c) becomes (u_r a_rc) u_c), in prepare() or
    /// here: the product then reads x itself, with no pass before or after it (y equal to the
    /// buffered product's to rounding, as SBSR's own order is).
    /// u must outlive the operator and keep its values; nullptr: A itself again.
    void scale_by(const Vec* u);
    /// The scaling of the products (nullptr when they give A x).
    const Vec* scaling() const { return m_scale; }
    /// Whether the stored blocks already hold U A U (SBSR with a scaling): the products then
    /// read x as it is.
    bool blocks_scaled() const { return m_blocks_scaled; }
    /// The buffer holding U x during a scaled product (one per operator: products on one
    /// operator run one at a time).
    Vec& scaled_input() const { return m_scaled_x; }

private:
    /// Multiplies SBSR's stored blocks by u on both sides (after they were built from A).
    void scale_blocks();
    const SpMat* m_csr;
    bool m_a_symmetric = false;  ///< A equals A' to the bit, as its reader established (Qp::a_symmetric)
    bool m_mirror_checked = false;
    const Vec* m_scale = nullptr;
    bool m_blocks_scaled = false;  ///< SBSR's blocks hold U A U (scale_by)
    mutable Vec m_scaled_x;
    AFormat m_format = AFormat::CSR;
    BlockRows m_blocks;
    std::string m_why_csr;
    double m_fill = 0.0;
    std::vector<int> m_part_start{0, 0};
};

/// Nonzeros of A from which `a_format = auto` reads the upper blocks on one thread (about 9 MB of
/// BSR blocks). The upper blocks were faster on every frame measured, small ones too; the bound
/// only keeps the small QPs of suites/ci.json on BSR's bits (docs/a_product.md).
constexpr long AUTO_SYMMETRIC_MIN_NONZEROS = 1L << 20;

/// Whether `a_format = auto` tries the upper blocks first for an A of `nonzeros` on `threads`.
inline bool auto_prefers_upper_blocks(long nonzeros, int threads)
{
    return threads <= 1 && nonzeros >= AUTO_SYMMETRIC_MIN_NONZEROS;
}

/// Fewest nonzeros of A per row range of a threaded product: below about this many a range's
/// work is shorter than waking a thread for it.
constexpr long MIN_NONZEROS_PER_PART = 32768;

/// Whether threaded products can run in parallel in this build (OpenMP found); without it the
/// ranges run one after the other, with the same results.
bool a_product_parallel_build();

/// Builds A's block rows; false (with `why`) when A has no usable 3x3 block structure.
bool build_block_rows(const SpMat& A, BlockRows& out, double max_fill, double& fill, std::string& why);

/// As build_block_rows(), keeping only the blocks on and above the block diagonal (block column
/// >= block row); `fill` is per nonzero of that part of A.
bool build_upper_block_rows(const SpMat& A, BlockRows& out, double max_fill, double& fill, std::string& why);

/// As build_upper_block_rows() for an A known to equal A' to the bit with increasing columns in
/// every row (Qp::a_symmetric): each row is read from its block diagonal on (the part left of it is
/// neither read nor checked), and with `scale` the blocks hold U A U, entry (r, c) of block (I, J)
/// being (u_r a_rc) u_c as AOperator::scale_by forms it, in the same pass.
bool build_symmetric_upper_block_rows(const SpMat& A, const Vec* scale, BlockRows& out, double max_fill, double& fill,
                                      std::string& why);

/// Whether the upper blocks U of A (build_upper_block_rows) stand for all of A, i.e. A is symmetric
/// to the bit; `why` names the first entry that differs.
bool upper_blocks_mirror_a(const SpMat& A, const BlockRows& U, std::string& why);

/// y = A x, counted. y is resized; it must not alias x.
void a_product(const AOperator& A, const Vec& x, Vec& y);

/// y = A x with x'y and x'w summed in the same pass over A, counted as one product: the CG step's
/// p'Ap and p'g without two more passes over vectors the product has just pushed out of cache.
/// y is resized; it must not alias x or w. @return x'y; xw receives x'w.
double a_product_dots(const AOperator& A, const Vec& x, Vec& y, const Vec& w, double& xw);

/// As above with x'w summed only where skip[i] == 0 (mprgp's p'g over the DOFs outside its rows).
double a_product_dots(const AOperator& A, const Vec& x, Vec& y, const Vec& w, const char* skip, double& xw);

/// The CG step's next direction and its product: p = z - beta p, then y = A p with p'y (returned)
/// and p'w (pw; with `skip`, only where skip[i] == 0), counted as one product. On SBSR the update
/// runs inside the product's pass, ahead of the rows that read p (no pass of its own); elsewhere
/// in a pass of its own first. p, y and the dots are the same to the bit either way. y must not
/// alias p, z or w; z not p.
double a_product_dots_next_direction(const AOperator& A, Vec& p, const Vec& z, double beta, Vec& y, const Vec& w,
                                     const char* skip, double& pw);

/// A x, counted (for expressions such as `b - a_product(A, x)`).
Vec a_product(const AOperator& A, const Vec& x);

/// One-off products outside a solver's iterations (the harness's measure, peers' reports): CSR, counted.
void a_product(const SpMat& A, const Vec& x, Vec& y);
double a_product_dots(const SpMat& A, const Vec& x, Vec& y, const Vec& w, double& xw);
Vec a_product(const SpMat& A, const Vec& x);

/// A-products done through a_product() by this process so far (all threads).
long a_product_count();

/// Checks of A's mirror (upper_blocks_mirror_a) AOperator::prepare() did in this process so far:
/// SBSR on an A whose symmetry the QP did not carry (Qp::a_symmetric).
long mirror_check_count();

/// Whether the BSR products run the AVX2 kernel (the CPU has AVX2 and the scalar loop is not
/// forced). Both kernels give the same y and dots to the last bit; tests compare them.
bool block_kernel_is_simd();
/// Forces the scalar BSR loop (true) or lets the CPU decide (false): for tests and benchmarks.
void force_scalar_block_kernel(bool scalar);

}  // namespace cb
