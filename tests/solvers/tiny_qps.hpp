#pragma once
/// Tiny hand-derived QPs shared by the solver tests (each documents its solution).
/// min 1/2 x'Ax - b'x  s.t.  Jx >= c.
#include "solvers/core/qp.hpp"

#include <vector>

namespace cb::testing_qps {

/// Builds an owned Qp from dense matrices (rows of J given as dense rows).
inline Qp dense_qp(const Eigen::MatrixXd& A, const Vec& b, const Eigen::MatrixXd& J, const Vec& c, const Vec& x0)
{
    Qp qp;
    qp.A = A.sparseView();
    qp.A.makeCompressed();
    qp.b = b;
    qp.J = SpMat(J.rows(), A.cols());
    if (J.rows() > 0) qp.J = J.sparseView();
    qp.J.makeCompressed();
    qp.c = c;
    qp.x0 = x0;
    return qp;
}

/// STYLE.md §7: min (x0^2 + x1^2) - 2 x1  s.t.  x0 >= 1.  A = 2I, b = (0, 2), J = [1 0], c = 1.
/// x* = (1, 1), lambda* = 2.
inline Qp tiny_active_qp()
{
    Eigen::MatrixXd J(1, 2);
    J << 1, 0;
    return dense_qp(2.0 * Eigen::MatrixXd::Identity(2, 2), Eigen::Vector2d(0, 2), J, Vec::Constant(1, 1.0),
                    Vec::Zero(2));
}

/// Two vertices (n = 6), one row each (decoupled). A = diag(2,1,1,4,1,1), b = (0,1,0,4,0,1):
/// unconstrained minimiser (0,1,0,1,0,1). Rows x_0 >= 1 and x_3 >= 2 are both active:
/// x* = (1,1,0,2,0,1), lambda* = (2*1 - 0, 4*2 - 4) = (2, 4).
inline Qp two_row_decoupled_qp()
{
    Eigen::MatrixXd A = Eigen::MatrixXd::Zero(6, 6);
    A.diagonal() << 2, 1, 1, 4, 1, 1;
    Vec b(6);
    b << 0, 1, 0, 4, 0, 1;
    Eigen::MatrixXd J = Eigen::MatrixXd::Zero(2, 6);
    J(0, 0) = 1;
    J(1, 3) = 1;
    return dense_qp(A, b, J, Eigen::Vector2d(1, 2), Vec::Zero(6));
}
inline Vec two_row_decoupled_x()
{
    Vec x(6);
    x << 1, 1, 0, 2, 0, 1;
    return x;
}

/// 2-D, coupled A = [[2,1],[1,2]], b = 0, rows x0 >= 1 and x1 >= 1 (both on vertex 0, so NOT
/// decoupled). x* = (1, 1): A x* = (3, 3) = J' lambda  ->  lambda* = (3, 3).
inline Qp two_row_coupled_qp()
{
    Eigen::MatrixXd A(2, 2);
    A << 2, 1, 1, 2;
    return dense_qp(A, Vec::Zero(2), Eigen::MatrixXd::Identity(2, 2), Eigen::Vector2d(1, 1), Vec::Zero(2));
}

/// Unconstrained (m = 0): A = [[4,1,0],[1,3,1],[0,1,2]], x* = (1,-1,2), b = A x* = (3,0,3).
inline Qp unconstrained_qp()
{
    Eigen::MatrixXd A(3, 3);
    A << 4, 1, 0, 1, 3, 1, 0, 1, 2;
    return dense_qp(A, Eigen::Vector3d(3, 0, 3), Eigen::MatrixXd(0, 3), Vec(0), Vec::Zero(3));
}
inline Vec unconstrained_x() { return Eigen::Vector3d(1, -1, 2); }

}  // namespace cb::testing_qps
