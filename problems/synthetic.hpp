#pragma once
/// Seeded synthetic QP families, for tests and the stress suite (DESIGN.md "Problems").
/// Every family shares one FEM-like SPD matrix: a box of tet cubes, linear elasticity, lumped
/// mass, A = M + h^2 K, the QP of one backward-Euler step of a linear elastic body.
#include "solvers/core/qp.hpp"

#include <nlohmann/json.hpp>
#include <cstdint>
#include <string>
#include <vector>

namespace cb {

struct FemGridParams {  ///< a box of nx*ny*nz cubes, 6 tets each, linear elasticity
    int nx = 4, ny = 4, nz = 4;
    double spacing = 0.1;                                  ///< m
    double youngs = 1e6, poisson = 0.4, density = 1000.0;  ///< Pa, -, kg/m^3
    double h = 0.01;  ///< s; A = M + h^2 K (SPD), the QP of one backward-Euler step
};

/// A = M + h^2 K of the grid body (vertex (i, j, k) at spacing * (i, j, k)), full CSR, exactly
/// symmetric. n = 3 (nx+1)(ny+1)(nz+1); DOF 3 v + d of vertex v = i + (nx+1) (j + (ny+1) k).
/// Throws InputError on bad parameters.
SpMat fem_like_matrix(const FemGridParams& p);

/// A seeded synthetic QP. Throws InputError naming the family or parameter when unknown/bad.
/// Same (family, params, seed) -> the same QP, bit for bit. Bounded before anything is built:
/// grids of at most 1e6 vertices, at most 1e7 rows (random-spd m, zero-rows count, 2 x
/// infeasible pairs); parameters that make any value non-finite (youngs 1e308) are refused, so a
/// generated snapshot always passes read_qpsnap.
Qp make_synthetic(const std::string& family, const nlohmann::json& params, std::uint64_t seed);

std::vector<std::string> synthetic_families();                 ///< sorted
std::string synthetic_family_help(const std::string& family);  ///< params with defaults

}  // namespace cb
