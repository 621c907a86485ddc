// `nsgs-friction` (see nsgs_friction.hpp).
#include "solvers/friction/nsgs_friction.hpp"

#include "solvers/core/solve_loop.hpp"
#include "solvers/friction/friction_nsgs.hpp"
#include "solvers/linalg/a_product.hpp"
#include "solvers/linalg/delassus.hpp"
#include "solvers/measure/friction_error.hpp"
#include "solvers/measure/friction_snapshot_error.hpp"
#include "solvers/measure/work_units.hpp"

#include <algorithm>
#include <climits>
#include <cmath>
#include <limits>
#include <memory>
#include <sstream>
#include <vector>

namespace cb {

namespace {

/// Every setting of `nsgs-friction`, declared once (settings.hpp SettingsTable).
const SettingsTable<NsgsFrictionSettings>& nsgs_friction_settings_table()
{
    static const SettingsTable<NsgsFrictionSettings> table =
        SettingsTable<NsgsFrictionSettings>()
            .integer("max_contacts", &NsgsFrictionSettings::max_contacts, 0, LONG_MAX,
                     "refuse (not_applicable) problems with more contacts (W is dense 3m x 3m)")
            .integer("block", &NsgsFrictionSettings::block, 1, 4096,
                     "right-hand sides per CHOLMOD solve when forming W")
            .integer("local_iterations", &NsgsFrictionSettings::local_iterations, 0, LONG_MAX,
                     "projected steps per contact and sweep after the closed forms");
    return table;
}

/// Y = A^-1 J_all' is kept (x = x_u + Y r without a solve) when it fits in this many doubles.
constexpr double MAX_STORED_ENTRIES = 16e6;

}  // namespace

NsgsFrictionSettings NsgsFrictionSettings::from_json(const nlohmann::json& settings)
{
    return read_settings(settings, "nsgs-friction", nsgs_friction_settings_table());
}

nlohmann::json NsgsFrictionSettings::to_json() const { return write_settings(*this, nsgs_friction_settings_table()); }

SolverResult NsgsFrictionSolver::solve(const QpView& qp, const SolveContext& context)
{
    const NsgsFrictionSettings& s = m_settings;
    const Eigen::Index n = qp.n(), m = qp.m();
    SolverResult result;
    Counters& counters = result.counters;
    result.x = qp.x0;
    result.lambda = Vec::Zero(m);
    result.lambda_t = Vec::Zero(2 * m);
    result.info["native_residual_definition"] =
        "FCLIB's relative natural-map error ||F_nat(r)|| / ||q|| of the local problem (W, q, mu)";

    SolveLoop loop("nsgs-friction", qp, s.common, context);
    if (m > s.max_contacts) {
        return loop.finish(result, SolveStatus::NOT_APPLICABLE,
                           "nsgs-friction: m = " + std::to_string(m) +
                               " contacts exceeds max_contacts = " + std::to_string(s.max_contacts) +
                               " (W = J_all A^-1 J_all' is a dense 3m x 3m matrix formed with 3m CHOLMOD solves); "
                               "raise the max_contacts setting to allow it");
    }
    const bool has_friction = qp.friction && qp.friction->mu.size() == m && qp.friction->T.rows() == 2 * m;

    // Contacts with a zero normal row exert nothing: left out (r_i = 0); c_i > 0 there cannot hold.
    std::vector<Eigen::Index> live;
    for (Eigen::Index i = 0; i < m; ++i) {
        bool zero = true;
        for (SpMat::InnerIterator it(qp.J, i); it; ++it) zero = zero && it.value() == 0.0;
        if (!zero) {
            live.push_back(i);
        } else if (qp.c[i] > 0.0) {
            std::ostringstream msg;
            msg << "nsgs-friction: row " << i << " of J is zero but c_" << i << " = " << qp.c[i]
                << " > 0: the constraint 0 >= c_i cannot hold";
            return loop.finish(result, SolveStatus::INFEASIBLE, msg.str());
        }
    }
    const auto k = static_cast<Eigen::Index>(live.size());
    result.info["zero_rows"] = static_cast<long>(m - k);
    Vec c_all_full;
    const SpMat rows_full = contact_frame_rows(qp, &c_all_full);
    // The live contacts' rows, three each.
    SpMat rows(3 * k, n);
    Vec c_all(3 * k), mu = Vec::Zero(k);
    {
        std::vector<Triplet> t;
        for (Eigen::Index j = 0; j < k; ++j) {
            const Eigen::Index i = live[static_cast<size_t>(j)];
            for (int a = 0; a < 3; ++a) {
                for (SpMat::InnerIterator it(rows_full, 3 * i + a); it; ++it)
                    t.emplace_back(static_cast<int>(3 * j + a), static_cast<int>(it.col()), it.value());
                c_all[3 * j + a] = c_all_full[3 * i + a];
            }
            if (has_friction) mu[j] = qp.friction->mu[i];
        }
        rows.setFromTriplets(t.begin(), t.end());
    }

    Delassus delassus;
    if (!delassus.factor(SpMatCol(qp.A), counters))
        return loop.finish(result, SolveStatus::INVALID_INPUT,
                           "nsgs-friction: CHOLMOD could not factor A (not positive definite to working precision)");
    const Vec x_u = delassus.solve(qp.b, counters);
    const Vec q = rows * x_u - c_all;
    if (!x_u.allFinite() || !q.allFinite()) return loop.finish(result, loop.check(counters.iterations, false, false));

    // W = J_all A^-1 J_all', with Y = A^-1 J_all' kept when it fits.
    const Eigen::Index k3 = 3 * k;
    const bool keep_y = static_cast<double>(n) * static_cast<double>(k3) <= MAX_STORED_ENTRIES;
    Eigen::MatrixXd Y, W;
    if (!delassus.form_dense(rows, W, counters, {s.block, keep_y ? &Y : nullptr, [&] { return loop.time_up(); }}))
        return loop.finish(result, SolveStatus::TIME_LIMIT, "while forming W = J_all A^-1 J_all'");
    FrictionLocal local;
    local.W = W.sparseView();
    local.q = q;
    local.mu = mu;
    local.name = "nsgs-friction";
    std::unique_ptr<FrictionSweeps> sweeps;
    try {
        sweeps = std::make_unique<FrictionSweeps>(local.W, mu, "nsgs-friction");
    } catch (const InputError& e) {
        return loop.finish(result, SolveStatus::INVALID_INPUT, e.what());
    }
    result.info["y_stored"] = keep_y;
    loop.setup_phase("local_problem");
    AOperator a_op(qp);
    a_op.prepare(AFormat::CSR, static_cast<int>(s.common.threads));
    loop.setup_phase("a_prepare");
    const AccuracyScale scale = accuracy_scale(qp);  // in the setup, as in every solver
    counters.a_products += scale.a_products;
    loop.setup_phase("measure_scale");
    if (!loop.end_setup()) return loop.finish(result, SolveStatus::TIME_LIMIT);

    Vec r = Vec::Zero(k3);
    if (context.lambda0 && context.lambda0->size() == m)
        for (Eigen::Index j = 0; j < k; ++j) r[3 * j] = std::max(0.0, (*context.lambda0)[live[static_cast<size_t>(j)]]);
    Vec x = x_u, lambda = Vec::Zero(m), lambda_t = Vec::Zero(2 * m);
    auto unpack = [&]() {
        for (Eigen::Index j = 0; j < k; ++j) {
            const Eigen::Index i = live[static_cast<size_t>(j)];
            lambda[i] = r[3 * j];
            lambda_t[2 * i] = r[3 * j + 1];
            lambda_t[2 * i + 1] = r[3 * j + 2];
        }
    };
    auto primal_point = [&](bool exact) {
        unpack();
        if (k == 0) {
            x = x_u;
        } else if (keep_y && !exact) {
            x = x_u + Y * r;
        } else {
            x = delassus.solve(Vec(qp.b + rows.transpose() * r), counters);
        }
    };
    double native = fclib_relative_error(local, r);
    auto finish = [&](SolveStatus status) {
        primal_point(true);
        result.x = x;
        result.lambda = lambda;
        result.lambda_t = lambda_t;
        result.native_residual = native;
        std::ostringstream detail;
        detail << "FCLIB relative error " << native << " after " << counters.iterations << " sweeps";
        return loop.finish(result, status, detail.str());
    };
    auto monitor = [&](long iteration, StepKind step) {
        IterationInfo info{iteration, step, &x, &lambda, native, -1, &counters, 0.0};
        info.lambda_t = &lambda_t;
        return loop.notify(info, [&] { primal_point(false); });
    };
    auto accuracy_error = [&]() -> double {
        primal_point(true);
        const Vec g = a_product(a_op, x) - qp.b;
        ++counters.a_products;
        return accuracy_from_gradient(qp, scale, x, g, lambda, &lambda_t).max();
    };

    const double norm_q = q.norm();
    SolveStatus status = monitor(0, StepKind::START) ? SolveStatus::NOT_RUN : SolveStatus::STOPPED_BY_MONITOR;
    while (status == SolveStatus::NOT_RUN) {
        status = loop.check(counters.iterations, r.allFinite() && std::isfinite(native), native, accuracy_error);
        if (status != SolveStatus::NOT_RUN) break;
        // Each contact's one-contact problem to a fraction of the current error (friction_nsgs's rule).
        const double target =
            std::pow(1e-3 * native * (norm_q > 0.0 ? norm_q : 1.0), 2) / double(std::max<Eigen::Index>(k, 1));
        sweeps->sweep(local.W, q, r, target, s.local_iterations);
        ++counters.iterations;
        ++counters.pgs_sweeps;
        counters.work_flops += dense_matvec_flops(static_cast<double>(k3), static_cast<double>(k3));
        native = fclib_relative_error(local, r);
        if (!monitor(counters.iterations, StepKind::PGS_SWEEP)) status = SolveStatus::STOPPED_BY_MONITOR;
    }
    return finish(status);
}

SolverEntry nsgs_friction_entry()
{
    return solver_entry<NsgsFrictionSolver>(
        "nsgs-friction", nsgs_friction_settings_table(),
        "non-smooth Gauss-Seidel on the exact frictional dual W = J_all A^-1 J_all' (Coulomb cones; CHOLMOD; small m)",
        "any J with at most max_contacts rows; Coulomb friction (mu, tangent rows) when the snapshot has it");
}

}  // namespace cb
