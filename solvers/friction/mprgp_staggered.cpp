// `mprgp-staggered` (see mprgp_staggered.hpp).
#include "solvers/friction/mprgp_staggered.hpp"

#include "solvers/core/solve_loop.hpp"
#include "solvers/linalg/a_product.hpp"
#include "solvers/linalg/dual_lcp.hpp"
#include "solvers/measure/accuracy.hpp"
#include "solvers/measure/friction_snapshot_error.hpp"
#include "solvers/measure/work_units.hpp"
#include "solvers/mprgp/disc_set.hpp"
#include "solvers/mprgp/mprgp_coupled.hpp"
#include "solvers/mprgp/mprgp_feasible.hpp"
#include "solvers/mprgp/mprgp_kernels.hpp"

#include <algorithm>
#include <climits>
#include <cmath>
#include <limits>
#include <sstream>
#include <vector>

namespace cb {

namespace {

const char* const STAGGERED_NAME = "mprgp-staggered";
const char* const NORMAL_SOLVER = "mprgp-coupled";

/// Every setting of `mprgp-staggered`, declared once (settings.hpp SettingsTable).
const SettingsTable<MprgpStaggeredSettings>& mprgp_staggered_settings_table()
{
    static const SettingsTable<MprgpStaggeredSettings> table =
        SettingsTable<MprgpStaggeredSettings>()
            .integer("max_outer", &MprgpStaggeredSettings::max_outer, 1, LONG_MAX,
                     "staggered rounds (a normal and a tangential solve each); reaching it ends max_iterations")
            .integer("max_contacts", &MprgpStaggeredSettings::max_contacts, 0, LONG_MAX,
                     "refuse (not_applicable) more frictional contacts (W_TT = T A^-1 T' is a dense 2m x 2m matrix)")
            .number("inner_fraction", &MprgpStaggeredSettings::inner_fraction, 0.0, 1.0,
                    "each inner solve stops at max(inner_fraction tol, inner_relative e_k)")
            .number("inner_relative", &MprgpStaggeredSettings::inner_relative, 0.0, 1.0,
                    "(see inner_fraction) e_k: the frictional e after the round before (loose while lambda_N moves); "
                    "both 10x tighter after each round without a 1% lower outer error")
            .integer("stall_rounds", &MprgpStaggeredSettings::stall_rounds, 1, LONG_MAX,
                     "rounds without a 1% lower outer error before the run ends stalled");
    return table;
}

/// Without friction the method is one normal solve: mprgp-coupled's run, its message under our name.
SolverResult frictionless(const QpView& qp, const SolveContext& context, const CommonSettings& common)
{
    MprgpCoupledSettings normal;
    normal.common = common;
    SolverResult r = mprgp_coupled_solve(qp, normal, context);
    const std::string prefix = std::string(NORMAL_SOLVER) + ": ";
    if (r.message.rfind(prefix, 0) == 0)
        r.message = std::string(STAGGERED_NAME) + ": " + r.message.substr(prefix.size());
    r.info["rounds"] = 1;
    r.info["normal_solver"] = NORMAL_SOLVER;
    if (qp.friction && qp.friction->T.rows() == 2 * qp.m()) r.lambda_t = Vec::Zero(2 * qp.m());
    return r;
}

/// The smallest nonzero row norm of J (the friction part's displacement unit: docs/accuracy.md).
double smallest_row_norm(const AccuracyScale& scale)
{
    double largest_inverse = 0.0;
    for (Eigen::Index i = 0; i < scale.inv_row_norm.size(); ++i)
        largest_inverse = std::max(largest_inverse, scale.inv_row_norm[i]);
    return largest_inverse > 0.0 ? 1.0 / largest_inverse : 1.0;
}

void add_inner_counters(Counters& total, const Counters& part)
{
    total.iterations += part.iterations;
    total.cg_steps += part.cg_steps;
    total.expansion_steps += part.expansion_steps;
    total.proportioning_steps += part.proportioning_steps;
    total.safeguard_steps += part.safeguard_steps;
    total.projections += part.projections;
    total.precond_applications += part.precond_applications;
    total.precond_factorizations += part.precond_factorizations;
    total.cholmod_analyses += part.cholmod_analyses;
    total.cholmod_factorizations += part.cholmod_factorizations;
    total.cholmod_solves += part.cholmod_solves;
    total.lcp_iterations += part.lcp_iterations;
    total.pivots += part.pivots;
    total.work_flops += part.work_flops;
}

}  // namespace

MprgpStaggeredSettings MprgpStaggeredSettings::from_json(const nlohmann::json& settings)
{
    return read_settings(settings, STAGGERED_NAME, mprgp_staggered_settings_table());
}

nlohmann::json MprgpStaggeredSettings::to_json() const
{
    return write_settings(*this, mprgp_staggered_settings_table());
}

SolverResult MprgpStaggeredSolver::solve(const QpView& qp, const SolveContext& context)
{
    const MprgpStaggeredSettings& s = m_settings;
    if (!qp.frictional()) return frictionless(qp, context, s.common);

    const Eigen::Index n = qp.n(), m = qp.m();
    const Friction& f = *qp.friction;
    SolverResult result;
    Counters& counters = result.counters;
    result.x = qp.x0;
    result.lambda = Vec::Zero(m);
    result.lambda_t = Vec::Zero(2 * m);
    result.info["normal_solver"] = NORMAL_SOLVER;
    result.info["native_residual_definition"] =
        "FCLIB's relative natural-map error ||F_nat(r)|| / ||q|| of the snapshot's local problem";
    SolveLoop loop(STAGGERED_NAME, qp, s.common, context);
    if (m > s.max_contacts)
        return loop.finish(result, SolveStatus::NOT_APPLICABLE,
                           std::string(STAGGERED_NAME) + ": m = " + std::to_string(m) +
                               " contacts exceeds max_contacts = " + std::to_string(s.max_contacts) +
                               " (W_TT = T A^-1 T' is a dense 2m x 2m matrix); raise the max_contacts setting to "
                               "allow it");
    if (f.mu.size() != m || f.T.rows() != 2 * m || f.T.cols() != n || (f.cT.size() != 0 && f.cT.size() != 2 * m))
        return loop.finish(result, SolveStatus::INVALID_INPUT,
                           std::string(STAGGERED_NAME) + ": friction fields of the wrong size (mu " +
                               std::to_string(f.mu.size()) + ", T " + std::to_string(f.T.rows()) + " x " +
                               std::to_string(f.T.cols()) + ", cT " + std::to_string(f.cT.size()) +
                               "; m = " + std::to_string(m) + ", n = " + std::to_string(n) + ")");
    if (!loop.inputs_finite() || !f.mu.allFinite()) return loop.finish(result, loop.check(0, false, false));

    // --- setup: W_TT and q_T0 = T A^-1 b - cT by one CHOLMOD factor of A, alpha_bar, D^-1 ---
    const Vec c_tangent = f.cT.size() == 2 * m ? f.cT : Vec(Vec::Zero(2 * m));
    const QpView tangent_rows{qp.A, qp.b, f.T, c_tangent, qp.x0, nullptr, nullptr};
    DualLcp tangential;
    std::string error;
    if (!tangential.form(tangent_rows, counters, error))
        return loop.finish(result, SolveStatus::INVALID_INPUT, std::string(STAGGERED_NAME) + ": " + error);
    const SpMat W_tt = tangential.matrix().sparseView();
    const Vec q_t0 = tangential.q();
    // ||q|| of the local problem (FCLIB's denominator): q = (J A^-1 b - c, q_T0).
    const Vec q_n0 = qp.J * tangential.unconstrained() - qp.c;
    const double norm_q = std::sqrt(q_n0.squaredNorm() + q_t0.squaredNorm());
    // D^-1 of W_TT; a zero tangent row (diagonal 0) never moves its disc's centre: 1 is harmless.
    Vec dinv(2 * m);
    for (Eigen::Index j = 0; j < 2 * m; ++j) dinv[j] = W_tt.coeff(j, j) > 0.0 ? 1.0 / W_tt.coeff(j, j) : 1.0;
    loop.setup_phase("tangential_dual");
    AOperator w_op(W_tt);
    w_op.prepare(AFormat::CSR);
    Vec eigenvector;
    const PowerResult power = power_method(w_op, eigenvector, PowerRule::POWER, 100, 1e-8, false, s.common.seed);
    const double alpha_bar = power.estimate > 0.0 ? 2.0 / (1.01 * power.estimate) : 1.0;
    const double w_product_flops = dense_matvec_flops(double(2 * m), double(2 * m));
    counters.work_flops += double(power.products) * w_product_flops;
    loop.setup_phase("power");
    const AccuracyScale scale = accuracy_scale(qp);  // in the setup, as in every solver
    counters.a_products += scale.a_products;
    loop.setup_phase("measure_scale");
    if (!loop.end_setup()) return loop.finish(result, SolveStatus::TIME_LIMIT);
    // The normal QPs are measured in the snapshot's scale (their b differs, so l is fixed here).
    const FixedLength length{scale.length, "given"};
    const bool native = s.common.stops_on_native();
    const double tangential_unit = scale.length * smallest_row_norm(scale);  // e's friction part, in lengths

    Vec x = qp.x0, lambda_n = Vec::Zero(m), lambda_t = Vec::Zero(2 * m), g;
    double e = 0.0, fclib = 0.0;
    auto measure = [&]() {
        g = a_product(qp.A, x) - qp.b;
        ++counters.a_products;
        e = accuracy_from_gradient(qp, scale, x, g, lambda_n, &lambda_t).max();
        fclib = friction_snapshot_error(qp, x, lambda_n, lambda_t, norm_q);
    };
    long rounds = 0, normal_iterations = 0, tangential_iterations = 0, tangential_products = 0;
    Counters tangential_steps;  // the tangential solves' step kinds, summed (info)
    auto finish = [&](SolveStatus status, const std::string& detail) {
        result.x = x;
        result.lambda = lambda_n;
        result.lambda_t = lambda_t;
        result.native_residual = fclib;
        result.info["rounds"] = rounds;
        result.info["normal_iterations"] = normal_iterations;
        result.info["tangential_iterations"] = tangential_iterations;
        result.info["tangential_w_products"] = tangential_products;
        result.info["tangential_steps"] = {{"cg", tangential_steps.cg_steps},
                                           {"expansion", tangential_steps.expansion_steps},
                                           {"proportioning", tangential_steps.proportioning_steps}};
        std::ostringstream text;
        text << rounds << " rounds (" << normal_iterations << " normal + " << tangential_iterations
             << " tangential MPRGP iterations), e " << e << ", FCLIB error " << fclib;
        return loop.finish(result, status, detail.empty() ? text.str() : detail + "; " + text.str());
    };
    auto notify = [&](StepKind step) {
        IterationInfo info;
        info.iteration = counters.iterations;
        info.step = step;
        info.x = &x;
        info.lambda = &lambda_n;
        info.lambda_t = &lambda_t;
        info.native_residual = fclib;
        info.counters = &counters;
        return loop.notify(info);
    };
    // An inner solve's limit: what is left of ours (never <= 0 there, which would read as "none").
    auto remaining_time = [&]() {
        return s.common.time_limit_s > 0.0 ? std::max(s.common.time_limit_s - loop.elapsed_s(), 1e-12) : 0.0;
    };

    measure();
    if (!notify(StepKind::START)) return finish(SolveStatus::STOPPED_BY_MONITOR, "");
    // The inner tolerances follow e in both stop rules: the normal solve's own measure is e, and
    // FCLIB's error (stop=native) does not bound it, so loose solves would hold it up.
    double outer = native ? fclib : e, best = std::numeric_limits<double>::infinity();
    // x 0.1 after each round that did not lower the outer error by 1%: an error held up by the
    // inner solves' accuracy (FCLIB's at e ~ tol) gets tighter ones.
    double tighten = 1.0;
    constexpr double TIGHTEST = 1e-6;
    long since_best = 0;
    Vec b_normal(n), b_disc(2 * m), x_free_n;
    std::vector<double> radius(static_cast<size_t>(m));
    const SpMat no_rows(0, 2 * m);
    const Vec no_c(0);
    while (true) {
        const double inner_tol = std::max(s.inner_fraction * s.common.tol, s.inner_relative * e) * tighten;
        // (a) the normal QP with lambda_T fixed: b + T'lambda_T, warm-started at x.
        b_normal = qp.b + f.T.transpose() * lambda_t;
        const QpView normal_qp{qp.A, b_normal, qp.J, qp.c, x, &length, nullptr, qp.a_symmetric};
        MprgpCoupledSettings normal;
        normal.common = s.common;
        normal.common.stop = StopRule::ACCURACY;
        normal.common.tol = inner_tol;
        normal.common.max_iterations = s.common.max_iterations - counters.iterations;
        normal.common.time_limit_s = remaining_time();
        const SolverResult nr = mprgp_coupled_solve(normal_qp, normal, SolveContext{});
        ++rounds;
        add_inner_counters(counters, nr.counters);
        counters.a_products += nr.counters.a_products;
        counters.power_products += nr.counters.power_products;
        normal_iterations += nr.counters.iterations;
        if (nr.status == SolveStatus::TIME_LIMIT) return finish(SolveStatus::TIME_LIMIT, "");
        if (nr.status == SolveStatus::MAX_ITERATIONS) return finish(SolveStatus::MAX_ITERATIONS, "");
        if (nr.status != SolveStatus::CONVERGED)
            return finish(nr.status == SolveStatus::NOT_RUN ? SolveStatus::STALLED : nr.status,
                          std::string(STAGGERED_NAME) + ": normal solve of round " + std::to_string(rounds) + ": " +
                              nr.message);
        x = nr.x;
        lambda_n = nr.lambda;

        // The point (x, lambda_N, lambda_T): Coulomb's law of the lambda_T it was solved with.
        measure();
        if (!notify(StepKind::OUTER)) return finish(SolveStatus::STOPPED_BY_MONITOR, "");
        const bool finite = x.allFinite() && lambda_t.allFinite() && std::isfinite(e) && std::isfinite(fclib);
        const SolveStatus exit = loop.check(counters.iterations, finite, fclib, e);
        if (exit != SolveStatus::NOT_RUN) return finish(exit, "");
        outer = native ? fclib : e;
        if (outer < 0.99 * best) {
            best = outer;
            since_best = 0;
        } else {
            tighten = std::max(0.1 * tighten, TIGHTEST);
            if (++since_best >= s.stall_rounds)
                return finish(SolveStatus::STALLED, std::string(STAGGERED_NAME) +
                                                        ": stalled: the outer error did not fall 1% in " +
                                                        std::to_string(s.stall_rounds) + " rounds");
        }
        if (rounds >= s.max_outer) {
            SolverResult out = finish(SolveStatus::MAX_ITERATIONS, "");
            // The loop's standard reason names max_iterations, which was not reached: say which cap was.
            out.message = std::string(STAGGERED_NAME) + ": outer cap max_outer = " + std::to_string(s.max_outer) +
                          " rounds reached" + out.message.substr(out.message.find(';'));
            return out;
        }

        // (b) the tangential QP with lambda_N fixed: discs of radius mu_i lambda_N,i, warm-started.
        for (Eigen::Index i = 0; i < m; ++i) radius[static_cast<size_t>(i)] = f.mu[i] * std::max(lambda_n[i], 0.0);
        b_normal = qp.b + qp.J.transpose() * lambda_n;
        const QpView normal_load{qp.A, b_normal, f.T, c_tangent, qp.x0, nullptr, nullptr};
        x_free_n = tangential.primal(normal_load, Vec::Zero(2 * m), counters);  // A^-1 (b + J'lambda_N)
        b_disc = -(f.T * x_free_n - c_tangent);                                 // -q_T
        CommonSettings disc_common;
        disc_common.stop = StopRule::NATIVE;
        disc_common.tol = inner_tol * tangential_unit;
        disc_common.max_iterations = s.common.max_iterations - counters.iterations;
        disc_common.time_limit_s = remaining_time();
        const QpView disc_qp{W_tt, b_disc, no_rows, no_c, lambda_t};
        SolveLoop disc_loop(STAGGERED_NAME, disc_qp, disc_common, SolveContext{});
        disc_loop.end_setup();
        Counters cnt;
        DiscSet discs(radius);
        FeasibleMprgpSteps<DiscSet> steps(discs, w_op, b_disc, dinv, alpha_bar, 1.0, disc_loop, cnt);
        steps.start(lambda_t);
        std::string why;
        const SolveStatus ts = run_mprgp(steps, disc_loop, cnt, why);
        lambda_t = steps.x();
        tangential_iterations += cnt.iterations;
        tangential_products += cnt.a_products;
        counters.work_flops += double(cnt.a_products) * w_product_flops;
        cnt.a_products = 0;  // products with W_TT, not A: counted as work above
        add_inner_counters(counters, cnt);
        add_inner_counters(tangential_steps, cnt);
        if (ts == SolveStatus::TIME_LIMIT) return finish(SolveStatus::TIME_LIMIT, "");
        if (ts == SolveStatus::MAX_ITERATIONS) return finish(SolveStatus::MAX_ITERATIONS, "");
        if (ts != SolveStatus::CONVERGED)
            return finish(ts, std::string(STAGGERED_NAME) + ": tangential solve of round " + std::to_string(rounds) +
                                  ": " + to_string(ts) + (why.empty() ? "" : " (" + why + ")"));
    }
}

SolverEntry mprgp_staggered_entry()
{
    return solver_entry<MprgpStaggeredSolver>(
        STAGGERED_NAME, mprgp_staggered_settings_table(),
        "staggered projections (Kaufman et al. 2008): the normal QP by mprgp-coupled with lambda_T fixed, the "
        "tangential discs by MPGP on W_TT = T A^-1 T' with lambda_N fixed, to a Coulomb fixed point",
        "any J with at most max_contacts rows; Coulomb friction (mu, tangent rows) when the snapshot has it, else "
        "mprgp-coupled's run");
}

}  // namespace cb
