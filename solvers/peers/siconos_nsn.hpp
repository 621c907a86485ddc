#pragma once
/// `siconos-nsn`: an external peer, Siconos numerics' global nonsmooth Newton on the Alart-Curnier
/// function (SICONOS_GLOBAL_FRICTION_3D_NSN_AC) on the QP written as a frictionless global
/// contact problem (the FCLIB mapping of problems/fclib_io.hpp, in Siconos's convention
///   M v = q + H r,  u = H'v + b:  M = A, q = b, H's normal columns = J', b = (-c, 0, 0), mu = 0).
/// The tangential columns of H are zero (mu = 0 makes the tangential reactions zero anyway).
/// Runs in a forked child process (Siconos can abort), like siconos-lemke; x = v, lambda = r_N.
#include "solvers/core/registry.hpp"
#include "solvers/core/solver.hpp"

namespace cb {

struct SiconosNsnSettings {
    CommonSettings common;

    static SiconosNsnSettings from_json(const nlohmann::json& settings);  ///< throws InputError
    nlohmann::json to_json() const;
};

class SiconosNsnSolver : public Solver {
public:
    explicit SiconosNsnSolver(SiconosNsnSettings settings) : m_settings(settings) {}
    std::string name() const override { return "siconos-nsn"; }
    nlohmann::json settings() const override { return m_settings.to_json(); }
    SolverResult solve(const QpView& qp, const SolveContext& context) override;

private:
    SiconosNsnSettings m_settings;
};

SolverEntry siconos_nsn_entry();

}  // namespace cb
