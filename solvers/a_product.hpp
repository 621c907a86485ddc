#pragma once
/// The counted product with A: y = A x through one non-inline function that also bumps a
/// process-wide counter. Solvers multiply by A through an AOperator, built once in their setup,
/// so the harness can count A-products itself (around each solve) instead of trusting the
/// solver's own count, and so A's storage for the product is chosen in one place.
/// Work that bypasses it (CHOLMOD, sparse partial products) shows up in instruction counts instead.
#include "solvers/types.hpp"

namespace cb {

/// The operator x -> A x that a solver multiplies by. It refers to A (no copy); A must outlive it.
class AOperator {
public:
    explicit AOperator(const SpMat& A) : m_csr(&A) {}
    /// A itself (CSR): for sparse partial products, diagonals and factorizations.
    const SpMat& csr() const { return *m_csr; }
    Eigen::Index rows() const { return m_csr->rows(); }

private:
    const SpMat* m_csr;
};

/// y = A x, counted. y is resized; it must not alias x.
void a_product(const AOperator& A, const Vec& x, Vec& y);

/// y = A x with x'y and x'w summed in the same pass over A, counted as one product: the CG step's
/// p'Ap and p'g without two more passes over vectors the product has just pushed out of cache.
/// y is resized; it must not alias x or w. @return x'y; xw receives x'w.
double a_product_dots(const AOperator& A, const Vec& x, Vec& y, const Vec& w, double& xw);

/// A x, counted (for expressions such as `b - a_product(A, x)`).
Vec a_product(const AOperator& A, const Vec& x);

/// One-off products outside a solver's iterations (the harness's measure, peers' reports): CSR, counted.
void a_product(const SpMat& A, const Vec& x, Vec& y);
double a_product_dots(const SpMat& A, const Vec& x, Vec& y, const Vec& w, double& xw);
Vec a_product(const SpMat& A, const Vec& x);

/// A-products done through a_product() by this process so far (all threads).
long a_product_count();

}  // namespace cb
