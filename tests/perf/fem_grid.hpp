#pragma once
/// A FEM-like A on a box of nx x ny x nz cubes (problems/synthetic.hpp's fem_like_matrix with the
/// other parameters at their defaults): the block product tests' grids.
#include "problems/synthetic.hpp"

namespace cb::test {

inline SpMat fem_grid(int nx, int ny, int nz)
{
    FemGridParams p;
    p.nx = nx;
    p.ny = ny;
    p.nz = nz;
    return fem_like_matrix(p);
}

}  // namespace cb::test
