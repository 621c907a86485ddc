#pragma once
/// Backward Euler with Rayleigh damping, as one QP per Newton step, in absolute positions and
/// scaled by h^2 (so that the QP's absolute tolerances mean what the paper's mean).
/// Ref: Li et al. 2015, Sec. 3.1, eq. (4)-(7).
///
/// Derivation. With v' = (x - x_n)/h, backward Euler reads
///     M (v' - v_n) / h = f_ext - grad E(x) - C v',      C = a_M M + a_K K.
/// Multiplying by h^2 gives the stationarity condition of the incremental potential
///     G(x) = 1/2 (x - xhat)'M(x - xhat) + h^2 E(x) + h/2 (x - x_n)'C(x - x_n) - h^2 f_ext'x,
/// with xhat = x_n + h v_n. One Newton step from x_k, with the corotated rotations of x_k held
/// fixed (Hessian of E ~ K(x_k)), solves
///     A x = b,   A = (1 + h a_M) M + (h^2 + h a_K) K(x_k),   b = A x_k - grad G(x_k),
///     grad G(x_k) = M (x_k - xhat) + h^2 (grad E(x_k) - f_ext) + h C (x_k - x_n).
/// For the first (and, as the authors did, only) Newton step x_k = x_n, so
///     b = A x_n + h M v_n + h^2 (f_ext - grad E(x_n)).
/// With contacts the step is the QP  min 1/2 x'Ax - b'x  s.t.  Jx >= c  (eq. 9).
#include "sim/fem_corotated.hpp"

namespace cb::sim {

struct StepParameters {
    double h = 0.01;                  ///< s
    double a_M = 0.0;                 ///< 1/s: Rayleigh mass damping (C = a_M M + a_K K)
    double a_K = 0.0;                 ///< s: Rayleigh stiffness damping
    Vec3 gravity = Vec3(0, -9.8, 0);  ///< m/s^2
};

/// Builds A and b of one Newton step (the rotations of `fem` are updated to x_k).
/// @param x_n, v_n  positions and velocities at the start of the step (3#V)
/// @param x_k       current Newton iterate (x_n for the first step)
void assemble_newton_qp(CorotatedFem& fem, const StepParameters& p, const Vec& x_n, const Vec& v_n, const Vec& x_k,
                        SpMat& A, Vec& b);

/// External force vector (gravity on the lumped masses), N.
Vec gravity_force(const CorotatedFem& fem, const Vec3& gravity);

/// 1/2 v'Mv.
double kinetic_energy(const CorotatedFem& fem, const Vec& v);

}  // namespace cb::sim
