#pragma once
/// Siconos numerics' frictional solvers as registry peers on a snapshot (solvers/core/qp.hpp, Friction), each in a
/// forked child process (solvers/peers/siconos_fc3d.*, siconos_gfc3d.*), judged by the harness's frictional e
/// (solvers/friction/friction_snapshot_solve.hpp: Siconos' tolerance tightened while e is not met):
///   `siconos-fc3d-nsgs`  fc3d NSGS on the local problem W = H A^-1 H', q (solvers/friction/friction_dual.hpp), x
///   recovered `siconos-fc3d-nsn`   fc3d NSN_AC (non-smooth Newton on Alart-Curnier's function), the same local problem
///   `siconos-gfc3d-nsn`  gfc3d NSN_AC on the global problem itself: M = A, H = J_all' (contact i's columns
///                        J_i', T_2i', T_2i+1'), f = b, w = -c_all (FCLIB's signs, as `convert` writes them), x = v;
///                        a contact with mu = 0 gets zero tangent columns (as `siconos-nsn`)
/// The native residual: FCLIB's relative error of the local problem (fc3d), Siconos' global error (gfc3d,
/// solvers/measure/friction_error.hpp global_relative_error). tol is passed to Siconos as its own tolerance;
/// max_iterations as its iteration cap. A snapshot without friction fields runs at mu = 0.
#include "solvers/core/registry.hpp"
#include "solvers/core/solver.hpp"

#include <string>

namespace cb {

struct SiconosFrictionSettings {
    CommonSettings common;
    long max_contacts = 700;  ///< fc3d: refuse (not_applicable) more contacts (W is dense 3m x 3m)
};

class SiconosFrictionSolver : public Solver {
public:
    /// kind "fc3d" or "gfc3d"; method one of siconos_fc3d_methods() / siconos_gfc3d_methods().
    SiconosFrictionSolver(std::string kind, std::string method, SiconosFrictionSettings settings);
    std::string name() const override { return "siconos-" + m_kind + "-" + m_method; }
    nlohmann::json settings() const override;
    bool handles_friction() const override { return true; }
    SolverResult solve(const QpView& qp, const SolveContext& context) override;

private:
    std::string m_kind, m_method;
    SiconosFrictionSettings m_settings;
};

/// The entry of "siconos-<kind>-<method>".
SolverEntry siconos_friction_entry(const std::string& kind, const std::string& method);

}  // namespace cb
