// `mprgp+bmf03` (see mprgp_bmf03.hpp).
#include "solvers/friction/mprgp_bmf03.hpp"

#include "solvers/core/solve_loop.hpp"
#include "solvers/core/stopwatch.hpp"
#include "solvers/linalg/a_product.hpp"
#include "solvers/measure/friction_snapshot_error.hpp"
#include "solvers/measure/work_units.hpp"
#include "solvers/mprgp/mprgp_coupled.hpp"

#include <Eigen/CholmodSupport>
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <map>
#include <sstream>

namespace cb {

namespace {

const char* const BMF03_NAME = "mprgp+bmf03";

const SettingsTable<MprgpBmf03Settings>& mprgp_bmf03_settings_table()
{
    static const SettingsTable<MprgpBmf03Settings> table;  // the common block only
    return table;
}

/// The inner solver's words under this solver's name (its standard reasons apply unchanged).
void rename_message(SolverResult& result)
{
    const std::string inner = "mprgp-coupled: ";
    if (result.message.rfind(inner, 0) == 0)
        result.message = std::string(BMF03_NAME) + ": " + result.message.substr(inner.size());
    else if (!result.message.empty())
        result.message = std::string(BMF03_NAME) + ": " + result.message;
}

}  // namespace

MprgpBmf03Settings MprgpBmf03Settings::from_json(const nlohmann::json& settings)
{
    return read_settings(settings, BMF03_NAME, mprgp_bmf03_settings_table());
}

nlohmann::json MprgpBmf03Settings::to_json() const { return write_settings(*this, mprgp_bmf03_settings_table()); }

Bmf03Update bmf03_update(const QpView& qp, const Vec& x_star, const Vec& lambda_n, const Vec& x_free)
{
    const Eigen::Index m = qp.m();
    const Friction& f = *qp.friction;
    Vec c_all;
    const SpMat H = contact_frame_rows(qp, &c_all);  // rows 3i, 3i+1, 3i+2: J_i, T_2i, T_2i+1
    const Vec d = qp.A.diagonal();
    Bmf03Update up;
    up.x = x_star;
    up.lambda = lambda_n;
    up.lambda_t = Vec::Zero(2 * m);
    for (Eigen::Index i = 0; i < m; ++i) {
        if (!(lambda_n[i] > 0.0) || !(f.mu[i] > 0.0)) {
            ++up.free;
            continue;
        }
        // The contact's three rows on the unknowns they touch (the same for the three: one frame).
        std::map<Eigen::Index, Eigen::Vector3d> cols;
        for (int a = 0; a < 3; ++a)
            for (SpMat::InnerIterator it(H, 3 * i + a); it; ++it) {
                auto [pos, fresh] = cols.try_emplace(it.col(), Eigen::Vector3d::Zero());
                pos->second[a] = it.value();
            }
        Eigen::Vector2d u_t = Eigen::Vector2d(-c_all[3 * i + 1], -c_all[3 * i + 2]);
        double d_n = 0.0;  // h dv_N: the normal displacement the contact solve added to x_free
        for (const auto& [col, w] : cols) {
            u_t += w.tail<2>() * up.x[col];
            d_n += w[0] * (x_star[col] - x_free[col]);
        }
        d_n = std::max(d_n, 0.0);
        const double slip = u_t.norm();
        const double scale = slip > 0.0 ? std::max(0.0, 1.0 - f.mu[i] * d_n / slip) : 0.0;
        if (scale == 0.0)
            ++up.sticking;
        else
            ++up.sliding;
        if (slip == 0.0) continue;
        // The impulse p (3 components in the contact's frame) whose response D^-1 H_i' p changes
        // the slip by (scale - 1) u_t and the normal displacement by 0.
        Eigen::Matrix3d G = Eigen::Matrix3d::Zero();
        for (const auto& [col, w] : cols) G += w * w.transpose() / d[col];
        const Eigen::Vector3d target(0.0, (scale - 1.0) * u_t[0], (scale - 1.0) * u_t[1]);
        const Eigen::Vector3d p = G.ldlt().solve(target);
        if (!p.allFinite()) continue;  // a degenerate frame (zero rows): nothing to move
        for (const auto& [col, w] : cols) up.x[col] += w.dot(p) / d[col];
        up.lambda[i] += p[0];
        up.lambda_t[2 * i] = p[1];
        up.lambda_t[2 * i + 1] = p[2];
    }
    return up;
}

SolverResult MprgpBmf03Solver::solve(const QpView& qp, const SolveContext& context)
{
    const CommonSettings& common = m_settings.common;
    const bool frictional = qp.frictional();
    if (frictional) {
        const Friction& f = *qp.friction;
        std::string missing;
        if (!(f.h > 0.0)) missing = "no time step h";
        if (f.v0.size() != qp.n()) missing += std::string(missing.empty() ? "" : " and ") + "no start velocities v0";
        if (f.T.rows() != 2 * qp.m() || f.T.cols() != qp.n() || f.mu.size() != qp.m())
            missing += std::string(missing.empty() ? "" : " and ") + "no tangent rows for every contact";
        if (!missing.empty()) {
            SolverResult result;
            SolveLoop loop(BMF03_NAME, qp, common, context);
            return loop.finish(result, SolveStatus::NOT_APPLICABLE,
                               std::string(BMF03_NAME) +
                                   ": a velocity update needs a simulator's frictional step (qpsnap version 2 "
                                   "with h and v0); this problem has " +
                                   missing);
        }
    }

    // Stage 1: the frictionless QP, exactly (friction fields hidden from mprgp-coupled).
    const QpView frictionless{qp.A, qp.b, qp.J, qp.c, qp.x0, qp.length, nullptr, qp.a_symmetric};
    SolverResult result = mprgp_coupled_solve(frictionless, MprgpCoupledSettings::from_json(common.to_json()), context);
    rename_message(result);
    result.info["frictionless_stage"] = {
        {"solver", "mprgp-coupled"}, {"status", to_string(result.status)}, {"iterations", result.iterations}};
    if (!frictional) return result;  // no friction: mprgp-coupled's solve is the answer
    if (result.status != SolveStatus::CONVERGED) {
        result.message += "; the frictionless stage did not converge: no friction update";
        result.lambda_t = Vec::Zero(2 * qp.m());
        return result;
    }

    // Stage 2: x_free = A^-1 b, the update, and the verdict on the frictional problem.
    Stopwatch watch;
    watch.start();
    Counters counters = result.counters;
    SolveLoop loop(BMF03_NAME, qp, common, SolveContext{});  // the verdict and its message (no monitor here)
    loop.end_setup();
    Eigen::CholmodSupernodalLLT<SpMatCol, Eigen::Lower> llt;
    {
        const SpMatCol A_col = qp.A;
        llt.compute(A_col);
    }
    ++counters.cholmod_analyses;
    ++counters.cholmod_factorizations;
    counters.work_flops += cholmod_factor_flops(llt.cholmod());
    if (llt.info() != Eigen::Success) {
        result.counters = counters;
        return loop.finish(result, SolveStatus::INVALID_INPUT,
                           std::string(BMF03_NAME) + ": CHOLMOD could not factor A (x_free = A^-1 b gives dv_N)");
    }
    const Vec x_free = llt.solve(qp.b);
    ++counters.cholmod_solves;
    counters.work_flops += cholmod_solve_flops(llt.cholmod());
    const Bmf03Update up = bmf03_update(qp, result.x, result.lambda, x_free);

    Vec c_all;
    const SpMat H = contact_frame_rows(qp, &c_all);
    const double norm_q = (H * x_free - c_all).norm();
    const double fclib = friction_snapshot_error(qp, up.x, up.lambda, up.lambda_t, norm_q);
    const AccuracyScale scale = accuracy_scale(qp);
    const Vec g = qp.A * up.x - qp.b;
    counters.a_products += scale.a_products + 1;
    const double e = accuracy_from_gradient(qp, scale, up.x, g, up.lambda, &up.lambda_t).max();
    const SolveStatus status = loop.verdict(up.x.allFinite(), fclib, e);

    const double inner_setup = result.setup_s, inner_solve = result.solve_s;
    result.x = up.x;
    result.lambda = up.lambda;
    result.lambda_t = up.lambda_t;
    result.native_residual = fclib;
    result.counters = counters;
    result.info["native_residual_definition"] =
        "FCLIB's relative natural-map error of the snapshot's local problem at the updated point";
    result.info["contacts"] = {{"sticking", up.sticking}, {"sliding", up.sliding}, {"free", up.free}};
    std::ostringstream detail;
    detail << "one BMF03 velocity update after mprgp-coupled (" << result.iterations << " iterations): " << up.sticking
           << " contacts sticking, " << up.sliding << " sliding, " << up.free << " free; frictional e " << e
           << ", FCLIB error " << fclib;
    SolverResult out = loop.finish(result, status, detail.str());
    watch.pause();
    out.setup_s = inner_setup;
    out.solve_s = inner_solve + watch.seconds();
    return out;
}

SolverEntry mprgp_bmf03_entry()
{
    return solver_entry<MprgpBmf03Solver>(
        BMF03_NAME, mprgp_bmf03_settings_table(),
        "mprgp-coupled on the frictionless QP, then one Coulomb velocity update per contact (BMF03; a baseline)",
        "any J; with friction only a simulator's frictional step (h and v0 given), else not_applicable");
}

}  // namespace cb
