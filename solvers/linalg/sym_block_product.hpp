#pragma once
/// y = A x from the blocks on and above the block diagonal of a symmetric A (AFormat::SBSR), for
/// AOperator's products (solvers/linalg/a_product.cpp). Block row I adds B x_J to y_I and scatters
/// B' x_I into y_J (J > I); y equals the CSR product's to rounding (another order of the terms).
/// Two kernels (AVX2 where the CPU has it, and a scalar loop) give the same y and dots to the bit.
#include "solvers/linalg/a_product.hpp"
#include "solvers/linalg/block_kernels.hpp"

#include <cstddef>

namespace cb {

/// y = A x over the nb block rows of B (y's 3 nb entries all written; y must not alias x); with
/// `dots` != NONE also x'y (returned) and x'w into xw (MASKED: only where skip[i] == 0).
double sym_block_product(Dots dots, const BlockRows& B, std::ptrdiff_t nb, const double* px, double* py,
                         const double* pw, const char* skip, double& xw);

}  // namespace cb
