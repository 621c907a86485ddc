// mprgp-tresca-fp and mprgp+ica-friction as registry entries (see mprgp_tresca_entries.hpp).
#include "solvers/friction/mprgp_tresca_entries.hpp"

#include "solvers/friction/friction_dual.hpp"
#include "solvers/friction/friction_snapshot_solve.hpp"
#include "solvers/friction/mprgp_tresca.hpp"

#include <climits>
#include <memory>

namespace cb {

namespace {

const char* const FCLIB_NATIVE =
    "FCLIB's relative natural-map error ||F_nat(r)|| / ||q|| of the local problem (W, q, mu)";
const char* const APPLIES_TO = "any J with at most max_contacts rows; Coulomb friction (mu, tangent rows) when the "
                               "snapshot has it, else mu = 0";

/// Every setting of the `mprgp-tresca-fp` entry, declared once.
const SettingsTable<MprgpTrescaFpEntrySettings>& mprgp_tresca_fp_settings_table()
{
    using S = MprgpTrescaFpEntrySettings;
    static const SettingsTable<S> table =
        SettingsTable<S>()
            .integer("max_contacts", &S::max_contacts, 0, LONG_MAX,
                     "refuse (not_applicable) problems with more contacts (W is dense 3m x 3m)")
            .integer("max_outer", &S::max_outer, 1, LONG_MAX, "Tresca solves (outer fixed-point iterations)")
            .number("inner_fraction", &S::inner_fraction, 0.0, 1.0,
                    "a Tresca solve stops at ||phi + beta|| <= max(inner_fraction tol, inner_relative e_k) ||q||")
            .number("inner_relative", &S::inner_relative, -1e-300, 1.0,
                    "see inner_fraction (e_k: the FCLIB error at the outer iterate; 0: inner_fraction tol alone)")
            .number("gamma", &S::gamma, 0.0, 1e300, "proportioning constant Gamma")
            .boolean("lag_skew", &S::lag_skew,
                     "W not symmetric: its skew part at the outer iterate moved into q (else dropped)");
    return table;
}

/// Every setting of the `mprgp+ica-friction` entry, declared once.
const SettingsTable<MprgpIcaFrictionEntrySettings>& mprgp_ica_friction_settings_table()
{
    using S = MprgpIcaFrictionEntrySettings;
    static const SettingsTable<S> table =
        SettingsTable<S>()
            .integer("max_contacts", &S::max_contacts, 0, LONG_MAX,
                     "refuse (not_applicable) problems with more contacts (W is dense 3m x 3m)")
            .number("normal_tol", &S::normal_tol, 0.0, 1.0,
                    "mprgp-box's native tolerance on (W_NN, q_N), relative to ||q_N||");
    return table;
}

/// Stops mprgp-tresca-fp once its MPRGP iterations, summed over the Tresca solves, reach the cap
/// (MprgpTrescaSettings caps each solve only).
class IterationCap : public Monitor {
public:
    explicit IterationCap(long cap) : m_cap(cap) {}
    bool on_iteration(const IterationInfo& info) override
    {
        if (info.step != StepKind::START) ++m_done;
        m_reached = m_done >= m_cap;
        return !m_reached;
    }
    bool wants_iterate() const override { return false; }
    bool reached() const { return m_reached; }

private:
    long m_cap, m_done = 0;
    bool m_reached = false;
};

/// The local problem of `framed` (FrictionDual) and a method on it returning r; x is recovered from r.
template <class Method>
SnapshotFrictionMethod local_method(const QpView& framed, const std::string& name, Method method)
{
    auto dual = std::make_shared<FrictionDual>(framed, name);
    auto local = std::make_shared<const FrictionLocal>(pin_frictionless_tangents(dual->local()));
    SnapshotFrictionMethod out;
    out.run = [dual, local, method](double tol, long max_iterations, double time_limit_s) {
        SnapshotFrictionRun one;
        one.run = method(*local, tol, max_iterations, time_limit_s);
        if (one.run.r.allFinite()) one.x = dual->primal(one.run.r);
        return one;
    };
    out.counters = [dual]() { return dual->counters(); };
    return out;
}

}  // namespace

MprgpTrescaFpEntrySettings MprgpTrescaFpEntrySettings::from_json(const nlohmann::json& settings)
{
    return read_settings(settings, "mprgp-tresca-fp", mprgp_tresca_fp_settings_table());
}

nlohmann::json MprgpTrescaFpEntrySettings::to_json() const
{
    return write_settings(*this, mprgp_tresca_fp_settings_table());
}

MprgpIcaFrictionEntrySettings MprgpIcaFrictionEntrySettings::from_json(const nlohmann::json& settings)
{
    return read_settings(settings, "mprgp+ica-friction", mprgp_ica_friction_settings_table());
}

nlohmann::json MprgpIcaFrictionEntrySettings::to_json() const
{
    return write_settings(*this, mprgp_ica_friction_settings_table());
}

/// Both entries: the snapshot's local form (FrictionDual), the method on it, x recovered.
template <class Method>
SolverResult solve_on_local_form(const std::string& name, const QpView& qp, const CommonSettings& common,
                                 long max_contacts, const SolveContext& context, Method method)
{
    SnapshotFrictionOptions options;
    options.max_contacts = max_contacts;
    options.native_definition = FCLIB_NATIVE;
    return solve_frictional_snapshot(name, qp, common, context, options,
                                     [&](const QpView& framed) { return local_method(framed, name, method); });
}

SolverResult MprgpTrescaFpSolver::solve(const QpView& qp, const SolveContext& context)
{
    const MprgpTrescaFpEntrySettings s = m_settings;
    return solve_on_local_form(name(), qp, s.common, s.max_contacts, context,
                               [s](const FrictionLocal& local, double tol, long max_iterations, double time_limit_s) {
                                   MprgpTrescaSettings t;
                                   t.tol = tol;
                                   t.max_outer = s.max_outer;
                                   t.max_inner = max_iterations;
                                   t.inner_fraction = s.inner_fraction;
                                   t.inner_relative = s.inner_relative;
                                   t.time_limit_s = time_limit_s;
                                   t.gamma = s.gamma;
                                   t.lag_skew = s.lag_skew;
                                   IterationCap cap(max_iterations);
                                   t.monitor = &cap;
                                   FrictionRun run = mprgp_tresca_fp(local, t).run;
                                   if (run.status == "stopped_by_monitor" && cap.reached())
                                       run.status = "max_iterations";
                                   return run;
                               });
}

SolverResult MprgpIcaFrictionSolver::solve(const QpView& qp, const SolveContext& context)
{
    const MprgpIcaFrictionEntrySettings s = m_settings;
    return solve_on_local_form(name(), qp, s.common, s.max_contacts, context,
                               [s](const FrictionLocal& local, double tol, long max_iterations, double time_limit_s) {
                                   MprgpIcaFrictionSettings t;
                                   t.tol = tol;
                                   t.normal_tol = s.normal_tol;
                                   t.max_mprgp = max_iterations;
                                   t.max_sweeps = max_iterations;
                                   t.time_limit_s = time_limit_s;
                                   return mprgp_ica_friction(local, t);
                               });
}

SolverEntry mprgp_tresca_fp_entry()
{
    return solver_entry<MprgpTrescaFpSolver>(
        "mprgp-tresca-fp", mprgp_tresca_fp_settings_table(),
        "Coulomb friction as a fixed point on Tresca slip bounds, each Tresca QP by MPGP (MPRGP over discs), on the "
        "exact local problem W = H A^-1 H' (CHOLMOD; small m)",
        APPLIES_TO);
}

SolverEntry mprgp_ica_friction_entry()
{
    return solver_entry<MprgpIcaFrictionSolver>(
        "mprgp+ica-friction", mprgp_ica_friction_settings_table(),
        "baseline (OTSG09): frictionless mprgp-box on W_NN, then nsgs from its r_n, on the exact local problem "
        "W = H A^-1 H' (CHOLMOD; small m)",
        APPLIES_TO);
}

}  // namespace cb
