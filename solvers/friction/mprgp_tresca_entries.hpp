#pragma once
/// The registry entries of the MPRGP-based frictional solvers (solvers/friction/mprgp_tresca.hpp) on a snapshot:
/// the local problem W = H A^-1 H', q of solvers/friction/friction_dual.hpp, the method on it, then
/// x = A^-1 (b + H'r), lambda = r_n and lambda_t = r_T in the snapshot's row order, judged by
/// solvers/friction/friction_snapshot_solve.hpp (frictional e; own tolerance tightened when e is not met).
///   `mprgp-tresca-fp`     the fixed point on Tresca slip bounds over MPGP; max_iterations caps the MPRGP
///                         iterations of each Tresca solve (max_outer the Tresca solves)
///   `mprgp+ica-friction`  frictionless mprgp-box on (W_NN, q_N), then nsgs from (r_n, 0); max_iterations
///                         caps each stage (mprgp-box iterations, nsgs sweeps)
/// Both stop on FCLIB's relative error of the local problem (the native residual) at the tolerance
/// given; a snapshot without friction fields runs at mu = 0 (friction_snapshot_solve.hpp's frame).
#include "solvers/core/registry.hpp"
#include "solvers/core/solver.hpp"

namespace cb {

struct MprgpTrescaFpEntrySettings {
    CommonSettings common;
    long max_contacts = 700;      ///< refuse (not_applicable) more contacts (W is dense 3m x 3m)
    long max_outer = 200;         ///< Tresca solves
    double inner_fraction = 0.5;  ///< MprgpTrescaSettings::inner_fraction
    double inner_relative = 0.1;  ///< MprgpTrescaSettings::inner_relative
    double gamma = 1.0;           ///< proportioning constant Gamma
    bool lag_skew = true;         ///< W not symmetric: its skew part at the outer iterate in q

    static MprgpTrescaFpEntrySettings from_json(const nlohmann::json& settings);  ///< throws InputError
    nlohmann::json to_json() const;
};

class MprgpTrescaFpSolver : public Solver {
public:
    explicit MprgpTrescaFpSolver(MprgpTrescaFpEntrySettings settings) : m_settings(settings) {}
    std::string name() const override { return "mprgp-tresca-fp"; }
    nlohmann::json settings() const override { return m_settings.to_json(); }
    bool handles_friction() const override { return true; }
    SolverResult solve(const QpView& qp, const SolveContext& context) override;

private:
    MprgpTrescaFpEntrySettings m_settings;
};

struct MprgpIcaFrictionEntrySettings {
    CommonSettings common;
    long max_contacts = 700;    ///< refuse (not_applicable) more contacts (W is dense 3m x 3m)
    double normal_tol = 1e-10;  ///< mprgp-box's native tolerance on (W_NN, q_N), relative to ||q_N||

    static MprgpIcaFrictionEntrySettings from_json(const nlohmann::json& settings);  ///< throws InputError
    nlohmann::json to_json() const;
};

class MprgpIcaFrictionSolver : public Solver {
public:
    explicit MprgpIcaFrictionSolver(MprgpIcaFrictionEntrySettings settings) : m_settings(settings) {}
    std::string name() const override { return "mprgp+ica-friction"; }
    nlohmann::json settings() const override { return m_settings.to_json(); }
    bool handles_friction() const override { return true; }
    SolverResult solve(const QpView& qp, const SolveContext& context) override;

private:
    MprgpIcaFrictionEntrySettings m_settings;
};

SolverEntry mprgp_tresca_fp_entry();
SolverEntry mprgp_ica_friction_entry();

}  // namespace cb
