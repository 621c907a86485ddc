// Siconos' fc3d/gfc3d solvers as registry peers on a frictional snapshot (see siconos_friction.hpp).
#include "solvers/peers/siconos_friction.hpp"

#include "solvers/core/friction_global.hpp"
#include "solvers/friction/friction_dual.hpp"
#include "solvers/friction/friction_snapshot_solve.hpp"
#include "solvers/measure/friction_snapshot_error.hpp"
#include "solvers/peers/siconos_fc3d.hpp"
#include "solvers/peers/siconos_gfc3d.hpp"

#include <algorithm>
#include <climits>
#include <memory>

namespace cb {

namespace {

/// fc3d's settings, declared once (gfc3d has none of its own: it never forms W).
const SettingsTable<SiconosFrictionSettings>& fc3d_settings_table()
{
    using S = SiconosFrictionSettings;
    static const SettingsTable<S> table = SettingsTable<S>().integer(
        "max_contacts", &S::max_contacts, 0, LONG_MAX,
        "refuse (not_applicable) problems with more contacts (W = H A^-1 H' is dense 3m x 3m)");
    return table;
}

const SettingsTable<SiconosFrictionSettings>& gfc3d_settings_table()
{
    static const SettingsTable<SiconosFrictionSettings> table;
    return table;
}

const SettingsTable<SiconosFrictionSettings>& table_of(const std::string& kind)
{
    return kind == "fc3d" ? fc3d_settings_table() : gfc3d_settings_table();
}

SnapshotFrictionMethod fc3d_method(const QpView& framed, const std::string& name, const std::string& method)
{
    auto dual = std::make_shared<FrictionDual>(framed, name);
    auto local = std::make_shared<const FrictionLocal>(pin_frictionless_tangents(dual->local()));
    SnapshotFrictionMethod out;
    out.run = [dual, local, method](double tol, long max_iterations, double time_limit_s) {
        SnapshotFrictionRun one;
        one.run = siconos_fc3d_solve(*local, method, max_iterations, tol, time_limit_s);
        // NSN_AC's loop test post-increments: at the cap it reports one more step than it took (siconos_nsn.cpp).
        one.run.iterations = std::min(one.run.iterations, max_iterations);
        if (one.run.r.allFinite()) one.x = dual->primal(one.run.r);
        return one;
    };
    out.counters = [dual]() { return dual->counters(); };
    return out;
}

/// FCLIB's global problem of the snapshot: M v = H r + f, u = H'v + w with M = A, H = J_all', f = b,
/// w = -c_all (then v = x, u = J_all x - c_all).
SnapshotFrictionMethod gfc3d_method(const QpView& framed, const std::string& name, const std::string& method)
{
    auto global = std::make_shared<FrictionGlobal>();
    Vec c_all;
    SpMat rows = contact_frame_rows(framed, &c_all);
    // A contact with mu = 0 carries no tangential force whatever its tangent rows. Siconos' Newton takes
    // them out (zero columns of H, as siconos-nsn passes them): with them its Newton matrix can be
    // singular (gfc3d_driver info 1 on plane_2x2x2 with unit tangent rows independent of each normal).
    const Vec& mu = framed.friction->mu;
    for (Eigen::Index row = 0; row < rows.outerSize(); ++row)
        if (row % 3 != 0 && mu[row / 3] == 0.0) {
            for (SpMat::InnerIterator it(rows, row); it; ++it) it.valueRef() = 0.0;
            c_all[row] = 0.0;
        }
    rows.prune(0.0);
    global->M = framed.A;
    global->H = SpMat(rows.transpose());
    global->f = framed.b;
    global->w = -c_all;
    global->mu = framed.friction->mu;
    global->name = name;
    SnapshotFrictionMethod out;
    out.run = [global, method](double tol, long max_iterations, double time_limit_s) {
        FrictionGlobalRun run = siconos_gfc3d_solve(*global, method, max_iterations, tol, time_limit_s);
        // NSN_AC's loop test post-increments: at the cap it reports one more step than it took (siconos_nsn.cpp).
        run.run.iterations = std::min(run.run.iterations, max_iterations);
        return SnapshotFrictionRun{run.run, run.v};
    };
    out.counters = []() { return Counters{}; };
    return out;
}

}  // namespace

SiconosFrictionSolver::SiconosFrictionSolver(std::string kind, std::string method, SiconosFrictionSettings settings)
    : m_kind(std::move(kind)), m_method(std::move(method)), m_settings(settings)
{
}

nlohmann::json SiconosFrictionSolver::settings() const { return write_settings(m_settings, table_of(m_kind)); }

SolverResult SiconosFrictionSolver::solve(const QpView& qp, const SolveContext& context)
{
    SnapshotFrictionOptions options;
    const bool local = m_kind == "fc3d";
    options.max_contacts = local ? m_settings.max_contacts : LONG_MAX;
    options.native_definition =
        local ? "FCLIB's relative natural-map error ||F_nat(r)|| / ||q|| of the local problem (W, q, mu)"
              : "Siconos' global error (gfc3d_compute_error: equilibrium plus natural map, each relative)";
    const std::string solver = name(), method = m_method;
    SolverResult result =
        solve_frictional_snapshot(solver, qp, m_settings.common, context, options, [&](const QpView& framed) {
            return local ? fc3d_method(framed, solver, method) : gfc3d_method(framed, solver, method);
        });
    result.info["library"] = std::string("Siconos numerics ") + CB_SICONOS_VERSION;
    result.info["child_process"] = true;
    result.info["history"] = "start and final point only (Siconos' drivers have no iteration callback)";
    return result;
}

SolverEntry siconos_friction_entry(const std::string& kind, const std::string& method)
{
    const std::string name = "siconos-" + kind + "-" + method;
    const SettingsTable<SiconosFrictionSettings>& table = table_of(kind);
    SolverEntry entry;
    entry.make = [name, kind, method, &table](const nlohmann::json& settings) -> std::unique_ptr<Solver> {
        return std::make_unique<SiconosFrictionSolver>(kind, method, read_settings(settings, name, table));
    };
    const std::string what = method == "nsgs"   ? "NSGS"
                             : method == "nsn"  ? "NSN_AC (non-smooth Newton)"
                             : method == "prox" ? "PROX_WR (proximal point on its reduced problem)"
                                                : method;
    entry.description = std::string("peer: Siconos numerics ") + CB_SICONOS_VERSION + " " + kind + " " + what +
                        (kind == "fc3d" ? " on the local problem W = H A^-1 H' (CHOLMOD; small m)"
                                        : " on the global problem M = A, H = [J; T]'") +
                        ", Coulomb friction (child process)";
    entry.settings = table.docs();
    entry.applies_to = kind == "fc3d" ? "any J with at most max_contacts rows; Coulomb friction when the snapshot "
                                        "has it, else mu = 0"
                                      : "any J; Coulomb friction when the snapshot has it, else mu = 0";
    entry.library = std::string("Siconos numerics ") + CB_SICONOS_VERSION;
    return entry;
}

}  // namespace cb
