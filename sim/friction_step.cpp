// The frictional time step: the contacts' local problem, NSGS, and the recovery of x (see friction_step.hpp).
#include "sim/friction_step.hpp"

#include "solvers/core/stopwatch.hpp"
#include "solvers/friction/friction_nsgs.hpp"
#include "solvers/linalg/delassus.hpp"
#include "solvers/measure/friction_error.hpp"
#include "solvers/peers/siconos_fc3d.hpp"

#include <cmath>
#include <stdexcept>

namespace cb::sim {

void tangent_frame(const Vec3& n, Vec3& t1, Vec3& t2)
{
    int axis = 0;
    for (int k = 1; k < 3; ++k)
        if (std::abs(n[k]) < std::abs(n[axis])) axis = k;
    t1 = n.cross(Vec3::Unit(axis)).normalized();
    t2 = n.cross(t1);
}

SpMat frictional_rows(const std::vector<ContactRow>& rows, Eigen::Index n_dofs)
{
    std::vector<Triplet> trip;
    trip.reserve(rows.size() * 36);
    for (size_t i = 0; i < rows.size(); ++i) {
        const ContactRow& r = rows[i];
        Vec3 t1, t2;
        tangent_frame(r.normal, t1, t2);
        const Vec3* dir[3] = {&r.normal, &t1, &t2};
        for (int a = 0; a < 3; ++a)
            for (int k = 0; k < 4; ++k) {
                if (r.vertex[k] < 0) continue;
                for (int d = 0; d < 3; ++d)
                    trip.emplace_back(static_cast<int>(3 * i + a), 3 * r.vertex[k] + d, r.weight[k] * (*dir[a])[d]);
            }
    }
    SpMat J(static_cast<Eigen::Index>(3 * rows.size()), n_dofs);
    J.setFromTriplets(trip.begin(), trip.end());
    return J;
}

SpMat tangent_rows(const std::vector<ContactRow>& rows, Eigen::Index n_dofs)
{
    const SpMat all = frictional_rows(rows, n_dofs);
    std::vector<Triplet> trip;
    trip.reserve(static_cast<size_t>(all.nonZeros()));
    for (Eigen::Index row = 0; row < all.rows(); ++row)
        if (row % 3 != 0)
            for (SpMat::InnerIterator it(all, row); it; ++it)
                trip.emplace_back(static_cast<int>(2 * (row / 3) + row % 3 - 1), static_cast<int>(it.col()),
                                  it.value());
    SpMat T(2 * static_cast<Eigen::Index>(rows.size()), n_dofs);
    T.setFromTriplets(trip.begin(), trip.end());
    return T;
}

FrictionalStepProblem frictional_step_problem(const SpMat& A, const Vec& b, const std::vector<ContactRow>& rows,
                                              const Vec& x_start, double mu, const std::string& name)
{
    Delassus delassus;
    Counters counters;  // the step reports its time, not its work
    if (!delassus.factor(SpMatCol(A), counters))
        throw std::runtime_error(name + ": CHOLMOD could not factor the step's A (not positive definite to working "
                                        "precision): the frictional step needs A^-1");
    const Eigen::Index m = static_cast<Eigen::Index>(rows.size());
    const SpMat J = frictional_rows(rows, A.cols());
    FrictionalStepProblem p;
    p.x_free = delassus.solve(b, counters);
    Eigen::MatrixXd W;
    DelassusForming forming;
    forming.columns = &p.Y;
    delassus.form_dense(J, W, counters, forming);
    // The target of each row: c_i for the normal (the gap), the tangent at x_start for the tangents (the slip).
    Vec c_all = J * x_start;
    for (Eigen::Index i = 0; i < m; ++i) c_all[3 * i] = rows[static_cast<size_t>(i)].c;
    p.local.W = W.sparseView(0.0, 0.0);  // every computed entry kept (an exact 0 only is dropped)
    p.local.q = J * p.x_free - c_all;
    p.local.mu = Vec::Constant(m, mu);
    p.local.name = name;
    return p;
}

FrictionalStepOutcome solve_frictional_step(const SpMat& A, const Vec& b, const std::vector<ContactRow>& rows,
                                            const Vec& x_start, const FrictionSettings& settings,
                                            const std::string& name)
{
    Stopwatch watch;
    watch.start();
    FrictionalStepOutcome out;
    const FrictionalStepProblem p = frictional_step_problem(A, b, rows, x_start, settings.mu, name);
    out.contacts = p.local.contacts();
    if (out.contacts == 0) {
        out.x = p.x_free;
        out.run.solver = settings.solver;
        out.run.status = "converged";
    } else {
        if (settings.solver == "nsgs") {
            FrictionNsgsSettings s;
            s.tol = settings.tol;
            s.max_iterations = settings.max_iterations;
            s.time_limit_s = settings.time_limit_s;
            out.run = friction_nsgs(p.local, s);
        } else {  // siconos-nsn, siconos-nsgs (scene.cpp admits no other name)
            out.run = siconos_fc3d_solve(p.local, settings.solver.substr(8), settings.max_iterations, settings.tol,
                                         settings.time_limit_s);
            out.run.solver = settings.solver;
        }
        out.x = p.x_free + p.Y * out.run.r;
        for (Eigen::Index i = 0; i < out.contacts; ++i) {
            const double rn = out.run.r[3 * i], rt = std::hypot(out.run.r[3 * i + 1], out.run.r[3 * i + 2]);
            if (!(rn > 0.0))
                ++out.separated;
            else if (rt < (1.0 - 1e-6) * settings.mu * rn)
                ++out.sticking;
            else
                ++out.sliding;
        }
    }
    watch.pause();
    out.seconds = watch.seconds();
    return out;
}

}  // namespace cb::sim
