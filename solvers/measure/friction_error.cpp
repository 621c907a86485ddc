// FCLIB's relative natural-map error of a frictional local problem (see friction_error.hpp).
#include "solvers/measure/friction_error.hpp"

#include <algorithm>
#include <cfloat>
#include <cmath>

namespace cb {

void project_on_coulomb_cone(double* r, double mu)
{
    const double tangent = std::hypot(r[1], r[2]);
    // The polar cone first: with mu = 0 and r_T = 0 the inside test alone would keep r_n < 0.
    if (mu * tangent <= -r[0]) {  // inside the polar cone: projects to the apex
        r[0] = r[1] = r[2] = 0.0;
        return;
    }
    if (tangent <= mu * r[0]) return;  // inside (r_n > 0 then)
    // onto the boundary ray through (1, mu r_T / ||r_T||)
    const double normal = (r[0] + mu * tangent) / (1.0 + mu * mu);
    r[0] = normal;
    r[1] *= mu * normal / tangent;
    r[2] *= mu * normal / tangent;
}

double natural_map_norm_at(const Vec& r, const Vec& u, const Vec& mus)
{
    double sum = 0.0;
    for (Eigen::Index i = 0; i < mus.size(); ++i) {
        const double mu = mus[i];
        const double* ri = r.data() + 3 * i;
        const double* ui = u.data() + 3 * i;
        // De Saxce's modified velocity u + mu ||u_T|| e_n makes the map a plain cone projection.
        double z[3] = {ri[0] - (ui[0] + mu * std::hypot(ui[1], ui[2])), ri[1] - ui[1], ri[2] - ui[2]};
        project_on_coulomb_cone(z, mu);
        for (int k = 0; k < 3; ++k) sum += (ri[k] - z[k]) * (ri[k] - z[k]);
    }
    return std::sqrt(sum);
}

double natural_map_norm(const FrictionLocal& problem, const Vec& r, Vec* u_out)
{
    Vec u = problem.W * r + problem.q;
    const double norm = natural_map_norm_at(r, u, problem.mu);
    if (u_out) *u_out = std::move(u);
    return norm;
}

double fclib_relative_error(const FrictionLocal& problem, const Vec& r, Vec* u)
{
    const double absolute = natural_map_norm(problem, r, u);
    const double norm_q = problem.q.norm();
    return norm_q > DBL_EPSILON ? absolute / norm_q : absolute;
}

double siconos_relative_error(const FrictionLocal& problem, const Vec& r)
{
    Vec u;
    const double absolute = natural_map_norm(problem, r, &u);
    const double scale = std::max({problem.q.norm(), u.norm(), r.norm()});
    return scale > DBL_EPSILON ? absolute / scale : absolute;
}

namespace {

double relative(double absolute, double scale) { return std::abs(scale) > DBL_EPSILON ? absolute / scale : absolute; }

}  // namespace

double global_relative_error(const FrictionGlobal& problem, const Vec& r, const Vec& v, Vec* u_out)
{
    const Vec Hr = problem.H * r, Mv = problem.M * v;
    const double equilibrium =
        relative((problem.f + Hr - Mv).norm(), std::max({problem.f.norm(), Mv.norm(), Hr.norm()}));
    Vec u = problem.H.transpose() * v + problem.w;
    const double complementarity = relative(natural_map_norm_at(r, u, problem.mu), std::max(u.norm(), r.norm()));
    if (u_out) *u_out = std::move(u);
    return equilibrium + complementarity;
}

}  // namespace cb
