// `mprgp-coupled`: extended MPRGP with general J (ALGORITHMS.md §4).
// Ref: Li et al., "Deformable Objects Collision Handling with Fast Convergence", CGF 2015,
//      eq. (15)-(16) free gradient, (17)-(18) chopped gradient, (19)-(20) projection, Alg. 3.
// Not a hot path: written for clarity; every subproblem is on CHOLMOD.
#include "solvers/mprgp_coupled.hpp"
#include "solvers/solve_loop.hpp"

#include "solvers/a_product.hpp"
#include "solvers/accuracy.hpp"
#include "solvers/mprgp_kernels.hpp"
#include "solvers/work_units.hpp"

#include <Eigen/CholmodSupport>
#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <sstream>

namespace cb {

namespace {

/// Every setting of `mprgp-coupled`, declared once (settings.hpp SettingsTable).
const SettingsTable<MprgpCoupledSettings>& mprgp_coupled_settings_table()
{
    static const SettingsTable<MprgpCoupledSettings> table =
        SettingsTable<MprgpCoupledSettings>()
            .number("gamma", &MprgpCoupledSettings::gamma, 0.0, 1e300, "proportioning constant Gamma > 0")
            .choice("precond", &MprgpCoupledSettings::precond, {"none", "jacobi"},
                    "none (the authors' Fig. 6 setting) | jacobi (D-weighted face projection, J_A D^-1 J_A' solve)")
            .integer("power_max", &MprgpCoupledSettings::power_max, 1, 1000000, "max power-method products")
            .integer("lcp_max_pivots", &MprgpCoupledSettings::lcp_max_pivots, 1, 100000000,
                     "block principal pivoting iterations per LCP before the PGS fallback")
            .integer("pgs_max_sweeps", &MprgpCoupledSettings::pgs_max_sweeps, 1, 100000000,
                     "PGS fallback sweeps per LCP")
            .integer("safeguard_max", &MprgpCoupledSettings::safeguard_max, 1, 100000000,
                     "max repeats of Alg. 3's safeguard after one step");
    return table;
}

}  // namespace

MprgpCoupledSettings MprgpCoupledSettings::from_json(const nlohmann::json& settings)
{
    SettingsReader reader(settings, "mprgp-coupled");
    MprgpCoupledSettings s;
    s.common = reader.common();
    mprgp_coupled_settings_table().read(reader, s);
    reader.finish();
    return s;
}

nlohmann::json MprgpCoupledSettings::to_json() const
{
    nlohmann::json j = common.to_json();
    mprgp_coupled_settings_table().write(*this, j);
    return j;
}

std::vector<SettingDoc> mprgp_coupled_setting_docs() { return mprgp_coupled_settings_table().docs(); }

SolverEntry mprgp_coupled_entry()
{
    SolverEntry entry;
    entry.make = [](const nlohmann::json& settings) -> std::unique_ptr<Solver> {
        return std::make_unique<MprgpCoupledSolver>(MprgpCoupledSettings::from_json(settings));
    };
    entry.description = "extended MPRGP with general (coupled) J: CHOLMOD subproblems, LCPs by principal pivoting";
    entry.settings = mprgp_coupled_setting_docs();
    return entry;
}

namespace {

using Cholmod = Eigen::CholmodDecomposition<SpMatCol, Eigen::Lower>;

std::string fmt(double v)
{
    std::ostringstream s;
    s.precision(3);
    s << std::scientific << v;
    return s.str();
}

/// The principal submatrix M(idx, idx).
SpMatCol submatrix(const SpMatCol& M, const std::vector<int>& idx)
{
    std::vector<int> local(static_cast<size_t>(M.rows()), -1);
    for (size_t k = 0; k < idx.size(); ++k) local[static_cast<size_t>(idx[k])] = static_cast<int>(k);
    std::vector<Triplet> t;
    for (size_t k = 0; k < idx.size(); ++k)
        for (SpMatCol::InnerIterator it(M, idx[k]); it; ++it)
            if (local[static_cast<size_t>(it.row())] >= 0)
                t.emplace_back(local[static_cast<size_t>(it.row())], static_cast<int>(k), it.value());
    SpMatCol S(static_cast<Eigen::Index>(idx.size()), static_cast<Eigen::Index>(idx.size()));
    S.setFromTriplets(t.begin(), t.end());
    return S;
}

/// A CHOLMOD factor of a (shifted) SPD Gram matrix, symmetrically scaled to unit diagonal
/// first so that the shift 1e-12 is relative to each row's own norm (rows scaled by 1e-3 and
/// 1e3 in one J must not be regularised away); the shift keeps dependent rows solvable (the
/// solve then splits their multiplier).
struct Factor {
    std::unique_ptr<Cholmod> chol;
    Vec scale;  ///< 1 / sqrt(diag)
    bool ok = false;
    bool compute(const SpMatCol& S, Counters& cnt)
    {
        chol = std::make_unique<Cholmod>();
        scale.resize(S.rows());
        for (Eigen::Index i = 0; i < S.rows(); ++i) {
            const double d = S.coeff(i, i);
            scale[i] = d > 0.0 ? 1.0 / std::sqrt(d) : 1.0;
        }
        const SpMatCol scaled = SpMatCol(scale.asDiagonal() * S * scale.asDiagonal());
        chol->setShift(1e-12);
        chol->compute(scaled);
        ++cnt.cholmod_analyses;
        ++cnt.cholmod_factorizations;
        cnt.work_flops += cholmod_factor_flops(chol->cholmod());
        ok = chol->info() == Eigen::Success;
        return ok;
    }
    Vec solve(const Vec& rhs, Counters& cnt)
    {
        ++cnt.cholmod_solves;
        cnt.work_flops += cholmod_solve_flops(chol->cholmod());
        return scale.cwiseProduct(Vec(chol->solve(Vec(scale.cwiseProduct(rhs)))));
    }
};

/// Solves 0 <= lambda  perp  M lambda - q >= 0 (M SPD up to the shift) by block principal
/// pivoting (Judice-Pires, Murty's single pivot when the infeasible count stops dropping),
/// warm-started from `set` (in/out); falls back to projected Gauss-Seidel.
/// @return false when neither method met the tolerance.
bool solve_lcp(const SpMatCol& M, const Vec& q, std::vector<char>& set, Vec& lambda, Counters& cnt, long max_pivots,
               long max_sweeps, long& pgs_fallbacks)
{
    const Eigen::Index k = q.size();
    lambda = Vec::Zero(k);
    if (k == 0) return true;
    if (static_cast<Eigen::Index>(set.size()) != k) set.assign(static_cast<size_t>(k), 0);
    const double tol_w = 1e-12 * std::max(1.0, q.lpNorm<Eigen::Infinity>());
    long best = std::numeric_limits<long>::max();
    int chances = 3;
    for (long it = 0; it < max_pivots; ++it) {
        std::vector<int> idx;
        for (Eigen::Index i = 0; i < k; ++i)
            if (set[static_cast<size_t>(i)]) idx.push_back(static_cast<int>(i));
        lambda.setZero();
        if (!idx.empty()) {
            Factor f;
            if (!f.compute(submatrix(M, idx), cnt)) break;
            Vec rhs(static_cast<Eigen::Index>(idx.size()));
            for (size_t r = 0; r < idx.size(); ++r) rhs[static_cast<Eigen::Index>(r)] = q[idx[r]];
            const Vec sol = f.solve(rhs, cnt);
            for (size_t r = 0; r < idx.size(); ++r) lambda[idx[r]] = sol[static_cast<Eigen::Index>(r)];
        }
        ++cnt.lcp_iterations;
        const Vec w = M * lambda - q;
        cnt.work_flops += sparse_product_flops(static_cast<double>(M.nonZeros()));
        const double tol_l = 1e-12 * std::max(1e-300, lambda.lpNorm<Eigen::Infinity>());
        std::vector<int> bad;
        for (Eigen::Index i = 0; i < k; ++i) {
            if (set[static_cast<size_t>(i)] ? lambda[i] < -tol_l : w[i] < -tol_w) bad.push_back(static_cast<int>(i));
        }
        if (bad.empty()) {
            for (Eigen::Index i = 0; i < k; ++i) lambda[i] = std::max(0.0, lambda[i]);
            return true;
        }
        const long count = static_cast<long>(bad.size());
        if (count < best) {
            best = count;
            chances = 3;
            for (int i : bad) set[static_cast<size_t>(i)] ^= 1;
        } else if (chances > 0) {
            --chances;
            for (int i : bad) set[static_cast<size_t>(i)] ^= 1;
        } else {
            set[static_cast<size_t>(bad.back())] ^= 1;  // Murty: finite for P-matrices
        }
    }
    // Projected Gauss-Seidel fallback.
    ++pgs_fallbacks;
    lambda = lambda.cwiseMax(0.0);
    Vec diag = M.diagonal();
    for (long sweep = 0; sweep < max_sweeps; ++sweep) {
        double change = 0.0;
        for (Eigen::Index i = 0; i < k; ++i) {
            if (!(diag[i] > 0.0)) continue;
            double mi = 0.0;
            for (SpMatCol::InnerIterator it(M, i); it; ++it) mi += it.value() * lambda[it.row()];  // symmetric
            const double next = std::max(0.0, lambda[i] - (mi - q[i]) / diag[i]);
            change = std::max(change, std::abs(next - lambda[i]));
            lambda[i] = next;
        }
        ++cnt.pgs_sweeps;
        ++cnt.lcp_iterations;
        cnt.work_flops += sparse_product_flops(static_cast<double>(M.nonZeros()));
        if (change <= 1e-14 * std::max(1.0, lambda.lpNorm<Eigen::Infinity>())) break;
    }
    const Vec w = M * lambda - q;
    for (Eigen::Index i = 0; i < k; ++i) set[static_cast<size_t>(i)] = lambda[i] > 0.0;
    return w.minCoeff() >= -1e-8 * std::max(1.0, q.lpNorm<Eigen::Infinity>());
}

}  // namespace

SolverResult MprgpCoupledSolver::solve(const QpView& qp, const SolveContext& context)
{
    const MprgpCoupledSettings& st = m_settings;
    const CommonSettings& common = st.common;
    const SpMat& A = qp.A;
    const SpMat& J = qp.J;
    const Eigen::Index n = qp.n(), m = qp.m();
    SolverResult result;
    Counters cnt;
    SolveLoop loop("mprgp-coupled", qp, common, context);
    result.x = qp.x0;
    result.lambda = Vec::Zero(m);
    Vec dinv = Vec::Ones(n);
    if (st.precond == "jacobi") {
        const Vec diag = A.diagonal();
        if (!(diag.minCoeff() > 0.0)) {
            result.status = SolveStatus::INVALID_INPUT;
            result.message = "mprgp-coupled: precond=jacobi needs a positive diagonal of A";
            return loop.finish(result, result.status);
        }
        dinv = diag.cwiseInverse();
    }
    const SpMatCol Jt = SpMatCol(J.transpose());
    const SpMatCol gram = SpMatCol(J * J.transpose());                        // J J'
    const SpMatCol gram_d = SpMatCol(J * dinv.asDiagonal() * J.transpose());  // J D^-1 J'
    for (Eigen::Index i = 0; i < m; ++i)
        if (!(gram.coeff(i, i) > 0.0) && qp.c[i] > active_tolerance(qp.c[i])) {
            result.status = SolveStatus::INFEASIBLE;
            result.message = "mprgp-coupled: row " + std::to_string(i) + " is zero but c > 0: empty feasible set";
            return loop.finish(result, result.status);
        }
    Vec eigenvector;
    const bool warm = context.eigenvector && context.eigenvector->size() == n;
    if (warm) eigenvector = *context.eigenvector;
    const PowerResult power =
        power_method(A, eigenvector, PowerRule::POWER, st.power_max, common.tol, warm, common.seed);
    if (context.eigenvector) *context.eigenvector = eigenvector;
    cnt.power_products = power.products;
    cnt.a_products += power.products;
    const double alpha_bar = power.estimate > 0.0 ? 2.0 / (1.01 * power.estimate) : 1.0;
    const AccuracyScale scale = accuracy_scale(qp);
    cnt.a_products += scale.a_products;
    if (!loop.end_setup()) return loop.finish(result, SolveStatus::TIME_LIMIT, "", loop.time_limit_message());

    long pgs_fallbacks = 0, lcp_failures = 0, face_factorizations = 0;
    std::vector<char> proj_set;
    // P(v): the projection LCP (eq. 20) over all rows, warm-started.
    auto project = [&](Vec& v) -> bool {
        ++cnt.projections;
        const Vec q = qp.c - J * v;
        if (m == 0 || q.maxCoeff() <= 0.0) return false;
        Vec lambda;
        if (!solve_lcp(gram, q, proj_set, lambda, cnt, st.lcp_max_pivots, st.pgs_max_sweeps, pgs_fallbacks))
            ++lcp_failures;
        v += Jt * lambda;
        return true;
    };
    // Translation invariance: positions enter only as differences from a reference point
    // x_ref = P(x0), whose gradient g_ref = A x_ref - b is formed once. F(v) - F(x_ref) and
    // g(v) = A (v - x_ref) + g_ref then carry rounding errors relative to |A||v - x_ref|,
    // not to |A||v|: a problem translated by 100 m gives the same F decreases, where
    // 1/2 v'Av - b'v would bury them under rounding of its huge absolute value (the
    // monotonicity tests then reject every CG step and the chain degenerates into expansions).
    Vec x_ref, g_ref;
    auto F = [&](const Vec& v) {
        ++cnt.a_products;
        const Vec u = v - x_ref;
        return 0.5 * u.dot(a_product(A, u)) + g_ref.dot(u);
    };
    auto gradient = [&](const Vec& v) {
        ++cnt.a_products;
        return Vec(a_product(A, Vec(v - x_ref)) + g_ref);
    };

    // Face data, refactored only when the active set changes.
    std::vector<int> face;
    std::vector<char> active(static_cast<size_t>(m), 0), beta_set;
    Factor face_factor, face_factor_d;
    SpMat JA;
    auto set_face = [&](const Vec& v) {
        const Vec slack = J * v - qp.c;
        std::vector<int> next;
        for (Eigen::Index i = 0; i < m; ++i)
            if (std::abs(slack[i]) <= active_tolerance(qp.c[i]) && gram.coeff(i, i) > 0.0)
                next.push_back(static_cast<int>(i));
        if (next == face && (face.empty() || face_factor.ok)) return;
        if (next != face) ++cnt.pivots;  // an active-set change
        face = next;
        std::fill(active.begin(), active.end(), 0);
        for (int i : face) active[static_cast<size_t>(i)] = 1;
        std::vector<Triplet> t;
        for (size_t r = 0; r < face.size(); ++r)
            for (SpMat::InnerIterator it(J, face[r]); it; ++it)
                t.emplace_back(static_cast<int>(r), static_cast<int>(it.col()), it.value());
        JA.resize(static_cast<Eigen::Index>(face.size()), n);
        JA.setFromTriplets(t.begin(), t.end());
        beta_set.assign(face.size(), 0);
        if (!face.empty()) {
            face_factor.compute(submatrix(gram, face), cnt);
            if (st.precond == "jacobi") face_factor_d.compute(submatrix(gram_d, face), cnt);
            ++face_factorizations;
        }
    };
    // phi = g - J_A' (J_A J_A')^-1 J_A g  (eq. 15-16)
    auto free_grad = [&](const Vec& g) -> Vec {
        if (face.empty()) return g;
        return g - JA.transpose() * face_factor.solve(JA * g, cnt);
    };
    // z = D^-1 g - D^-1 J_A' (J_A D^-1 J_A')^-1 J_A D^-1 g: J_A z = 0.
    auto precondition = [&](const Vec& g, const Vec& phi) -> Vec {
        ++cnt.precond_applications;
        if (st.precond != "jacobi") return phi;
        const Vec dg = dinv.cwiseProduct(g);
        if (face.empty()) return dg;
        return dg - dinv.cwiseProduct(Vec(JA.transpose() * face_factor_d.solve(JA * dg, cnt)));
    };
    // beta = g_b - J_A' mu, 0 <= mu perp J_A J_A' mu - J_A g_b >= 0 (eq. 17-18); mu = multipliers.
    auto chopped = [&](const Vec& g, const Vec& phi, Vec& mu) -> Vec {
        const Vec gb = g - phi;
        if (face.empty()) {
            mu.resize(0);
            return Vec::Zero(n);
        }
        const SpMatCol MA = submatrix(gram, face);
        if (!solve_lcp(MA, Vec(JA * gb), beta_set, mu, cnt, st.lcp_max_pivots, st.pgs_max_sweeps, pgs_fallbacks))
            ++lcp_failures;
        return gb - JA.transpose() * mu;
    };
    auto safeguard = [&](Vec& x, Vec& g, double f_before, double& f_now) {
        long repeats = 0;
        while (f_now > f_before + 1e-12 * (std::abs(f_before) + std::abs(f_now)) && repeats < st.safeguard_max) {
            x -= alpha_bar * g;
            project(x);
            g = gradient(x);
            f_now = F(x);
            ++cnt.safeguard_steps;
            ++repeats;
            if (loop.time_up()) break;
        }
    };

    Vec x = qp.x0;
    project(x);
    x_ref = x;
    g_ref = a_product(A, x) - qp.b;
    ++cnt.a_products;
    Vec g = g_ref;
    set_face(x);
    Vec phi = free_grad(g), z = precondition(g, phi), p = z, mu, beta, lambda = Vec::Zero(m);
    double f_proj_x = F(x);
    bool x_feasible = true;
    const bool native = common.stop == StopRule::NATIVE;
    SolveStatus status = SolveStatus::MAX_ITERATIONS;
    std::string why = "iteration cap " + std::to_string(common.max_iterations) + " reached";
    StepKind last = StepKind::START;
    double native_residual = 0.0, error = 0.0;
    auto restart = [&]() {
        set_face(x);
        phi = free_grad(g);
        z = precondition(g, phi);
        p = z;
        f_proj_x = F(x);
        x_feasible = true;
    };
    while (true) {
        beta = chopped(g, phi, mu);
        lambda.setZero();
        for (size_t r = 0; r < face.size(); ++r) lambda[face[r]] = mu[static_cast<Eigen::Index>(r)];
        native_residual = (phi + beta).norm();
        error = accuracy_from_gradient(qp, scale, x, g, lambda).max();
        bool converged = x_feasible && (native ? native_residual <= common.tol : error <= common.tol);
        IterationInfo info;
        info.iteration = cnt.iterations;
        info.step = last;
        info.x = &x;
        info.lambda = &lambda;
        info.native_residual = native_residual;
        info.active_set_size = static_cast<long>(face.size());
        info.counters = &cnt;
        if (!loop.notify(info)) {
            status = SolveStatus::STOPPED_BY_MONITOR;
            why = "the monitor asked to stop";
            break;
        }
        // The exit checks in the loop's order (a non-finite residual never counts as converged).
        status = loop.exit_status(std::isfinite(native_residual), converged, cnt.iterations);
        if (status != SolveStatus::NOT_RUN) {
            if (status == SolveStatus::DIVERGED) why = "non-finite gradient";
            if (status == SolveStatus::TIME_LIMIT) why = loop.time_limit_reason();
            break;
        }
        ++cnt.iterations;
        // phitilde'phi through one projection (eq. 13).
        Vec trial = x - alpha_bar * phi;
        project(trial);
        const double phitilde_phi = (x - trial).dot(phi) / alpha_bar;
        // An infeasible chain iterate whose face problem is solved cannot improve along the face.
        // (The face residual phi measured like the stationarity part of the accuracy error.)
        const bool face_done =
            !x_feasible &&
            (native ? phi.norm() <= common.tol
                    : phi.cwiseProduct(scale.inv_diag).lpNorm<Eigen::Infinity>() * scale.inv_length <= common.tol);
        const bool proportional = !face_done && beta.squaredNorm() <= st.gamma * st.gamma * phitilde_phi;
        bool do_expansion = false;
        if (proportional) {
            const Vec Ap = a_product(A, p);
            ++cnt.a_products;
            const double pap = p.dot(Ap);
            if (!(pap > 0.0)) {
                status = pap == 0.0 ? SolveStatus::STALLED : SolveStatus::DIVERGED;
                why = "p'Ap <= 0";
                break;
            }
            const double alpha = z.dot(phi) / pap;  // z'g = z'phi (z in null(J_A)), without cancellation
            Vec y = x - alpha * p;
            Vec py = y;
            const bool moved = project(py);
            const double f_proj_y = F(py);
            if (moved ? f_proj_y < f_proj_x : f_proj_y <= f_proj_x) {
                x = y;
                g -= alpha * Ap;
                phi = free_grad(g);
                z = precondition(g, phi);
                p = z - (z.dot(Ap) / pap) * p;
                f_proj_x = f_proj_y;
                x_feasible = !moved;
                ++cnt.cg_steps;
                last = StepKind::CG;
                continue;
            }
            do_expansion = true;
        } else if (!x_feasible) {
            do_expansion = true;
        }
        double f_before = f_proj_x, f_now = 0.0;
        if (do_expansion) {
            if (project(x)) g = gradient(x);  // y = P(x)
            set_face(x);
            x -= alpha_bar * free_grad(g);
            project(x);
            g = gradient(x);
            f_now = F(x);
            ++cnt.expansion_steps;
            last = StepKind::EXPANSION;
        } else {
            const Vec Ad = a_product(A, beta);
            ++cnt.a_products;
            const double dad = beta.dot(Ad);
            if (!(dad > 0.0)) {
                status = SolveStatus::STALLED;
                why = "beta'A beta <= 0";
                break;
            }
            x -= (g.dot(beta) / dad) * beta;
            project(x);  // -beta may leave the set when rows are coupled (Sec. 4.4)
            g = gradient(x);
            f_now = F(x);
            ++cnt.proportioning_steps;
            last = StepKind::PROPORTIONING;
        }
        safeguard(x, g, f_before, f_now);
        restart();
    }
    // Confirm at the exact gradient: the recurrence g -= alpha Ap drifts, and on ill-conditioned
    // problems the drift alone can fake convergence (stress case tiny-h2K). One more A-product.
    project(x);
    g = gradient(x);
    restart();
    beta = chopped(g, phi, mu);
    lambda.setZero();
    for (size_t r = 0; r < face.size(); ++r) lambda[face[r]] = mu[static_cast<Eigen::Index>(r)];
    native_residual = (phi + beta).norm();
    error = accuracy_from_gradient(qp, scale, x, g, lambda).max();
    if (status == SolveStatus::CONVERGED && !(native ? native_residual <= common.tol : error <= common.tol)) {
        status = SolveStatus::STALLED;
        why = "the criterion held on the updated gradient but not at the exact gradient (rounding drift)";
    }
    result.x = x;
    result.lambda = lambda;
    result.counters = cnt;
    result.native_residual = native_residual;
    result.info = {{"alpha_bar", alpha_bar},
                   {"power", {{"products", power.products}, {"estimate", power.estimate}, {"warm_start", power.warm}}},
                   {"precond", st.precond},
                   {"face_factorizations", face_factorizations},
                   {"pgs_fallbacks", pgs_fallbacks},
                   {"lcp_failures", lcp_failures},
                   {"safeguard_firings", cnt.safeguard_steps},
                   {"dependent_rows", "handled by a shift 1e-12 of the unit-diagonal-scaled J_A J_A' and J J'"}};
    if (status == SolveStatus::CONVERGED) {
        result.message =
            "converged: " +
            std::string(native ? "||phi+beta||_2 = " + fmt(native_residual) : "accuracy error = " + fmt(error)) +
            " <= tol; safeguard firings " + std::to_string(cnt.safeguard_steps);
    } else {
        result.message = "not converged: " + why + " (accuracy error " + fmt(error) + ")";
    }
    if (lcp_failures > 0) result.message += "; " + std::to_string(lcp_failures) + " LCP solves missed their tolerance";
    return loop.finish(result, status, status == SolveStatus::CONVERGED ? (native ? "native" : "kkt") : "");
}

}  // namespace cb
