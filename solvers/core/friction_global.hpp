#pragma once
/// A frictional contact problem in FCLIB's global form, 3-D (Ref: FCLIB, fclib.h, struct fclib_global;
/// Acary, Bremond, Huber (2018), Sec. 2):
///   M v = H r + f,   u = H' v + w,   K*_mu ∋ u + mu ||u_T|| e_n  ⊥  r ∈ K_mu  per contact,
/// with v the n generalised velocities, r and u the 3m local reactions and velocities (contact i:
/// components 3i normal, 3i+1 and 3i+2 tangents). Siconos' GlobalFrictionContactProblem is the same
/// problem with q = f and b = w (its fclib_interface.c maps them so). M is symmetric positive definite
/// (a mass or an iteration matrix); eliminating v gives the local problem of friction_problem.hpp
/// (solvers/friction/friction_global_reduction.hpp).
#include "solvers/core/friction_problem.hpp"
#include "solvers/core/types.hpp"

#include <string>

namespace cb {

struct FrictionGlobal {
    SpMat M;           ///< n x n, both triangles stored (a file's one triangle is mirrored on reading)
    SpMat H;           ///< n x 3m
    Vec f;             ///< n
    Vec w;             ///< 3m
    Vec mu;            ///< m friction coefficients, each finite and >= 0
    std::string name;  ///< the file it came from (for reports and errors)
    Eigen::Index contacts() const { return mu.size(); }
    Eigen::Index unknowns() const { return f.size(); }
};

/// A run on the global problem: r, u (= H' v + w), error (global_relative_error of
/// friction_error.hpp, by the harness) in `run`, and the global velocity v.
struct FrictionGlobalRun {
    FrictionRun run;
    Vec v;
};

}  // namespace cb
