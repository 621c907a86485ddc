#pragma once
/// The machine-independent work unit (docs/work.md): one unit is one product with A, which costs
/// 2 nnz(A) flops. Work that is not a product with A (CHOLMOD factorisations and solves,
/// incomplete Cholesky, dense sweeps) is counted in flops in Counters::work_flops at the line that
/// does it; work_units() converts the total to A-product equivalents. Products with J and vector
/// operations (O(nnz(J) + n) per iteration in every solver) are not counted.
#include "solvers/core/solver.hpp"
#include "solvers/core/types.hpp"

#include <cholmod.h>

namespace cb {

/// Flops of one product with A: 2 nnz(A) (at least 1, so an empty A divides safely).
double a_product_flops(const SpMat& A);

/// A-product equivalents of a solve's work: a_products + work_flops / (2 nnz(A)).
double work_units(const Counters& counters, const SpMat& A);
double work_units(long a_products, double work_flops, const SpMat& A);

/// A CHOLMOD numeric factorisation: the flop count of its last analysis (cholmod_common::fl,
/// the LL' count for the chosen ordering). Pass the factor's `.cholmod()`.
double cholmod_factor_flops(const cholmod_common& common);

/// Solving with L and L' (forward and back substitution): 4 nnz(L) flops per right-hand side
/// (nnz(L) = cholmod_common::lnz of the last analysis).
double cholmod_solve_flops(const cholmod_common& common, long right_hand_sides = 1);

/// A dense (rows x cols) matrix times a vector: 2 rows cols flops.
double dense_matvec_flops(double rows, double cols);

/// Forward or back substitution with a dense triangular q x q factor: q^2 flops.
double dense_triangular_solve_flops(double q);

/// A sparse matrix with `nonzeros` entries times `vectors` vectors: 2 nonzeros vectors flops.
double sparse_product_flops(double nonzeros, double vectors = 1.0);

}  // namespace cb
