// FCLIB's relative natural-map error of a frictional snapshot (see friction_snapshot_error.hpp).
#include "solvers/measure/friction_snapshot_error.hpp"

#include "solvers/measure/friction_error.hpp"

#include <Eigen/SparseCholesky>
#include <cfloat>
#include <cmath>
#include <limits>

namespace cb {

namespace {

bool has_friction(const QpView& qp)
{
    return qp.friction && qp.friction->mu.size() == qp.m() && qp.friction->T.rows() == 2 * qp.m() &&
           qp.friction->T.cols() == qp.n();
}

}  // namespace

SpMat contact_frame_rows(const QpView& qp, Vec* c_all)
{
    const Eigen::Index m = qp.m(), n = qp.n();
    const Friction* f = has_friction(qp) ? qp.friction : nullptr;
    SpMat rows(3 * m, n);
    rows.reserve(qp.J.nonZeros() + (f ? f->T.nonZeros() : 0));
    for (Eigen::Index i = 0; i < m; ++i) {
        rows.startVec(3 * i);
        for (SpMat::InnerIterator it(qp.J, i); it; ++it) rows.insertBack(3 * i, it.col()) = it.value();
        for (int k = 0; k < 2; ++k) {
            rows.startVec(3 * i + 1 + k);
            if (f)
                for (SpMat::InnerIterator it(f->T, 2 * i + k); it; ++it)
                    rows.insertBack(3 * i + 1 + k, it.col()) = it.value();
        }
    }
    rows.finalize();
    if (c_all) {
        *c_all = Vec::Zero(3 * m);
        for (Eigen::Index i = 0; i < m; ++i) {
            (*c_all)[3 * i] = qp.c[i];
            if (f && f->cT.size() == 2 * m) (*c_all).segment<2>(3 * i + 1) = f->cT.segment<2>(2 * i);
        }
    }
    return rows;
}

double friction_local_q_norm(const QpView& qp)
{
    if (!has_friction(qp)) return std::numeric_limits<double>::quiet_NaN();
    const Eigen::SimplicialLDLT<SpMatCol> ldlt{SpMatCol(qp.A)};
    if (ldlt.info() != Eigen::Success) return std::numeric_limits<double>::quiet_NaN();
    const Vec x_free = ldlt.solve(qp.b);  // where the bodies go without contact forces
    Vec c_all;
    const SpMat rows = contact_frame_rows(qp, &c_all);
    return (rows * x_free - c_all).norm();
}

double friction_natural_map_norm(const QpView& qp, const Vec& x, const Vec& lambda, const Vec& lambda_t)
{
    const Eigen::Index m = qp.m();
    if (!has_friction(qp) || x.size() != qp.n()) return std::numeric_limits<double>::quiet_NaN();
    const Friction& f = *qp.friction;
    const Vec un = qp.J * x - qp.c;
    Vec ut = f.T * x;
    if (f.cT.size() == 2 * m) ut -= f.cT;
    double sum = 0.0;
    for (Eigen::Index i = 0; i < m; ++i) {
        const double r[3] = {lambda.size() == m ? lambda[i] : 0.0, lambda_t.size() == 2 * m ? lambda_t[2 * i] : 0.0,
                             lambda_t.size() == 2 * m ? lambda_t[2 * i + 1] : 0.0};
        const double u[3] = {un[i], ut[2 * i], ut[2 * i + 1]};
        const double mu = f.mu[i];
        double z[3] = {r[0] - (u[0] + mu * std::hypot(u[1], u[2])), r[1] - u[1], r[2] - u[2]};
        project_on_coulomb_cone(z, mu);
        for (int k = 0; k < 3; ++k) sum += (r[k] - z[k]) * (r[k] - z[k]);
    }
    return std::sqrt(sum);
}

double friction_snapshot_error(const QpView& qp, const Vec& x, const Vec& lambda, const Vec& lambda_t, double norm_q)
{
    const double natural = friction_natural_map_norm(qp, x, lambda, lambda_t);
    return norm_q > DBL_EPSILON ? natural / norm_q : natural;
}

}  // namespace cb
