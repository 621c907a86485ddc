// The work unit (docs/work.md): flop counts of the kernels the solvers use, in A-products.
#include "solvers/measure/work_units.hpp"

#include <algorithm>

namespace cb {

double a_product_flops(const SpMat& A) { return std::max(1.0, 2.0 * static_cast<double>(A.nonZeros())); }

double work_units(long a_products, double work_flops, const SpMat& A)
{
    return static_cast<double>(a_products) + work_flops / a_product_flops(A);
}

double work_units(const Counters& counters, const SpMat& A)
{
    return work_units(counters.a_products, counters.work_flops, A);
}

double cholmod_factor_flops(const cholmod_common& common) { return std::max(0.0, common.fl); }

double cholmod_solve_flops(const cholmod_common& common, long right_hand_sides)
{
    return 4.0 * std::max(0.0, common.lnz) * static_cast<double>(right_hand_sides);
}

double dense_matvec_flops(double rows, double cols) { return 2.0 * rows * cols; }

double dense_triangular_solve_flops(double q) { return q * q; }

double sparse_product_flops(double nonzeros, double vectors) { return 2.0 * nonzeros * vectors; }

}  // namespace cb
