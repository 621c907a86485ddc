#include "sim/integrator.hpp"

namespace cb::sim {

Vec gravity_force(const CorotatedFem& fem, const Vec3& gravity)
{
    Vec f(3 * fem.vertices());
    for (long i = 0; i < fem.vertices(); ++i) f.segment<3>(3 * i) = fem.vertex_mass()[i] * gravity;
    return f;
}

double kinetic_energy(const CorotatedFem& fem, const Vec& v)
{
    double e = 0;
    for (long i = 0; i < fem.vertices(); ++i) e += 0.5 * fem.vertex_mass()[i] * v.segment<3>(3 * i).squaredNorm();
    return e;
}

void assemble_newton_qp(CorotatedFem& fem, const StepParameters& p, const Vec& x_n, const Vec& v_n, const Vec& x_k,
                        SpMat& A, Vec& b)
{
    const double h = p.h;
    fem.update(x_k);
    fem.assemble(1.0 + h * p.a_M, h * h + h * p.a_K, A);
    const Vec f_ext = gravity_force(fem, p.gravity);
    Vec mass3(3 * fem.vertices());
    for (long i = 0; i < fem.vertices(); ++i) mass3.segment<3>(3 * i).setConstant(fem.vertex_mass()[i]);
    // grad G(x_k) = M (x_k - x_n - h v_n) + h^2 (grad E - f_ext) + h C (x_k - x_n).
    const Vec d = x_k - x_n;
    Vec grad = mass3.cwiseProduct(d - h * v_n) + h * h * (fem.gradient() - f_ext);
    if (d.squaredNorm() > 0) {
        grad += h * p.a_M * mass3.cwiseProduct(d);
        if (p.a_K != 0) {
            SpMat K;
            fem.assemble(0.0, 1.0, K);
            grad += h * p.a_K * (K * d);
        }
    }
    b = A * x_k - grad;
}

}  // namespace cb::sim
