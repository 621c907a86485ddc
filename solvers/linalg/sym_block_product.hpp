#pragma once
/// y = A x from the blocks on and above the block diagonal of a symmetric A (AFormat::SBSR), for
/// AOperator's products (solvers/linalg/a_product.cpp). Block row I adds B x_J to y_I and scatters
/// B' x_I into y_J (J > I); y equals the CSR product's to rounding (another order of the terms).
/// Two kernels (AVX2 where the CPU has it, and a scalar loop) give the same y and dots to the bit.
#include "solvers/linalg/a_product.hpp"
#include "solvers/linalg/block_kernels.hpp"

#include <cstddef>

namespace cb {

/// The CG direction's update x = z - beta x, done inside the product's pass (x null: none). x is the
/// product's own x (the same array as its px); z must not alias x or y.
struct DirectionUpdate {
    double* x = nullptr;
    const double* z = nullptr;
    double beta = 0.0;
};

/// y = A x over the nb block rows of B (y's 3 nb entries all written; y must not alias x); with
/// `dots` != NONE also x'y (returned) and x'w into xw (MASKED: only where skip[i] == 0). With
/// `update`, x is first replaced by z - beta x, entry by entry ahead of the rows that read it (at
/// y's zeroing frontier): the same bits as a pass of its own before the product, without its loop.
double sym_block_product(Dots dots, const BlockRows& B, std::ptrdiff_t nb, const double* px, double* py,
                         const double* pw, const char* skip, double& xw, DirectionUpdate update = {});

}  // namespace cb
