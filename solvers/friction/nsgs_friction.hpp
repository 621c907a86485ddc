#pragma once
/// `nsgs-friction`: our non-smooth Gauss-Seidel (solvers/friction/friction_nsgs.hpp) on the exact dual of a
/// frictional snapshot (solvers/core/qp.hpp Friction), the frictional extension of `pgs`.
/// Ref: Jean (1999), "The non-smooth contact dynamics method"; Acary et al. (2018), Sec. 5.
///
/// Dual (FCLIB's local form): u = W r + q with, per contact i, the rows J_i, T_2i, T_2i+1 stacked
/// in J_all (normal first), W = J_all A^-1 J_all' (dense 3m x 3m, 3m CHOLMOD solves), q = J_all A^-1 b
/// - c_all, and Coulomb's law per contact. One iteration = one FrictionSweeps sweep; the primal point
/// is x = A^-1 (b + J_all' r) (exact stationarity up to the solve's error), the multipliers lambda =
/// the r_n and lambda_t = the r_T. Stop rule: stop=kkt (default) the frictional accuracy error e
/// (docs/accuracy.md "e for Coulomb friction") at x; stop=native FCLIB's relative natural-map error of
/// the local problem (the native residual). A contact whose normal row is zero is left out (r_i = 0);
/// one with c_i > 0 makes the problem infeasible. Without friction fields (or mu = 0) every contact
/// takes pgs's closed-form update, so the iterates are pgs's up to the order of the sums.
#include "solvers/core/registry.hpp"
#include "solvers/core/solver.hpp"

namespace cb {

struct NsgsFrictionSettings {
    CommonSettings common;
    long max_contacts = 700;       ///< refuse (not_applicable) more contacts (W is dense 3m x 3m)
    long block = 64;               ///< right-hand sides per CHOLMOD solve when forming W
    long local_iterations = 1000;  ///< projected steps per contact and sweep after the closed forms

    static NsgsFrictionSettings from_json(const nlohmann::json& settings);  ///< throws InputError
    nlohmann::json to_json() const;
};

class NsgsFrictionSolver : public Solver {
public:
    explicit NsgsFrictionSolver(NsgsFrictionSettings settings) : m_settings(settings) {}
    std::string name() const override { return "nsgs-friction"; }
    nlohmann::json settings() const override { return m_settings.to_json(); }
    bool handles_friction() const override { return true; }
    SolverResult solve(const QpView& qp, const SolveContext& context) override;

private:
    NsgsFrictionSettings m_settings;
};

SolverEntry nsgs_friction_entry();

}  // namespace cb
