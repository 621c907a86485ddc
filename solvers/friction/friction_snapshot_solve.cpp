// A frictional method run on a snapshot and judged by the harness's measure (see friction_snapshot_solve.hpp).
#include "solvers/friction/friction_snapshot_solve.hpp"

#include "solvers/core/format_number.hpp"
#include "solvers/core/solve_loop.hpp"
#include "solvers/measure/accuracy.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace cb {

namespace {

void add_work_counters(Counters& total, const Counters& part)
{
    total.a_products += part.a_products;
    total.cholmod_analyses += part.cholmod_analyses;
    total.cholmod_factorizations += part.cholmod_factorizations;
    total.cholmod_solves += part.cholmod_solves;
    total.work_flops += part.work_flops;
}

SolveStatus status_of(const std::string& text)
{
    try {
        return solve_status_from_string(text);
    } catch (const InputError&) {
        return SolveStatus::STALLED;  // a word the harness does not know: the verdict decides
    }
}

}  // namespace

Friction frictionless_frame(const QpView& qp)
{
    Friction frame;
    frame.mu = Vec::Zero(qp.m());
    frame.T.resize(2 * qp.m(), qp.n());
    return frame;
}

FrictionLocal pin_frictionless_tangents(const FrictionLocal& local)
{
    const Eigen::Index m = local.contacts(), n = 3 * m;
    std::vector<bool> touched(static_cast<size_t>(n), false);
    for (Eigen::Index row = 0; row < local.W.outerSize(); ++row)
        for (SpMat::InnerIterator it(local.W, row); it; ++it)
            if (it.value() != 0.0) touched[static_cast<size_t>(row)] = touched[static_cast<size_t>(it.col())] = true;
    FrictionLocal out = local;
    std::vector<Eigen::Triplet<double>> entries;
    for (Eigen::Index row = 0; row < local.W.outerSize(); ++row)
        for (SpMat::InnerIterator it(local.W, row); it; ++it)
            entries.emplace_back(static_cast<int>(row), static_cast<int>(it.col()), it.value());
    bool pinned = false;
    for (Eigen::Index i = 0; i < m; ++i) {
        if (local.mu[i] != 0.0) continue;
        const double normal = local.W.coeff(3 * i, 3 * i);
        for (Eigen::Index k = 3 * i + 1; k <= 3 * i + 2; ++k) {
            if (touched[static_cast<size_t>(k)]) continue;
            entries.emplace_back(static_cast<int>(k), static_cast<int>(k), normal > 0.0 ? normal : 1.0);
            out.q[k] = 0.0;
            pinned = true;
        }
    }
    if (!pinned) return out;
    out.W.resize(n, n);
    out.W.setFromTriplets(entries.begin(), entries.end());
    return out;
}

SolverResult solve_frictional_snapshot(const std::string& name, const QpView& qp, const CommonSettings& common,
                                       const SolveContext& context, const SnapshotFrictionOptions& options,
                                       const SnapshotFrictionSetup& setup)
{
    const Eigen::Index m = qp.m();
    SolverResult result;
    Counters& counters = result.counters;
    result.x = qp.x0;
    result.lambda = Vec::Zero(m);
    const bool own_frame = qp.friction && qp.friction->mu.size() == m && qp.friction->T.rows() == 2 * m;
    if (own_frame) result.lambda_t = Vec::Zero(2 * m);
    result.info["native_residual_definition"] = options.native_definition;

    SolveLoop loop(name, qp, common, context);
    if (m > options.max_contacts)
        return loop.finish(result, SolveStatus::NOT_APPLICABLE,
                           name + ": m = " + std::to_string(m) +
                               " contacts exceeds max_contacts = " + std::to_string(options.max_contacts) +
                               " (the local problem's W = H A^-1 H' is a dense 3m x 3m matrix); raise the "
                               "max_contacts setting to allow it");
    if (!loop.inputs_finite()) return loop.finish(result, loop.check(0, false, false), "the method was not called");

    Friction synthesized;
    if (!own_frame) synthesized = frictionless_frame(qp);
    const QpView framed{qp.A,          qp.b, qp.J, qp.c, qp.x0, qp.length, own_frame ? qp.friction : &synthesized,
                        qp.a_symmetric};
    result.info["frame"] =
        own_frame ? "the snapshot's (mu, T)" : "no friction fields: mu = 0 with synthesized tangent rows (no lambda_t)";
    SnapshotFrictionMethod method;
    try {
        method = setup(framed);
    } catch (const InputError& e) {
        return loop.finish(result, SolveStatus::INVALID_INPUT, e.what());
    }
    loop.setup_phase("local_problem");
    const AccuracyScale scale = accuracy_scale(qp);  // in the setup, as in every solver
    counters.a_products += scale.a_products;
    loop.setup_phase("measure_scale");
    if (!loop.end_setup()) {
        add_work_counters(counters, method.counters());
        return loop.finish(result, SolveStatus::TIME_LIMIT);
    }

    Vec x = qp.x0, lambda = Vec::Zero(m), lambda_t = Vec::Zero(own_frame ? 2 * m : 0);
    double native = std::numeric_limits<double>::infinity(), e = native;
    const bool kkt = !common.stops_on_native();
    double own_tol = common.tol;
    long iterations = 0;
    bool finite = true, have_point = false;
    std::string last_status = "not_run", notes;
    nlohmann::json rounds = nlohmann::json::array();
    for (int round = 0; round < options.max_rounds; ++round) {
        double left_s = 0.0;
        if (common.time_limit_s > 0.0) {
            left_s = common.time_limit_s - loop.elapsed_s();
            if (left_s <= 0.0) break;
        }
        const long left_iterations = std::max(0L, common.max_iterations - iterations);
        if (round > 0 && left_iterations == 0) break;
        SnapshotFrictionRun one;
        try {
            one = method.run(own_tol, left_iterations, left_s);
        } catch (const InputError& error) {
            add_work_counters(counters, method.counters());
            return loop.finish(result, SolveStatus::INVALID_INPUT, error.what());
        }
        iterations += one.run.iterations;
        const Vec& r = one.run.r;
        const bool one_finite = r.size() == 3 * m && r.allFinite() && one.x.size() == qp.n() && one.x.allFinite();
        Vec one_lambda = Vec::Zero(m), one_lambda_t = Vec::Zero(lambda_t.size());
        double one_e = std::numeric_limits<double>::infinity();
        if (one_finite) {
            for (Eigen::Index i = 0; i < m; ++i) {
                one_lambda[i] = r[3 * i];
                if (own_frame) {
                    one_lambda_t[2 * i] = r[3 * i + 1];
                    one_lambda_t[2 * i + 1] = r[3 * i + 2];
                }
            }
            const Vec g = qp.A * one.x - qp.b;
            ++counters.a_products;
            one_e = accuracy_from_gradient(qp, scale, one.x, g, one_lambda, own_frame ? &one_lambda_t : nullptr).max();
        }
        rounds.push_back({{"own_tol", own_tol},
                          {"status", one.run.status},
                          {"iterations", one.run.iterations},
                          {"seconds", one.run.seconds},
                          {"own_error", one.run.error},
                          {"e", one_e},
                          {"note", one.run.note}});
        notes += std::string(notes.empty() ? "" : "; ") + "round " + std::to_string(round + 1) + " (own tol " +
                 format_e(own_tol, 2) + "): " + one.run.status + ", " + std::to_string(one.run.iterations) +
                 " iterations, own error " + format_e(one.run.error, 3) + ", e " + format_e(one_e, 3) +
                 (one.run.note.empty() ? "" : " (" + one.run.note + ")");
        if (have_point && !(one_e < e)) {  // a tighter round that did not improve e: the previous point stands
            notes += ": the previous round's point is kept";
            break;
        }
        have_point = true;
        finite = one_finite;
        last_status = one.run.status;
        native = one.run.error;
        e = one_e;
        if (one_finite) {
            x = one.x;
            lambda = one_lambda;
            lambda_t = one_lambda_t;
        }
        if (!kkt || !one_finite || e <= common.tol || one.run.status != "converged") break;
        // The method met its own stop but not e: ask it for more, in proportion.
        const double tighter = std::max(1e-16, own_tol * std::min(0.1, common.tol / e));
        if (!(tighter < own_tol)) break;
        own_tol = tighter;
    }
    add_work_counters(counters, method.counters());
    counters.iterations = iterations;
    result.info["rounds"] = rounds;
    if (!have_point) return loop.finish(result, SolveStatus::TIME_LIMIT);  // the limit came before any round
    result.x = x;
    result.lambda = lambda;
    result.lambda_t = lambda_t;
    result.native_residual = native;

    // The monitor sees the returned point only: the methods have no iteration callback here.
    IterationInfo last{iterations, StepKind::FINAL, &x, &lambda, native, -1, &counters, 0.0};
    if (own_frame) last.lambda_t = &lambda_t;
    const bool go_on = loop.notify(last);
    SolveStatus otherwise = status_of(last_status);
    if (otherwise == SolveStatus::CONVERGED || otherwise == SolveStatus::NOT_RUN) otherwise = SolveStatus::STALLED;
    if (otherwise == SolveStatus::STALLED && iterations >= common.max_iterations)
        otherwise = SolveStatus::MAX_ITERATIONS;
    if (otherwise == SolveStatus::STALLED && loop.time_up()) otherwise = SolveStatus::TIME_LIMIT;
    SolveStatus status = loop.verdict(finite, native, e, otherwise);
    if (!go_on && status != SolveStatus::CONVERGED) status = SolveStatus::STOPPED_BY_MONITOR;
    return loop.finish(result, status, notes);
}

}  // namespace cb
