// mprgp-tresca-fp and mprgp+ica-friction (see mprgp_tresca.hpp).
#include "solvers/friction/mprgp_tresca.hpp"

#include "solvers/core/format_number.hpp"
#include "solvers/core/solve_loop.hpp"
#include "solvers/core/stopwatch.hpp"
#include "solvers/linalg/a_product.hpp"
#include "solvers/measure/friction_error.hpp"
#include "solvers/mprgp/mprgp_box.hpp"
#include "solvers/mprgp/mprgp_feasible.hpp"
#include "solvers/mprgp/mprgp_kernels.hpp"
#include "solvers/mprgp/mprgp_parts.hpp"
#include "solvers/mprgp/tresca_set.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <vector>

namespace cb {

namespace {

constexpr Eigen::Index DENSE_CHECK_ROWS = 3000;  ///< the definiteness check's dense size cap
/// ||W - W'||_F / ||W||_F up to which W counts as symmetric (rounding of a product H M^-1 H', LMGC's
/// 1e-16); (W + W')/2 is used either way, said in the note only beyond it.
constexpr double ROUNDING_ASYMMETRY = 1e-12;

/// Rows and columns `keep` of W (in that order).
SpMat principal_submatrix(const SpMat& W, const std::vector<Eigen::Index>& keep)
{
    std::vector<Eigen::Index> position(static_cast<size_t>(W.cols()), -1);
    for (size_t k = 0; k < keep.size(); ++k) position[static_cast<size_t>(keep[k])] = static_cast<Eigen::Index>(k);
    std::vector<Eigen::Triplet<double>> entries;
    for (size_t k = 0; k < keep.size(); ++k)
        for (SpMat::InnerIterator it(W, keep[k]); it; ++it)
            if (position[static_cast<size_t>(it.col())] >= 0)
                entries.emplace_back(static_cast<int>(k), static_cast<int>(position[static_cast<size_t>(it.col())]),
                                     it.value());
    const Eigen::Index n = static_cast<Eigen::Index>(keep.size());
    SpMat sub(n, n);
    sub.setFromTriplets(entries.begin(), entries.end());
    return sub;
}

/// The normal components 0, 3, 6, ...
std::vector<Eigen::Index> normal_rows(Eigen::Index contacts)
{
    std::vector<Eigen::Index> rows;
    for (Eigen::Index i = 0; i < contacts; ++i) rows.push_back(3 * i);
    return rows;
}

/// ||W - W'||_F / ||W||_F (0 for W = 0).
double asymmetry(const SpMat& W)
{
    const SpMat T = SpMat(W.transpose());
    const double norm = W.norm();
    return norm > 0.0 ? (W - T).norm() / norm : 0.0;
}

SpMat symmetric_part(const SpMat& W) { return SpMat(0.5 * (W + SpMat(W.transpose()))); }

/// Whether W (symmetric, up to DENSE_CHECK_ROWS rows) is positive semidefinite to rounding: a
/// Cholesky factor of W + 1e-10 max|W_jj| I exists. (Eigen's pivoted LDL' is no test here: on the
/// singular W of a rigid multibody problem, Capsules', its trailing pivots are noise of either sign.)
bool semidefinite(const SpMat& W)
{
    Eigen::MatrixXd dense(W);
    const double shift = 1e-10 * dense.diagonal().cwiseAbs().maxCoeff();
    dense.diagonal().array() += shift;
    return Eigen::LLT<Eigen::MatrixXd>(dense).info() == Eigen::Success;
}

void add_counters(Counters& total, const Counters& part)
{
    total.iterations += part.iterations;
    total.a_products += part.a_products;
    total.power_products += part.power_products;
    total.cg_steps += part.cg_steps;
    total.expansion_steps += part.expansion_steps;
    total.proportioning_steps += part.proportioning_steps;
    total.projections += part.projections;
    total.precond_applications += part.precond_applications;
}

}  // namespace

MprgpTrescaRun mprgp_tresca_fp(const FrictionLocal& p, const MprgpTrescaSettings& s)
{
    const Eigen::Index m = p.contacts(), n = 3 * m;
    MprgpTrescaRun out;
    FrictionRun& run = out.run;
    run.solver = "mprgp-tresca-fp";
    run.r = Vec::Zero(n);
    Stopwatch watch;
    watch.start();
    auto finish = [&](const std::string& status, const std::string& note) {
        watch.pause();
        run.status = status;
        run.note = std::to_string(out.outer) + " Tresca solves" +
                   (status != "not_applicable" ? ", setup " + format_e(out.setup_s, 2) + " s" : "") +
                   (note.empty() ? "" : "; " + note);
        run.seconds = watch.seconds();
        run.iterations = out.counters.iterations;
        run.error = fclib_relative_error(p, run.r, &run.u);
        if (out.symmetrised && !s.lag_skew && status != "not_applicable") {
            FrictionLocal symmetric = p;  // what the fixed point solved, to tell the two errors apart
            symmetric.W = symmetric_part(p.W);
            run.note += "; FCLIB error on (W + W')/2: " + format_e(fclib_relative_error(symmetric, run.r), 3);
        }
        return out;
    };

    // --- setup: the QP's matrix (symmetric), its definiteness, D^-1, alpha_bar ---
    out.asymmetry = asymmetry(p.W);
    out.symmetrised = out.asymmetry > ROUNDING_ASYMMETRY;
    const SpMat W = out.asymmetry > 0.0 ? symmetric_part(p.W) : p.W;
    std::string note;
    if (out.symmetrised)
        note = "W is not symmetric (||W - W'||_F / ||W||_F = " + format_e(out.asymmetry, 2) + "): the Tresca QPs use " +
               (s.lag_skew ? "(W + W')/2 with the skew part (W - W')/2 r at the outer iterate in q"
                           : "(W + W')/2 (skew part dropped); the error is on the given W");
    // W = S + K, S = (W + W')/2, K = (W - W')/2: with K r^k in the linear term, a fixed point of the
    // outer iteration solves u = S r + K r + q = W r + q, the given problem.
    const SpMat skew = out.symmetrised && s.lag_skew ? SpMat(0.5 * (p.W - SpMat(p.W.transpose()))) : SpMat(n, n);
    auto with_note = [&](const std::string& more) { return note.empty() ? more : note + "; " + more; };
    if (n <= DENSE_CHECK_ROWS && n > 0) {
        if (!semidefinite(W))
            return finish("not_applicable", with_note(std::string(out.symmetrised ? "(W + W')/2" : "W") +
                                                      " is not positive semidefinite (no Cholesky factor of W + "
                                                      "1e-10 max|W_jj| I): the Tresca dual is not a convex QP"));
    }
    Vec dinv;
    std::string why;
    if (!jacobi_inverse_diagonal(W, dinv, why)) return finish("not_applicable", with_note(why));
    // alpha_bar <= 2/||W_RR||, R the components that can move (every normal, the tangents of
    // contacts with mu > 0): at mu = 0 this is mprgp-box's alpha_bar on W_NN.
    std::vector<Eigen::Index> movable;
    for (Eigen::Index i = 0; i < m; ++i) {
        movable.push_back(3 * i);
        if (p.mu[i] > 0.0) {
            movable.push_back(3 * i + 1);
            movable.push_back(3 * i + 2);
        }
    }
    const SpMat W_movable = principal_submatrix(W, movable);
    AOperator movable_op(W_movable);
    movable_op.prepare(AFormat::BSR);
    Vec eigenvector;
    const PowerResult power =
        power_method(movable_op, eigenvector, PowerRule::POWER, s.power_max, s.power_tol, false, 0);
    out.counters.power_products = power.products;
    out.counters.a_products = power.products;
    out.alpha_bar = power.estimate > 0.0 ? 2.0 / (1.01 * power.estimate) : 1.0;
    AOperator a_op(W);
    a_op.prepare(AFormat::BSR);
    Vec b = -p.q;
    const SpMat no_rows(0, n);
    const Vec no_c = Vec::Zero(0);
    const QpView qp{W, b, no_rows, no_c, run.r};
    const double norm_q = p.q.norm();
    out.setup_s = watch.seconds();
    const bool frictionless = m == 0 || p.mu.maxCoeff() <= 0.0;

    // --- the fixed point on the slip bounds ---
    double error = fclib_relative_error(p, run.r);
    double best = error;
    long since_best = 0;
    constexpr long STALL_WINDOW = 20;  // outer iterations without a 1% better error: stalled
    Vec slip = Vec::Zero(m);
    while (true) {
        if (error <= s.tol) return finish("converged", note);
        if (out.outer >= s.max_outer) return finish("max_iterations", with_note("outer cap reached"));
        if (since_best >= STALL_WINDOW)
            return finish("stalled", with_note("the FCLIB error did not fall 1% in " + std::to_string(STALL_WINDOW) +
                                               " Tresca solves"));
        const double left = s.time_limit_s > 0.0 ? s.time_limit_s - watch.seconds() : 0.0;
        if (s.time_limit_s > 0.0 && left <= 0.0) return finish("time_limit", note);
        for (Eigen::Index i = 0; i < m; ++i) slip[i] = p.mu[i] * run.r[3 * i];
        if (skew.nonZeros() > 0) b = -(p.q + skew * run.r);
        CommonSettings common;
        common.stop = StopRule::NATIVE;
        // Loose Tresca solves while the slip bounds still move (tightened with the outer error);
        // without friction they never move, so the one solve is tight.
        const double relative =
            frictionless ? s.inner_fraction * s.tol : std::max(s.inner_fraction * s.tol, s.inner_relative * error);
        common.tol = relative * (norm_q > 0.0 ? norm_q : 1.0);
        common.max_iterations = s.max_inner;
        common.time_limit_s = left;
        SolveContext context;
        context.monitor = s.monitor;
        SolveLoop loop("mprgp-tresca-fp", qp, common, context);
        loop.end_setup();
        Counters cnt;
        TrescaSet set(slip);
        FeasibleMprgpSteps<TrescaSet> steps(set, a_op, b, dinv, out.alpha_bar, s.gamma, loop, cnt);
        steps.start(run.r);
        const SolveStatus inner = run_mprgp(steps, loop, cnt, why);
        run.r = steps.x();
        add_counters(out.counters, cnt);
        ++out.outer;
        if (inner == SolveStatus::DIVERGED || inner == SolveStatus::STALLED)
            return finish(to_string(inner), with_note("Tresca solve " + std::to_string(out.outer) + ": " + why));
        if (inner == SolveStatus::TIME_LIMIT) return finish("time_limit", note);
        if (inner == SolveStatus::STOPPED_BY_MONITOR) return finish("stopped_by_monitor", note);
        error = fclib_relative_error(p, run.r);
        if (!std::isfinite(error)) return finish("diverged", note);
        if (error < 0.99 * best) {
            best = error;
            since_best = 0;
        } else {
            ++since_best;
        }
    }
}

FrictionRun mprgp_ica_friction(const FrictionLocal& p, const MprgpIcaFrictionSettings& s)
{
    const Eigen::Index m = p.contacts();
    const std::vector<Eigen::Index> normals = normal_rows(m);
    Qp qp;
    const SpMat W_nn = principal_submatrix(p.W, normals);
    const double skew = asymmetry(W_nn);
    qp.A = skew > 0.0 ? symmetric_part(W_nn) : W_nn;
    const bool symmetrised = skew > ROUNDING_ASYMMETRY;
    qp.b = Vec(m);
    for (Eigen::Index i = 0; i < m; ++i) qp.b[i] = -p.q[3 * i];
    qp.J = SpMat(m, m);
    qp.J.setIdentity();
    qp.c = Vec::Zero(m);
    qp.x0 = Vec::Zero(m);
    MprgpBoxSettings box;
    box.common.stop = StopRule::NATIVE;
    box.common.tol = s.normal_tol * std::max(qp.b.norm(), 1e-300);
    box.common.max_iterations = s.max_mprgp;
    box.common.time_limit_s = s.time_limit_s;
    const SolverResult normal = mprgp_box_solve(qp.view(), box, {});
    Vec start = Vec::Zero(3 * m);
    if (normal.x.size() == m && normal.x.allFinite())
        for (Eigen::Index i = 0; i < m; ++i) start[3 * i] = std::max(normal.x[i], 0.0);
    FrictionNsgsSettings ns;
    ns.tol = s.tol;
    ns.max_iterations = s.max_sweeps;
    ns.time_limit_s = s.time_limit_s;
    ns.start = &start;
    FrictionRun run = friction_nsgs(p, ns);
    run.solver = "mprgp+ica-friction";
    run.seconds += normal.setup_s + normal.solve_s;
    run.note = "mprgp-box on W_NN" + std::string(symmetrised ? " (symmetrised)" : "") + ": " +
               to_string(normal.status) + ", " + std::to_string(normal.counters.iterations) +
               " iterations; then nsgs from (r_n, 0): " + std::to_string(run.iterations) + " sweeps";
    return run;
}

}  // namespace cb
