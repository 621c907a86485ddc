// Our non-smooth Gauss-Seidel on a frictional local problem (see friction_nsgs.hpp).
#include "solvers/friction/friction_nsgs.hpp"

#include "solvers/core/stopwatch.hpp"
#include "solvers/measure/friction_error.hpp"

#include <Eigen/Dense>
#include <cmath>
#include <vector>

namespace cb {

namespace {

using Mat3 = Eigen::Matrix3d;
using Vec3 = Eigen::Vector3d;

/// ||r - P_K(r - (u + mu ||u_T|| e_n))||^2 of one contact.
double local_residual(const Vec3& r, const Vec3& u, double mu)
{
    double z[3] = {r[0] - (u[0] + mu * std::hypot(u[1], u[2])), r[1] - u[1], r[2] - u[2]};
    project_on_coulomb_cone(z, mu);
    return (r - Vec3(z[0], z[1], z[2])).squaredNorm();
}

/// The sliding state of one contact along the unit tangent t = (cos th, sin th): the reaction on
/// the cone's boundary against t, r = r_n (1, -mu t), with r_n from u_n = 0. Returns false when that
/// r_n is not positive (no closed sliding contact along t). `cross` is u_T x t (0 at a solution).
bool sliding_state(const Mat3& A, const Vec3& b, double mu, double th, Vec3& r, double& cross, double& along)
{
    const Vec3 d(1.0, -mu * std::cos(th), -mu * std::sin(th));
    const double an = A.row(0).dot(d);
    if (!(an > 0.0)) return false;
    const double rn = -b[0] / an;
    if (!(rn > 0.0)) return false;
    r = rn * d;
    const Vec3 u = A * r + b;
    cross = u[1] * std::sin(th) - u[2] * std::cos(th);
    along = u[1] * std::cos(th) + u[2] * std::sin(th);
    return true;
}

/// One contact: u = A r + b, find r in K_mu with Coulomb's law (take-off, stick or slide). Returns
/// its squared residual. Sliding: the direction is found by a scan of 64 angles and bisection on
/// u_T x t = 0 with u_T along t (the one-contact problem is then solved to rounding); when no
/// sliding direction exists, the projected fixed point polishes r.
double solve_contact(const Mat3& A, const Eigen::PartialPivLU<Mat3>& factor, double rho, const Vec3& b, double mu,
                     Vec3& r, double target, long max_steps)
{
    if (b[0] >= 0.0) {  // take-off: r = 0, u = b separates (b_n >= 0 puts u + mu||u_T|| e_n in K*)
        r.setZero();
        return 0.0;
    }
    if (mu == 0.0) {  // the cone is the normal ray: r_T = 0 and u_n = 0, exactly (pgs's update)
        r = Vec3(-b[0] / A(0, 0), 0.0, 0.0);
        return 0.0;
    }
    const Vec3 stick = factor.solve(-b);  // u = 0 (LU: W_ii need not be symmetric; Capsules' is not)
    if (stick[0] >= 0.0 && std::hypot(stick[1], stick[2]) <= mu * stick[0]) {
        r = stick;
        return local_residual(r, A * r + b, mu);
    }
    double best = local_residual(r, A * r + b, mu);
    if (mu > 0.0) {
        constexpr int SAMPLES = 64;
        const double step = 2.0 * M_PI / SAMPLES;
        Vec3 r0, r1;
        double c0 = 0.0, c1 = 0.0, a0 = 0.0, a1 = 0.0;
        bool ok0 = sliding_state(A, b, mu, 0.0, r0, c0, a0);
        for (int k = 1; k <= SAMPLES; ++k) {
            const double lo0 = (k - 1) * step, hi0 = k * step;
            const bool ok1 = sliding_state(A, b, mu, hi0, r1, c1, a1);
            if (ok0 && ok1 && (c0 <= 0.0) != (c1 <= 0.0) && (a0 > 0.0 || a1 > 0.0)) {
                double lo = lo0, hi = hi0, clo = c0;
                Vec3 rm;
                double cm = 0.0, am = 0.0;
                for (int it = 0; it < 60; ++it) {
                    const double mid = 0.5 * (lo + hi);
                    if (!sliding_state(A, b, mu, mid, rm, cm, am)) break;
                    if ((cm <= 0.0) == (clo <= 0.0))
                        lo = mid, clo = cm;
                    else
                        hi = mid;
                }
                if (sliding_state(A, b, mu, 0.5 * (lo + hi), rm, cm, am) && am > 0.0) {
                    const double res = local_residual(rm, A * rm + b, mu);
                    if (res < best) best = res, r = rm;
                }
            }
            r0 = r1, c0 = c1, a0 = a1, ok0 = ok1;
        }
    }
    for (long k = 0; k < max_steps && best > target; ++k) {
        const Vec3 u = A * r + b;
        double z[3] = {r[0] - rho * (u[0] + mu * std::hypot(u[1], u[2])), r[1] - rho * u[1], r[2] - rho * u[2]};
        project_on_coulomb_cone(z, mu);
        r = Vec3(z[0], z[1], z[2]);
        best = local_residual(r, A * r + b, mu);
    }
    return best;
}

}  // namespace

FrictionSweeps::FrictionSweeps(const SpMat& W, const Vec& mu, const std::string& name)
    : m_mu(mu), m_block(size_t(mu.size()), Mat3::Zero()), m_factor(size_t(mu.size())), m_rho(size_t(mu.size()), 0.0)
{
    // The diagonal blocks, their factors and step lengths, once.
    const Eigen::Index m = mu.size();
    for (Eigen::Index row = 0; row < 3 * m; ++row)
        for (SpMat::InnerIterator it(W, row); it; ++it)
            if (it.col() / 3 == row / 3) m_block[size_t(row / 3)](row % 3, it.col() % 3) = it.value();
    for (Eigen::Index i = 0; i < m; ++i) {
        const Mat3& block = m_block[size_t(i)];
        if (mu[i] == 0.0) {  // closed form: only the normal entry is read
            if (!(block(0, 0) > 0.0))
                throw InputError(name + ": W: the normal entry of frictionless contact " + std::to_string(i) + " is " +
                                 std::to_string(block(0, 0)) + ", not positive");
            continue;
        }
        const Mat3 sym = 0.5 * (block + block.transpose());
        const Eigen::SelfAdjointEigenSolver<Mat3> eig(sym, Eigen::EigenvaluesOnly);
        if (!(eig.eigenvalues()[0] > 0.0))
            throw InputError(name + ": W: the diagonal block of contact " + std::to_string(i) +
                             " is not positive definite (smallest eigenvalue of its symmetric part " +
                             std::to_string(eig.eigenvalues()[0]) +
                             "): nsgs needs each one-contact problem to have "
                             "a unique solution");
        m_factor[size_t(i)].compute(block);
        m_rho[size_t(i)] = 1.0 / eig.eigenvalues()[2];
    }
}

void FrictionSweeps::sweep(const SpMat& W, const Vec& q, Vec& r, double target, long local_iterations) const
{
    for (Eigen::Index i = 0; i < m_mu.size(); ++i) {
        Vec3 u = Vec3::Zero();
        for (int k = 0; k < 3; ++k)
            for (SpMat::InnerIterator it(W, 3 * i + k); it; ++it) u[k] += it.value() * r[it.col()];
        Vec3 ri = r.segment<3>(3 * i);
        const Vec3 b = u + q.segment<3>(3 * i) - m_block[size_t(i)] * ri;
        solve_contact(m_block[size_t(i)], m_factor[size_t(i)], m_rho[size_t(i)], b, m_mu[i], ri, target,
                      local_iterations);
        r.segment<3>(3 * i) = ri;
    }
}

FrictionRun friction_nsgs(const FrictionLocal& p, const FrictionNsgsSettings& s)
{
    const Eigen::Index m = p.contacts();
    FrictionRun run;
    run.solver = "nsgs";
    run.r = Vec::Zero(3 * m);
    if (s.start) {
        if (s.start->size() != 3 * m || !s.start->allFinite())
            throw InputError(p.name + ": nsgs start: needs " + std::to_string(3 * m) +
                             " finite numbers (3 per contact)");
        run.r = *s.start;
    }
    Stopwatch watch;
    watch.start();
    const FrictionSweeps sweeps(p.W, p.mu, p.name);
    const double norm_q = p.q.norm();
    double error = fclib_relative_error(p, run.r);
    run.status = "max_iterations";
    for (long sweep = 0; sweep < s.max_iterations; ++sweep) {
        if (error <= s.tol) {
            run.status = "converged";
            break;
        }
        if (s.time_limit_s > 0.0 && watch.seconds() > s.time_limit_s) {
            run.status = "time_limit";
            break;
        }
        // Each contact's one-contact problem is solved to a fraction of the current global error.
        const double target = std::pow(1e-3 * error * (norm_q > 0.0 ? norm_q : 1.0), 2) / double(m);
        sweeps.sweep(p.W, p.q, run.r, target, s.local_iterations);
        ++run.iterations;
        error = fclib_relative_error(p, run.r);
        if (!std::isfinite(error)) {
            run.status = "diverged";
            break;
        }
    }
    if (run.status == "max_iterations" && error <= s.tol) run.status = "converged";
    watch.pause();
    run.seconds = watch.seconds();
    run.error = fclib_relative_error(p, run.r, &run.u);
    return run;
}

}  // namespace cb
