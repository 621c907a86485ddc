#pragma once
/// A sparse matrix as a Siconos NumericsMatrix in triplet storage (the caller frees it: NM_free).
/// Included only where Siconos numerics is built (CB_HAVE_SICONOS).
#include "solvers/core/types.hpp"

#include <NumericsMatrix.h>
#include <NumericsSparseMatrix.h>

namespace cb {

inline NumericsMatrix* numerics_triplet_matrix(const SpMat& A)
{
    NumericsMatrix* N = NM_create(NM_SPARSE, static_cast<int>(A.rows()), static_cast<int>(A.cols()));
    NM_triplet_alloc(N, A.nonZeros());
    N->matrix2->origin = NSM_TRIPLET;
    for (int i = 0; i < A.outerSize(); ++i)
        for (SpMat::InnerIterator it(A, i); it; ++it) NM_zentry(N, i, static_cast<int>(it.col()), it.value(), 0.0);
    return N;
}

}  // namespace cb
