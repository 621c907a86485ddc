// `cg`: preconditioned conjugate gradients on A x = b, ignoring J (ALGORITHMS.md §9).
// Ref: Li et al. 2015, Fig. 8 (the PCG baseline); Hestenes-Stiefel CG with a Jacobi preconditioner.
#include "solvers/methods/cg.hpp"

#include "solvers/core/solve_loop.hpp"
#include "solvers/linalg/a_product.hpp"
#include "solvers/linalg/ichol.hpp"
#include "solvers/measure/work_units.hpp"
#include "solvers/mprgp/mprgp_deflation.hpp"

#include <cmath>
#include <sstream>

namespace cb {

namespace {

const SettingsTable<CgSettings>& cg_settings_table()
{
    static const SettingsTable<CgSettings> table =
        SettingsTable<CgSettings>()
            .choice("precond", &CgSettings::precond, {"none", "jacobi", "ichol"},
                    "none | jacobi: preconditioner (diagonal of A) | ichol: incomplete Cholesky of A (Eigen, AMD, no "
                    "fill; docs/preconditioners.md)")
            .choice("start", &CgSettings::start, {"x0", "zero"},
                    "x0 | zero: start point (zero: a 1e-8 reduction of |b|, free of the rounding floor eps |A||x0| "
                    "that a start near the solution meets; docs/preconditioners.md)")
            .choice("deflation", &CgSettings::deflation, {"none", "rigid"},
                    "none | rigid: deflated PCG over the slow rigid modes of each body (from x0; mprgp's coarse "
                    "space without the face): a Galerkin start, then every preconditioned residual made "
                    "A-conjugate to them (docs/preconditioners.md)");
    return table;
}

}  // namespace

CgSettings CgSettings::from_json(const nlohmann::json& settings)
{
    return read_settings(settings, "cg", cg_settings_table());
}

nlohmann::json CgSettings::to_json() const { return write_settings(*this, cg_settings_table()); }

SolverResult CgSolver::solve(const QpView& qp, const SolveContext& context)
{
    SolverResult result;
    result.info["ignores_constraints"] = true;
    Counters& counters = result.counters;
    const Eigen::Index n = qp.n();
    const CommonSettings& common = m_settings.common;

    SolveLoop loop("cg", qp, common, context);
    result.lambda = Vec::Zero(qp.m());
    if (qp.A.cols() != n || qp.b.size() != n || qp.x0.size() != n) {
        result.x = qp.x0;
        return loop.finish(result, SolveStatus::INVALID_INPUT,
                           "cg: sizes disagree (A " + std::to_string(qp.A.rows()) + "x" + std::to_string(qp.A.cols()) +
                               ", b " + std::to_string(qp.b.size()) + ", x0 " + std::to_string(qp.x0.size()) + ")");
    }
    AOperator a_op(qp);  // the product with A: 3x3 blocks when A has them, built in the setup
    a_op.prepare(common.a_format, static_cast<int>(common.threads));
    loop.setup_phase("a_prepare");
    result.info["a_format"] = to_string(a_op.format());  // the storage the products read
    const bool jacobi = m_settings.precond == "jacobi";
    Vec inv_diag;
    if (jacobi) {
        inv_diag = qp.A.diagonal();
        for (Eigen::Index i = 0; i < n; ++i) {
            if (!(inv_diag[i] > 0.0) || !std::isfinite(inv_diag[i])) {
                std::ostringstream msg;
                msg << "cg: jacobi preconditioner needs a positive diagonal; A(" << i << "," << i
                    << ") = " << inv_diag[i];
                result.x = qp.x0;
                return loop.finish(result, SolveStatus::INVALID_INPUT, msg.str());
            }
            inv_diag[i] = 1.0 / inv_diag[i];
        }
    }
    const bool ichol = m_settings.precond == "ichol";
    IncompleteCholeskyPreconditioner ic;
    if (ichol) {
        std::string error;
        if (!ic.factor(qp.A, error)) {
            result.x = qp.x0;
            return loop.finish(result, SolveStatus::INVALID_INPUT, "cg: precond=ichol: " + error);
        }
        ++counters.precond_factorizations;
        counters.work_flops += ic.factor_flops();
        result.info["ichol"] = {{"factor_nonzeros", ic.factor_nonzeros()},
                                {"a_nonzeros", static_cast<long>(qp.A.nonZeros())}};
    }
    auto precondition = [&](const Vec& r) -> Vec {
        if (ichol) {
            ++counters.precond_applications;
            counters.work_flops += ic.apply_flops();
            Vec z;
            ic.apply(r, z);
            return z;
        }
        if (!jacobi) return r;
        ++counters.precond_applications;
        return inv_diag.cwiseProduct(r);
    };
    loop.setup_phase("preconditioner");
    // deflation = rigid: V = the slow rigid modes of each body of A. cg has no face (it ignores
    // J), so V is built over all DOFs with no rows: the face with no active row.
    const SpMat no_rows(0, n);
    RigidDeflation defl;
    bool deflate = false;
    if (m_settings.deflation == "rigid") {
        deflate = defl.build(qp.A, no_rows, qp.x0, RigidDeflation::SLOW_RAYLEIGH);
        counters.a_products += defl.build_products();
        if (deflate && defl.set_face(qp.A, no_rows, DecoupledRows{}, std::vector<char>(), &counters.work_flops))
            counters.a_products += RigidDeflation::MODES;  // A V
        loop.setup_phase("deflation");
    }
    // cg solves the unconstrained relaxation: its stop test measures that QP (J without rows). The
    // scale is setup, as in every solver.
    const Vec no_c(0);
    const AccuracyScale scale =
        accuracy_scale(QpView{qp.A, qp.b, no_rows, no_c, qp.x0, qp.length, nullptr, qp.a_symmetric});
    counters.a_products += scale.a_products;
    loop.setup_phase("measure_scale");
    // The search direction: M^-1 r, made A-conjugate to V when deflating (deflated PCG).
    auto direction = [&](const Vec& r) -> Vec {
        Vec z = precondition(r);
        if (deflate) {
            defl.deflate(z);
            counters.work_flops += defl.apply_flops();
        }
        return z;
    };
    if (!loop.end_setup()) {
        result.x = qp.x0;
        return loop.finish(result, SolveStatus::TIME_LIMIT);
    }

    Vec x = m_settings.start == "zero" ? Vec(Vec::Zero(n)) : qp.x0;
    Vec r = qp.b - a_product(a_op, x);  // r = -g
    ++counters.a_products;
    // Stop test of cg: native = |r|_2 absolute; accuracy = the error of the unconstrained
    // relaxation (its stationarity part, docs/accuracy.md).
    const Vec no_lambda(0);
    auto relaxation_error = [&](const Vec& res) { return scale.stationarity(res, x, no_lambda); };
    auto rule_met = [&](const Vec& res) {
        return loop.criterion_met([&] { return res.norm(); }, [&] { return relaxation_error(res); });
    };

    auto monitor = [&](StepKind step) {
        IterationInfo info;
        info.iteration = counters.iterations;
        info.step = step;
        info.x = &x;
        info.lambda = &result.lambda;
        info.native_residual = r.norm();
        info.counters = &counters;
        return loop.notify(info);
    };
    bool stopped = !monitor(StepKind::START);
    if (stopped) result.status = SolveStatus::STOPPED_BY_MONITOR;

    // deflation: the Galerkin correction x += V E^+ V'r (E = V'AV) minimises F over x + V y and
    // leaves V'r = 0; the A-conjugate directions then keep it so. Not an iteration.
    long galerkin_steps = 0;
    Vec d(n), ad(n);
    auto galerkin = [&]() {
        if (!deflate) return;
        defl.coarse(r, d, ad);
        x += d;
        r -= ad;
        counters.work_flops += defl.apply_flops();
        ++galerkin_steps;
    };
    if (!stopped) galerkin();
    Vec z = direction(r);
    Vec p = z;
    double rz = r.dot(z);
    Vec Ap(n);

    long replacements = 0;  // residual replacements after a false (recurrence-only) convergence
    while (result.status == SolveStatus::NOT_RUN) {
        const bool finite = std::isfinite(rz) && x.allFinite();
        bool converged = false;
        if (finite && rule_met(r)) {
            // The recurrence residual drifts from b - Ax: confirm on the true residual.
            Vec r_true = qp.b - a_product(a_op, x);
            ++counters.a_products;
            converged = rule_met(r_true);
            r = r_true;
            if (!converged) {
                ++replacements;
                galerkin();
                z = direction(r);
                p = z;
                rz = r.dot(z);
                continue;
            }
        }
        result.status = loop.check(counters.iterations, finite, converged);
        if (result.status != SolveStatus::NOT_RUN) break;
        a_product(a_op, p, Ap);
        ++counters.a_products;
        const double p_ap = p.dot(Ap);
        if (!(p_ap > 0.0)) {
            std::ostringstream msg;
            msg << "cg: breakdown at iteration " << counters.iterations << ": p'Ap = " << p_ap
                << (p_ap < 0.0 ? " < 0 (A is not positive definite)" : "");
            result.status = (p_ap == 0.0) ? SolveStatus::STALLED : SolveStatus::DIVERGED;
            result.message = msg.str();
            break;
        }
        const double alpha = rz / p_ap;
        x.noalias() += alpha * p;
        r.noalias() -= alpha * Ap;
        z = direction(r);
        const double rz_new = r.dot(z);
        const double beta = rz_new / rz;
        rz = rz_new;
        p = z + beta * p;
        ++counters.iterations;
        ++counters.cg_steps;
        if (!monitor(StepKind::CG)) {
            result.status = SolveStatus::STOPPED_BY_MONITOR;
            break;
        }
    }
    if (result.status != SolveStatus::CONVERGED) {
        r = qp.b - a_product(a_op, x);  // report the true residual, not the recurrence one
        ++counters.a_products;
    }
    result.x = x;
    result.iterations = counters.iterations;
    result.native_residual = r.norm();
    result.info["residual_replacements"] = replacements;
    result.info["unconstrained_error"] = n ? scale.stationarity(r, x, no_lambda) : 0.0;
    if (m_settings.deflation != "none")
        result.info["deflation"] = {{"active", deflate},
                                    {"bodies", defl.components()},
                                    {"modes", defl.kept_modes()},
                                    {"rayleigh_min", defl.min_rayleigh_seen()},
                                    {"rayleigh_max", defl.max_rayleigh_seen()},
                                    {"galerkin_steps", galerkin_steps}};
    std::ostringstream detail;  // the loop writes the reason (a breakdown's message is kept as it is)
    detail << m_settings.precond << (deflate ? ", rigid deflation" : "") << ", " << counters.iterations
           << " iterations, |b - Ax|_2 = " << result.native_residual << " (constraints ignored)";
    return loop.finish(result, result.status, result.message.empty() ? detail.str() : result.message);
}

SolverEntry cg_entry()
{
    return solver_entry<CgSolver>(
        "cg", cg_settings_table(),
        "preconditioned (jacobi | ichol) CG on Ax = b ignoring J (Fig. 8 baseline); stop=kkt is the "
        "accuracy error of the unconstrained relaxation",
        "ignores J (solves Ax = b)");
}

}  // namespace cb
