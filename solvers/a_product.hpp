#pragma once
/// The counted product with A: y = A x through one non-inline function that also bumps a
/// process-wide counter. Solvers use it for their plain `A * v` products, so the harness can
/// count A-products itself (around each solve) instead of trusting the solver's own count.
/// Work that bypasses it (CHOLMOD, fused kernels) shows up in instruction counts instead.
#include "solvers/types.hpp"

namespace cb {

/// y = A x, counted. y is resized; it must not alias x.
void a_product(const SpMat& A, const Vec& x, Vec& y);

/// y = A x with x'y and x'w summed in the same pass over A, counted as one product: the CG step's
/// p'Ap and p'g without two more passes over vectors the product has just pushed out of cache.
/// y is resized; it must not alias x or w. @return x'y; xw receives x'w.
double a_product_dots(const SpMat& A, const Vec& x, Vec& y, const Vec& w, double& xw);

/// A x, counted (for expressions such as `b - a_product(A, x)`).
Vec a_product(const SpMat& A, const Vec& x);

/// A-products done through a_product() by this process so far (all threads).
long a_product_count();

}  // namespace cb
