// `mprgp-coupled`: extended MPRGP with general J (ALGORITHMS.md §4).
// Ref: Li et al., "Deformable Objects Collision Handling with Fast Convergence", CGF 2015,
//      eq. (15)-(16) free gradient, (17)-(18) chopped gradient, (19)-(20) projection, Alg. 3.
// The operators split over the components of J's row graph (solvers/coupled_face_operators.*);
// the steps, the proportioning test and the CG direction stay global. F(P(y)) is formed in
// difference form from scalar recurrences plus the sparse correction J'lambda of the projection,
// so a CG step costs one A-product, as in `mprgp` (objective=cheap).
#include "solvers/mprgp_coupled.hpp"
#include "solvers/solve_loop.hpp"

#include "solvers/a_product.hpp"
#include "solvers/accuracy.hpp"
#include "solvers/accuracy_rows.hpp"
#include "solvers/coupled_face_operators.hpp"
#include "solvers/coupled_preconditioner.hpp"
#include "solvers/format_number.hpp"
#include "solvers/mprgp_kernels.hpp"
#include "solvers/row_components.hpp"
#include "solvers/work_units.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <optional>
#include <sstream>

namespace cb {

namespace {

/// Every setting of `mprgp-coupled`, declared once (settings.hpp SettingsTable).
const SettingsTable<MprgpCoupledSettings>& mprgp_coupled_settings_table()
{
    static const SettingsTable<MprgpCoupledSettings> table =
        SettingsTable<MprgpCoupledSettings>()
            .number("gamma", &MprgpCoupledSettings::gamma, 0.0, 1e300, "proportioning constant Gamma > 0")
            .choice("precond", &MprgpCoupledSettings::precond, {"auto", "none", "jacobi", "ichol", "scaled"},
                    "auto: scaled when a component of J's row graph has more than dense_max_rows rows (CHOLMOD "
                    "face factors, where jacobi's second factor and solve per CG step cost most) and deflation = "
                    "none, else jacobi; the record's info.precond names the one used | "
                    "none (the authors' Fig. 6 setting) | jacobi (D-weighted face projection, J_A D^-1 J_A' solve) | "
                    "ichol: Q M^-1 Q g, M the incomplete Cholesky factor of A (once), Q the per-component face "
                    "projector (docs/preconditioners.md) | scaled: Jacobi as a change of variables, MPRGP on y = "
                    "D^1/2 x (A -> D^-1/2 A D^-1/2, J -> J D^-1/2), one face factor instead of two; judged on the "
                    "original QP")
            .choice(
                "deflation", &MprgpCoupledSettings::deflation, {"none", "rigid"},
                "none | rigid: the slow rigid modes of each body, projected on each new face (E = V'AV per body), "
                "balance the preconditioner, and a Galerkin step over them follows the start, each expansion and "
                "each proportioning step; default rigid with precond = ichol (docs/preconditioners.md)",
                // As for `mprgp`: ichol alone hits the iteration cap on the stiff dino (stress case
                // dino-stiff-1e10, tol 1e-8), ichol with the rigid modes converges in 746 iterations.
                [](const MprgpCoupledSettings& s) { return s.precond == "ichol" ? std::string("rigid") : s.deflation; })
            .integer("power_max", &MprgpCoupledSettings::power_max, 1, 1000000, "max power-method products")
            .integer("lcp_max_pivots", &MprgpCoupledSettings::lcp_max_pivots, 1, 100000000,
                     "block principal pivoting iterations per LCP before the PGS fallback")
            .integer("pgs_max_sweeps", &MprgpCoupledSettings::pgs_max_sweeps, 1, 100000000,
                     "PGS fallback sweeps per LCP")
            .integer("safeguard_max", &MprgpCoupledSettings::safeguard_max, 1, 100000000,
                     "max repeats of Alg. 3's safeguard after one step")
            .choice("operators", &MprgpCoupledSettings::operators, {"components", "global"},
                    "components: one small problem per component of J's row graph (dense factors per face) | "
                    "global: one CHOLMOD problem over all rows (the reference)")
            .integer("dense_max_rows", &MprgpCoupledSettings::dense_max_rows, 1, 100000000,
                     "operators = components: largest component with dense factors; larger ones use CHOLMOD")
            .integer("sparse_max_updates", &MprgpCoupledSettings::sparse_max_updates, 1, 100000000,
                     "operators = components, components above dense_max_rows: a face or LCP set that changes in "
                     "more rows than this is refactored; fewer are CHOLMOD row additions / deletions")
            .choice(
                "expansion_projection", &MprgpCoupledSettings::expansion_projection, {"face", "all"},
                "the expansion's projections (of an infeasible chain iterate and of x - alpha_bar phi): face (onto "
                "the feasible points that keep the face rows active, as decoupled MPRGP's projection does) | all (P "
                "of Alg. 1: coupled neighbours may lift face rows off)");
    return table;
}

}  // namespace

MprgpCoupledSettings MprgpCoupledSettings::from_json(const nlohmann::json& settings)
{
    return read_settings(settings, "mprgp-coupled", mprgp_coupled_settings_table());
}

nlohmann::json MprgpCoupledSettings::to_json() const { return write_settings(*this, mprgp_coupled_settings_table()); }

SolverEntry mprgp_coupled_entry()
{
    return solver_entry<MprgpCoupledSolver>(
        "mprgp-coupled", mprgp_coupled_settings_table(),
        "extended MPRGP with general (coupled) J: exact operators per component of the row graph (dense, or CHOLMOD "
        "factors updated by row changes)");
}

namespace {

/// Projected coordinate-descent sweeps tried on the chopped problem's upper bound before its LCP.
constexpr int BOUND_SWEEPS = 8;

/// Why chains end (issue 31's question: why the coupled chain keeps expanding), counted.
struct ChainCounts {
    long rejected_infeasible_trials = 0;   ///< CG trial with a projected P(y) and F(P(y)) >= F(P(x)): expansion
    long rejected_feasible_trials = 0;     ///< CG trial at a feasible y with F(y) > F(P(x)) (rounding): expansion
    long infeasible_not_proportional = 0;  ///< not proportional at an infeasible chain iterate: expansion
    long face_done_expansions = 0;         ///< infeasible iterate whose face problem is solved: expansion
    long expansions_same_face = 0;         ///< expansions after which the face was the one before
    long drift_only_trials = 0;            ///< trials whose only violated rows were face rows within tau_i
    long accepted_infeasible_trials = 0;   ///< CG trials accepted although P moved y (the chain goes on)
    long violated_rows_accepted = 0;       ///< rows P moved, summed over the accepted infeasible trials
    long violated_rows_rejected = 0;       ///< rows P moved, summed over the rejected infeasible trials
    double rejected_gain = 0.0;            ///< sum of -(F(y) - F(x)) over the rejected infeasible trials
    double rejected_cost = 0.0;            ///< sum of the projection corrections F(P(y)) - F(y) over them
    nlohmann::json to_json() const
    {
        return {{"rejected_infeasible_trials", rejected_infeasible_trials},
                {"rejected_feasible_trials", rejected_feasible_trials},
                {"infeasible_not_proportional", infeasible_not_proportional},
                {"face_done_expansions", face_done_expansions},
                {"expansions_same_face", expansions_same_face},
                {"drift_only_trials", drift_only_trials},
                {"accepted_infeasible_trials", accepted_infeasible_trials},
                {"violated_rows_accepted", violated_rows_accepted},
                {"violated_rows_rejected", violated_rows_rejected},
                {"rejected_cost_over_gain", rejected_gain > 0.0 ? rejected_cost / rejected_gain : 0.0}};
    }
};

/// LCP pivots (Counters::lcp_iterations) by the operator that asked for them.
struct LcpPivotsByUse {
    long chopped = 0;           ///< the chopped gradient's LCP on the face (evaluate)
    long reduced_gradient = 0;  ///< P(x - alpha_bar phi) of the proportioning test
    long trial = 0;             ///< P(y) of a CG trial
    long iterate = 0;           ///< P(x) of an expansion, proportioning or safeguard step, and the returned point
    nlohmann::json to_json() const
    {
        return {{"chopped", chopped}, {"reduced_gradient", reduced_gradient}, {"trial", trial}, {"iterate", iterate}};
    }
};

/// The chopped gradient's LCP: solved, or deferred because bounds decided without it.
struct ChoppedCounts {
    long solved = 0;                     ///< chopped LCPs solved for the solver
    long deferred = 0;                   ///< evaluations that stopped at the bounds
    long proportional_by_bound = 0;      ///< proportionality decided by beta'beta's upper bound
    long proportional_without_beta = 0;  ///< no negative face multiplier at a feasible x
    long proportional_by_sweeps = 0;     ///< decided by the projected sweeps' bound
    long bound_sweeps = 0;               ///< those sweeps, counted
    nlohmann::json to_json() const
    {
        return {{"solved", solved},
                {"deferred", deferred},
                {"proportional_by_bound", proportional_by_bound},
                {"proportional_without_beta", proportional_without_beta},
                {"proportional_by_sweeps", proportional_by_sweeps},
                {"bound_sweeps", bound_sweeps}};
    }
};

/// The research counters of one run, in one place; they fill `info` and change no decision.
struct ResearchStats {
    ChainCounts chain;
    LcpPivotsByUse lcp_by_use;
    ChoppedCounts chopped;
    void fill(nlohmann::json& info) const
    {
        info["chain"] = chain.to_json();
        info["lcp_pivots_by_use"] = lcp_by_use.to_json();
        info["chopped_lcp"] = chopped.to_json();
    }
};

/// The preconditioner a run uses: `precond` itself, or for auto scaled or jacobi by the size of
/// the largest component of J's row graph (the settings' help and docs/preconditioners.md give why).
struct PrecondChoice {
    std::string name;  ///< the preconditioner used
    std::string rule;  ///< how auto chose (empty unless precond = auto)
    /// J's row components when auto found them; the face operators take them (a column scaling of
    /// J, as precond = scaled makes, has the same components), so they are found once per solve.
    std::optional<RowComponents> components;

    static PrecondChoice make(const QpView& qp, const MprgpCoupledSettings& st)
    {
        PrecondChoice c;
        if (st.precond != "auto") {
            c.name = st.precond;
        } else if (st.deflation != "none") {
            c.name = "jacobi";
            c.rule = "auto: jacobi (deflation = " + st.deflation + ")";
        } else {
            c.components = find_row_components(qp.J);
            const int largest = qp.m() > 0 ? c.components->largest() : 0;
            c.name = largest > st.dense_max_rows ? "scaled" : "jacobi";
            c.rule = "auto: " + c.name + " (largest component " + std::to_string(largest) + " rows, dense_max_rows " +
                     std::to_string(st.dense_max_rows) + ")";
        }
        return c;
    }
};

/// precond = scaled: the QP in the variables y = D^1/2 x (D = diag(A)): A -> U A U, J -> J U,
/// b -> U b, x0 -> x0 / U with U = D^-1/2; c and the multipliers are the same.
struct ScaledVariables {
    Vec unscale;  ///< U: x = U y
    SpMat A, J;
    Vec b, y0;
    /// null unless precond = scaled applies (deflation = none, a positive diagonal of A)
    static std::unique_ptr<ScaledVariables> make(const QpView& qp, const std::string& precond,
                                                 const MprgpCoupledSettings& st)
    {
        if (precond != "scaled" || st.deflation != "none") return nullptr;
        if (qp.n() > 0 && !(qp.A.diagonal().minCoeff() > 0.0)) return nullptr;
        auto s = std::make_unique<ScaledVariables>();
        s->unscale = qp.A.diagonal().cwiseSqrt().cwiseInverse();
        const Vec& u = s->unscale;
        s->A = qp.A;  // the same pattern, each entry scaled by its row's and its column's U
        for (Eigen::Index i = 0; i < s->A.outerSize(); ++i)
            for (SpMat::InnerIterator it(s->A, i); it; ++it) it.valueRef() *= u[i] * u[it.col()];
        s->J = qp.J;
        for (Eigen::Index i = 0; i < s->J.outerSize(); ++i)
            for (SpMat::InnerIterator it(s->J, i); it; ++it) it.valueRef() *= u[it.col()];
        s->b = u.cwiseProduct(qp.b);
        s->y0 = qp.x0.cwiseQuotient(u);
        return s;
    }
};

/// One solve; every vector is allocated before the loop.
class CoupledRun {
public:
    /// With precond = scaled the run iterates on the QP in y = D^1/2 x (ScaledVariables, formed on
    /// the solver's clock) and measures, monitors and returns x of `qp`, the QP in the file.
    CoupledRun(const QpView& qp, const MprgpCoupledSettings& st, const SolveContext& context)
        : m_loop("mprgp-coupled", qp, st.common, context), m_original(qp), m_choice(PrecondChoice::make(qp, st)),
          m_scaled(ScaledVariables::make(qp, m_choice.name, st)),
          m_qp(m_scaled ? QpView{m_scaled->A, m_scaled->b, m_scaled->J, qp.c, m_scaled->y0} : qp), m_A(m_qp.A),
          m_a_op(m_A), m_J(m_qp.J), m_c(m_qp.c), m_st(st), m_ctx(context), m_n(qp.n()), m_m(qp.m()),
          m_unscale(m_scaled ? &m_scaled->unscale : nullptr)
    {
    }
    SolverResult run();

private:
    void rows_times(const Vec& v, Vec& out) const
    {
        for (Eigen::Index i = 0; i < m_m; ++i) out[i] = row_dot(m_J, i, v);
    }
    /// v += a J' coef over the rows with coef_i != 0.
    void add_rows_transpose(const Vec& coef, double a, Vec& v) const
    {
        for (Eigen::Index i = 0; i < m_m; ++i)
            if (coef[i] != 0.0) row_axpy(m_J, i, a * coef[i], v);
    }
    void exact_gradient()
    {
        m_tmp = m_x - m_x_ref;
        a_product(m_a_op, m_tmp, m_g);
        m_g += m_g_ref;
        ++m_cnt.a_products;
    }
    /// F(x) - F(x_ref) = 1/2 u'(g + g_ref), u = x - x_ref (no A-product; translation invariant).
    double objective_from_gradient() const
    {
        double f = 0.0;
        for (Eigen::Index j = 0; j < m_n; ++j) f += (m_x[j] - m_x_ref[j]) * (m_g[j] + m_g_ref[j]);
        return 0.5 * f;
    }
    /// Flags the rows that P must move for q = c - J v: zero rows never, face rows only beyond
    /// tau_i (J_A p = 0 holds to rounding only: their drift is not a violation), others when q_i > 0.
    long flag_violated(const Vec& q, bool strict)
    {
        long count = 0, drift = 0;
        for (Eigen::Index i = 0; i < m_m; ++i) {
            const bool face = m_active[static_cast<size_t>(i)] != 0;
            const double thr = face && !strict ? active_tolerance(m_c[i]) : 0.0;
            const bool v = m_s[i] > 0.0 && q[i] > thr;
            m_violated[static_cast<size_t>(i)] = v;
            count += v;
            drift += !v && face && m_s[i] > 0.0 && q[i] > 0.0;
        }
        m_last_drift = drift;
        return count;
    }
    /// Sparse d = J' lam over the rows with lam_i > 0 (m_touched lists its DOFs once).
    void build_d(const Vec& lam)
    {
        m_touched.clear();
        for (Eigen::Index i = 0; i < m_m; ++i) {
            if (lam[i] == 0.0) continue;
            for (SpMat::InnerIterator it(m_J, i); it; ++it) {
                const int j = static_cast<int>(it.col());
                if (!m_mark[static_cast<size_t>(j)]) {
                    m_mark[static_cast<size_t>(j)] = 1;
                    m_touched.push_back(j);
                }
                m_d[j] += lam[i] * it.value();
            }
        }
    }
    void clear_d()
    {
        for (int j : m_touched) {
            m_d[j] = 0.0;
            m_mark[static_cast<size_t>(j)] = 0;
        }
        m_touched.clear();
    }
    /// d'Ad over the touched rows of A (A symmetric, d sparse).
    double d_a_d() const
    {
        const int* outer = m_A.outerIndexPtr();
        const int* inner = m_A.innerIndexPtr();
        const double* val = m_A.valuePtr();
        double dad = 0.0;
        for (int j : m_touched) {
            double s = 0.0;
            for (int k = outer[j]; k < outer[j + 1]; ++k) s += val[k] * m_d[inner[k]];
            dad += m_d[j] * s;
        }
        return dad;
    }
    /// The nonzeros of A's columns at the touched DOFs (the work of d_a_d or add_a_d).
    double touched_nonzeros() const
    {
        const int* outer = m_A.outerIndexPtr();
        long nz = 0;
        for (int j : m_touched) nz += outer[j + 1] - outer[j];
        return static_cast<double>(nz);
    }
    /// g += A d (columns of A = rows, A symmetric), O(nnz of the touched columns).
    void add_a_d(Vec& g) const
    {
        const int* outer = m_A.outerIndexPtr();
        const int* inner = m_A.innerIndexPtr();
        const double* val = m_A.valuePtr();
        for (int j : m_touched)
            for (int k = outer[j]; k < outer[j + 1]; ++k) g[inner[k]] += val[k] * m_d[j];
    }
    /// x = P(x) with g updated sparsely (g += A J'lam). @return whether x moved.
    /// With keep_face, the projection keeps the face rows as equalities (the expansion's projections).
    bool project_x(bool strict, bool keep_face = false)
    {
        ++m_cnt.projections;
        rows_times(m_x, m_jx);
        m_q = m_c - m_jx;
        if (flag_violated(m_q, strict) == 0) return false;
        const long pivots_before = m_cnt.lcp_iterations;
        const long solved =
            m_ops->projection_multipliers(m_q, m_violated, m_lam, m_cnt, keep_face ? &m_active : nullptr);
        m_stats.lcp_by_use.iterate += m_cnt.lcp_iterations - pivots_before;
        if (solved == 0) return false;
        build_d(m_lam);
        for (int j : m_touched) m_x[j] += m_d[j];
        add_a_d(m_g);
        clear_d();
        return true;
    }
    /// nu, phi = g - J_A' nu and (with with_z) the direction z and z'phi, from the current g and
    /// face; with `ap`, first the accepted CG step x -= alpha p, g -= alpha Ap, and z'Ap (the CG
    /// coefficient). Every pass is a short Eigen one: after an A-product the vectors come from
    /// memory, and a loop over few streams keeps the hardware prefetch (one fused pass over the
    /// ten vectors measured 3x slower than eight Eigen passes, flank_press's n, cold cache).
    void face_gradient(bool with_z, const Vec* ap = nullptr, double alpha = 0.0)
    {
        if (ap != nullptr) {
            // x -= alpha p, g -= alpha Ap and phi = g in one pass (no reduction in it, so it vectorises)
            double* __restrict px = m_x.data();
            double* __restrict pg = m_g.data();
            double* __restrict pphi = m_phi.data();
            const double* __restrict pp = m_p.data();
            const double* __restrict pap = ap->data();
            for (Eigen::Index j = 0; j < m_n; ++j) {
                px[j] -= alpha * pp[j];
                const double gj = pg[j] - alpha * pap[j];
                pg[j] = gj;
                pphi[j] = gj;
            }
            m_jx -= alpha * m_jp;  // J x by the step's own J p (the trial's); restarts form it afresh
        } else {
            m_phi = m_g;
        }
        rows_times(m_g, m_jg);
        m_ops->face_multipliers(m_jg, m_nu, m_cnt);
        add_rows_transpose(m_nu, -1.0, m_phi);
        if (!with_z) return;  // the expansion's intermediate face: m_phi2 and z are not read before the next restart
        ++m_cnt.precond_applications;
        if (m_precond) {
            m_precond->apply(m_active, m_g, m_phi, m_z, m_cnt);  // ichol or deflation=rigid
        } else if (!m_jacobi) {
            // z = phi: read from m_phi where it is (direction()), not copied (precond = none or scaled)
        } else {
            // z = D^-1 (g - J_A' eta) (J_A z = 0): one pass for D^-1 g, then only the DOFs of the
            // face rows, where g - J_A' eta is accumulated row by row as a full copy would be.
            m_z = m_dinv.cwiseProduct(m_g);
            rows_times(m_z, m_jdg);
            m_ops->jacobi_multipliers(m_jdg, m_eta, m_cnt);
            for (int j : m_face_dofs) m_tmp[j] = m_g[j];
            add_rows_transpose(m_eta, -1.0, m_tmp);
            for (int j : m_face_dofs) m_z[j] = m_dinv[j] * m_tmp[j];
        }
        const Vec& z = direction();
        m_zphi = z.dot(m_phi);
        m_zap = ap != nullptr ? z.dot(*ap) : 0.0;
        // phi'phi for evaluate (every evaluate follows a face_gradient with z): z'phi itself when z = phi.
        m_phi2 = &z == &m_phi ? m_zphi : m_phi.squaredNorm();
    }
    /// m_face_dof / m_face_dofs: the DOFs some face row touches (after every face change).
    void list_face_dofs()
    {
        for (int j : m_face_dofs) {
            m_face_dof[static_cast<size_t>(j)] = 0;
            m_free_weight[j] = m_scale.inv_diag[j];
        }
        m_face_dofs.clear();
        for (Eigen::Index i = 0; i < m_m; ++i) {
            if (!m_active[static_cast<size_t>(i)]) continue;
            for (SpMat::InnerIterator it(m_J, i); it; ++it) {
                const int j = static_cast<int>(it.col());
                if (!m_face_dof[static_cast<size_t>(j)]) {
                    m_face_dof[static_cast<size_t>(j)] = 1;
                    m_face_dofs.push_back(j);
                    m_free_weight[j] = 0.0;
                }
            }
        }
        m_face_dofs_known = true;
    }
    /// Chain start at the current (feasible) x with the current g: face, phi, z, p, F. With
    /// `galerkin` (after the start, an expansion or a proportioning) and deflation = rigid, first
    /// the Galerkin steps over the face's rigid modes. Without `with_z` only the face and phi
    /// (the expansion's intermediate face; z and p are then stale until the next restart).
    void restart(bool galerkin = false, bool with_z = true)
    {
        if (galerkin && m_precond) m_precond->galerkin_steps(m_x, m_g, m_c, m_s, m_cnt);
        rows_times(m_x, m_jx);
        bool changed = false;
        for (Eigen::Index i = 0; i < m_m; ++i) {
            const char a = m_s[i] > 0.0 && std::abs(m_jx[i] - m_c[i]) <= active_tolerance(m_c[i]);
            changed = changed || a != m_active[static_cast<size_t>(i)];
            m_active[static_cast<size_t>(i)] = a;
        }
        if (changed) ++m_cnt.pivots;  // an active-set change
        if (changed || !m_face_dofs_known) list_face_dofs();
        m_ops->set_face(m_active, m_cnt);
        face_gradient(with_z);
        if (with_z) m_p = direction();
        m_f_x = objective_from_gradient();
        m_corr_x = 0.0;
        m_x_feasible = true;
    }
    /// phi'phi, the face error and bounds at x; with `exact`, or when the criterion may hold, the
    /// chopped gradient too (chopped_gradient), else the error is a lower bound, beta'beta an upper one.
    void evaluate(bool exact = false);
    /// The chopped LCP: mu, beta, native residual and accuracy error at x (once per evaluate).
    /// @param solver_work  false for the monitor's copy (notify's prepare): not counted as solver work
    void chopped_gradient(Counters& cnt, bool solver_work);
    /// beta'beta <= Gamma^2 phitilde'phi, from the upper bound of beta'beta when that decides it.
    bool proportional_test(double gamma2);
    /// Whether a few projected coordinate-descent sweeps on the chopped problem bring its value
    /// (an upper bound of beta'beta) to `bound` or below.
    bool projected_sweeps_bound(double bound);
    /// The monitor's view of x: the exact mu, native residual and error (chopped_gradient, not
    /// counted as solver work, so the iterates and counters are those of an unmonitored run).
    void monitor_view(IterationInfo& shown)
    {
        if (!m_chopped_exact) {
            m_monitor_chopped = Counters();
            chopped_gradient(m_monitor_chopped, false);
            m_chopped_by_monitor = true;
        }
        shown.lambda = &m_mu;
        if (m_unscale != nullptr) shown.x = &original_x(m_x);
        shown.native_residual = m_native;
    }
    /// phitilde'phi = phi'phi - lam'(J phi) / alpha_bar with lam of P(x - alpha_bar phi) (eq. 13).
    double reduced_free_gradient_dot();
    bool safeguard(double f_before, double& f_now);
    /// x = P(x - alpha_bar phi) (Alg. 1), from P(x) of an infeasible chain iterate.
    bool expansion();
    bool proportioning();

    /// The preconditioned face direction z: m_z, or phi itself without a preconditioner.
    const Vec& direction() const { return m_precond || m_jacobi ? m_z : m_phi; }
    /// x of the original QP from the iterate (precond = scaled: x = D^-1/2 y), in m_x_out.
    const Vec& original_x(const Vec& v)
    {
        if (m_unscale == nullptr) return v;
        m_x_out = m_unscale->cwiseProduct(v);
        return m_x_out;
    }

    SolveLoop m_loop;                           // first: its clock starts before the scaled copies are formed
    const QpView m_original;                    // the QP in the file
    PrecondChoice m_choice;                     // the preconditioner used and, for auto, why
    std::unique_ptr<ScaledVariables> m_scaled;  // precond = scaled: the QP in y = D^1/2 x, else null
    const QpView m_qp;                          // the QP iterated on: m_original or m_scaled's
    const SpMat& m_A;
    AOperator m_a_op;  // the product with A (prepared in the setup)
    const SpMat& m_J;
    const Vec& m_c;
    const MprgpCoupledSettings& m_st;
    const SolveContext& m_ctx;
    const Eigen::Index m_n, m_m;
    const Vec* m_unscale;  // precond = scaled: D^-1/2 (x = D^-1/2 y), else null
    Vec m_x_out;           // original_x's result
    Counters m_cnt;
    ResearchStats m_stats;
    std::unique_ptr<CoupledFaceOperators> m_ops;
    std::unique_ptr<CoupledPreconditioner> m_precond;  // precond = ichol or deflation = rigid only
    bool m_jacobi = false;
    double m_alpha_bar = 1.0;
    AccuracyScale m_scale;
    Vec m_s, m_dinv;
    Vec m_x, m_g, m_phi, m_z, m_p, m_Ap, m_beta, m_tmp, m_d, m_x_ref, m_g_ref;
    Vec m_jx, m_jg, m_jp, m_jphi, m_jdg, m_q, m_nu, m_eta, m_mu, m_lam;
    std::vector<char> m_active, m_violated, m_mark;
    std::vector<int> m_touched;
    long m_last_drift = 0;
    bool m_keep_face = false;
    double m_f_x = 0.0, m_corr_x = 0.0;
    double m_zphi = 0.0, m_zap = 0.0;  // z'phi and z'Ap of face_gradient
    bool m_x_feasible = true;
    double m_native = 0.0, m_error = 0.0, m_face_error = 0.0, m_beta2 = 0.0, m_phi2 = 0.0;
    double m_primal = 0.0, m_beta2_upper = 0.0;
    double m_stat_free = 0.0;  // max |phi_j| w_j over the DOFs no face row touches (evaluate)
    bool m_chopped_exact = false;
    bool m_chopped_by_monitor = false;  // m_monitor_chopped: that solve's work, not yet counted
    Counters m_monitor_chopped;
    std::vector<char> m_face_dof;  // flags of m_face_dofs
    Vec m_free_weight;             // the measure's D^-1 on DOFs no face row touches, 0 on m_face_dofs
    std::vector<int> m_face_dofs;
    bool m_face_dofs_known = false;
    Vec m_mu_bound, m_w_bound;
    SpMat m_gram;  // J J' (symmetric: row i is column i), for the proportioning test's sweeps
};

void CoupledRun::evaluate(bool exact)
{
    // J x comes from the last restart, moved by each accepted CG step (J x - alpha J p, the trial's
    // J p): every evaluate follows one of the two. (J phi as J g - G nu, also without a gather, took
    // the components' iterates 10x further from the global operators' on 251-step chains: the
    // difference cancels on the face rows.)
    rows_times(m_phi, m_jphi);
    // The parts of the accuracy error that do not depend on mu: the feasibility, and the
    // stationarity at DOFs no face row touches (there g - J_A'mu = g = phi for every mu): one
    // vectorised pass over every DOF with the face DOFs weighted 0, then the face DOFs alone.
    m_stat_free = m_n > 0 ? m_phi.cwiseAbs().cwiseProduct(m_free_weight).maxCoeff() : 0.0;
    const double stat_free = m_stat_free;
    double stat_phi = stat_free;
    for (int j : m_face_dofs) stat_phi = std::max(stat_phi, std::abs(m_phi[j]) * m_scale.inv_diag[j]);
    m_face_error = stat_phi * m_scale.inv_length;
    RowParts feasibility;
    for (Eigen::Index i = 0; i < m_m; ++i) {
        const double inv_norm = m_scale.inv_row_norm[i];
        if (inv_norm == 0.0)
            feasibility.add_zero_row(m_c[i]);
        else
            feasibility.add_primal(m_jx[i] - m_c[i], inv_norm);
    }
    m_primal = feasibility.primal;
    // beta'beta = min over mu >= 0 of ||J_A'(nu - mu)||^2 <= its value at mu = max(nu, 0).
    for (Eigen::Index i = 0; i < m_m; ++i) m_q[i] = std::min(m_nu[i], 0.0);
    build_d(m_q);
    m_beta2_upper = 0.0;
    for (int j : m_touched) m_beta2_upper += m_d[j] * m_d[j];
    clear_d();
    m_chopped_exact = false;
    m_chopped_by_monitor = false;
    const double error_lower = std::max(stat_free, m_primal) * m_scale.inv_length;
    // ||phi + beta||^2 = ||phi||^2 + ||beta||^2 (beta in range(J_A'), phi in its complement):
    // both are lower bounds, so the rule can hold only when it holds on them.
    const bool may_converge = m_x_feasible && m_loop.rule_holds(std::sqrt(m_phi2), error_lower);
    if (exact || may_converge) {
        chopped_gradient(m_cnt, true);
        return;
    }
    // Bounds until the chopped LCP is needed: the criterion cannot hold, the monitor gets the exact
    // values from chopped_gradient in notify's prepare, the proportioning test tries the upper bound.
    m_beta2 = m_beta2_upper;
    m_native = std::sqrt(m_phi2 + m_beta2_upper);
    m_error = std::isfinite(error_lower) ? error_lower : std::numeric_limits<double>::infinity();
    ++m_stats.chopped.deferred;
}

void CoupledRun::chopped_gradient(Counters& cnt, bool solver_work)
{
    if (m_chopped_exact) {
        if (solver_work && m_chopped_by_monitor) {
            // The solver needs the solve the monitor had done: its work counts now, as without a monitor.
            m_cnt.lcp_iterations += m_monitor_chopped.lcp_iterations;
            m_cnt.pgs_sweeps += m_monitor_chopped.pgs_sweeps;
            m_cnt.cholmod_factorizations += m_monitor_chopped.cholmod_factorizations;
            m_cnt.cholmod_solves += m_monitor_chopped.cholmod_solves;
            m_cnt.work_flops += m_monitor_chopped.work_flops;
            m_stats.lcp_by_use.chopped += m_monitor_chopped.lcp_iterations;
            ++m_stats.chopped.solved;
            m_chopped_by_monitor = false;
        }
        return;
    }
    // q_A = J_A (g - phi) on the face rows for the chopped LCP; beta = J_A'(nu - mu).
    for (Eigen::Index i = 0; i < m_m; ++i) m_q[i] = m_active[static_cast<size_t>(i)] ? m_jg[i] - m_jphi[i] : 0.0;
    const long pivots_before = cnt.lcp_iterations;
    m_ops->chopped_multipliers(m_q, m_nu, m_mu, cnt);
    if (solver_work) {
        m_stats.lcp_by_use.chopped += cnt.lcp_iterations - pivots_before;
        ++m_stats.chopped.solved;
    }
    // beta = J_A'(nu - mu) lives on the face rows' DOFs (nu and mu are 0 off the face), so phi + beta =
    // g - J'mu differs from phi only there: ||phi + beta||^2 = phi'phi + sum beta_j (2 phi_j + beta_j)
    // (no cancellation: phi'beta = 0 to rounding) and the free DOFs' stationarity is evaluate's.
    for (Eigen::Index i = 0; i < m_m; ++i)
        if (m_nu[i] != m_mu[i]) row_axpy(m_J, i, m_nu[i] - m_mu[i], m_beta);
    // phi + beta = g - J'mu: the native residual and the measure's stationarity part together.
    double pb2 = m_phi2, stat = m_stat_free;
    m_beta2 = 0.0;
    for (int j : m_face_dofs) {
        const double r = m_phi[j] + m_beta[j];
        m_beta2 += m_beta[j] * m_beta[j];
        pb2 += m_beta[j] * (2.0 * m_phi[j] + m_beta[j]);
        stat = std::max(stat, std::abs(r) * m_scale.inv_diag[j]);
        m_beta[j] = 0.0;  // all of m_beta is 0 again
    }
    RowParts rows;  // the multiplier's parts; the primal part is evaluate's (m_primal)
    for (Eigen::Index i = 0; i < m_m; ++i) {
        const double inv_norm = m_scale.inv_row_norm[i];
        if (inv_norm != 0.0) rows.add_multiplier(m_jx[i] - m_c[i], m_mu[i], inv_norm, m_scale.length_per_multiplier[i]);
    }
    m_native = std::sqrt(pb2);
    const RowParts parts = rows.scaled(m_scale.inv_length, m_scale.inv_energy);
    const double error =
        std::max(std::max(std::max(stat, m_primal) * m_scale.inv_length, std::max(parts.dual, parts.complementarity)),
                 parts.gap);
    m_error = std::isfinite(error) ? error : std::numeric_limits<double>::infinity();
    m_chopped_exact = true;
}

bool CoupledRun::proportional_test(double gamma2)
{
    // No face multiplier negative: beta = 0, and at a feasible x phitilde'phi >= ||phitilde||^2 >= 0
    // (P is a projection onto a convex set), so the test holds without the projection of eq. (13).
    if (m_beta2_upper == 0.0 && m_x_feasible) {
        ++m_stats.chopped.proportional_without_beta;
        return true;
    }
    const double reduced = reduced_free_gradient_dot();
    const double bound = gamma2 * reduced;
    // beta'beta <= any ||J_A'(nu - mu)||^2 with mu >= 0 decides without the chopped LCP when the
    // bound passes. Tried first even when a monitor had mu computed: a monitor changes no decision.
    if (m_beta2_upper <= bound) {
        ++m_stats.chopped.proportional_by_bound;
        return true;
    }
    if (projected_sweeps_bound(bound)) {
        ++m_stats.chopped.proportional_by_sweeps;
        return true;
    }
    chopped_gradient(m_cnt, true);
    return m_beta2 <= bound;
}

bool CoupledRun::projected_sweeps_bound(double bound)
{
    // Coordinate descent on 1/2 ||r||^2, r = J_A'(nu - mu), mu >= 0, from mu = max(nu, 0): each
    // row step is exact and keeps mu feasible, so ||r||^2 only falls and bounds beta'beta at
    // every point. Done in the rows' space: w = J_A r = G (nu - mu) (G = J J', nu and mu zero off
    // the face), a row step reads w_i and moves w by a column of G, and ||r||^2 = (nu - mu)'w; the
    // m-vectors stay in cache where r's DOFs were gathered and scattered (flank_press frame 0:
    // 1052 face rows, 12 DOFs each). Row work, not counted in `work` (solvers/work_units.hpp).
    const int* outer = m_gram.outerIndexPtr();
    const int* inner = m_gram.innerIndexPtr();
    const double* val = m_gram.valuePtr();
    m_w_bound.setZero();
    for (Eigen::Index i = 0; i < m_m; ++i) {
        m_mu_bound[i] = std::max(m_nu[i], 0.0);
        const double delta = m_nu[i] - m_mu_bound[i];
        if (delta == 0.0) continue;
        for (int k = outer[i]; k < outer[i + 1]; ++k) m_w_bound[inner[k]] += val[k] * delta;
    }
    bool decided = false;
    for (int sweep = 0; sweep < BOUND_SWEEPS && !decided; ++sweep) {
        for (Eigen::Index i = 0; i < m_m; ++i) {
            if (!m_active[static_cast<size_t>(i)]) continue;
            const double next = std::max(0.0, m_mu_bound[i] + m_w_bound[i] / m_s[i]);
            const double step = next - m_mu_bound[i];
            if (step == 0.0) continue;
            m_mu_bound[i] = next;
            for (int k = outer[i]; k < outer[i + 1]; ++k) m_w_bound[inner[k]] -= val[k] * step;
        }
        double r2 = 0.0;
        for (Eigen::Index i = 0; i < m_m; ++i)
            if (m_active[static_cast<size_t>(i)]) r2 += (m_nu[i] - m_mu_bound[i]) * m_w_bound[i];
        ++m_stats.chopped.bound_sweeps;
        decided = r2 <= bound;
    }
    return decided;
}

double CoupledRun::reduced_free_gradient_dot()
{
    ++m_cnt.projections;
    for (Eigen::Index i = 0; i < m_m; ++i) m_q[i] = m_c[i] - m_jx[i] + m_alpha_bar * m_jphi[i];
    if (flag_violated(m_q, false) == 0) return m_phi2;
    const long pivots_before = m_cnt.lcp_iterations;
    const long solved =
        m_ops->projection_multipliers(m_q, m_violated, m_lam, m_cnt, nullptr, ProjectionUse::REDUCED_GRADIENT);
    m_stats.lcp_by_use.reduced_gradient += m_cnt.lcp_iterations - pivots_before;
    if (solved == 0) return m_phi2;
    double lj = 0.0;
    for (Eigen::Index i = 0; i < m_m; ++i) lj += m_lam[i] * m_jphi[i];
    return m_phi2 - lj / m_alpha_bar;
}

bool CoupledRun::safeguard(double f_before, double& f_now)
{
    auto increased = [&](double f) { return f > f_before + 1e-12 * (std::abs(f_before) + std::abs(f)); };
    long repeats = 0;
    while (increased(f_now) && repeats < m_st.safeguard_max) {
        m_x -= m_alpha_bar * m_g;
        project_x(false);
        exact_gradient();
        f_now = objective_from_gradient();
        ++m_cnt.safeguard_steps;
        ++repeats;
        if (m_loop.time_up()) return false;
    }
    return true;
}

bool CoupledRun::expansion()
{
    const double f_before = m_f_x + m_corr_x;  // F(P(x))
    // y = P(x) of the infeasible chain iterate, g(y) = g + A J'lam; with `face` the chain's frozen
    // face stays active here too (the safeguard below keeps F(P(x)) as the bound).
    if (!m_x_feasible) project_x(false, m_keep_face);
    const std::vector<char> face_before = m_active;
    restart(false, false);  // the face of P(x) and phi(P(x)); z is not needed to step along phi
    m_x -= m_alpha_bar * m_phi;
    project_x(false, m_keep_face);
    exact_gradient();
    double f_now = objective_from_gradient();
    ++m_cnt.expansion_steps;
    const bool ok = safeguard(f_before, f_now);
    restart(true);
    if (m_active == face_before) ++m_stats.chain.expansions_same_face;
    return ok;
}

bool CoupledRun::proportioning()
{
    const double f_before = m_f_x;
    // beta = J_A'(nu - mu) (chopped_gradient's multipliers) is 0 off the face rows' DOFs: A beta
    // over its columns, as the projections' corrections, not a full A-product.
    for (Eigen::Index i = 0; i < m_m; ++i) m_q[i] = m_nu[i] - m_mu[i];
    build_d(m_q);
    const double dad = d_a_d();
    double gb = 0.0;
    for (int j : m_touched) gb += m_g[j] * m_d[j];
    m_cnt.work_flops += 2.0 * sparse_product_flops(touched_nonzeros());
    if (!(dad > 0.0) || !std::isfinite(dad)) {
        clear_d();
        return false;
    }
    const double alpha_p = gb / dad;
    for (int j : m_touched) {
        m_d[j] *= -alpha_p;
        m_x[j] += m_d[j];
    }
    add_a_d(m_g);  // g -= alpha_p A beta
    clear_d();
    project_x(false);  // -beta may leave the set when rows are coupled (Sec. 4.4)
    double f_now = objective_from_gradient();
    ++m_cnt.proportioning_steps;
    const bool ok = safeguard(f_before, f_now);
    restart(true);
    return ok;
}

SolverResult CoupledRun::run()
{
    const CommonSettings& common = m_st.common;
    SolverResult result;
    result.x = m_original.x0;
    result.lambda = Vec::Zero(m_m);
    if (m_choice.name == "scaled" && !m_scaled) {
        result.status = SolveStatus::INVALID_INPUT;
        result.message = m_st.deflation != "none"
                             ? "mprgp-coupled: precond=scaled takes deflation=none (rigid modes are of x, not of y)"
                             : "mprgp-coupled: precond=scaled needs a positive diagonal of A";
        if (!m_choice.rule.empty()) result.message += " (" + m_choice.rule + ")";
        return m_loop.finish(result, result.status);
    }
    m_jacobi = m_choice.name == "jacobi";
    m_keep_face = m_st.expansion_projection == "face";
    m_dinv = Vec::Ones(m_n);
    if (m_jacobi) {
        const Vec diag = m_A.diagonal();
        if (!(diag.minCoeff() > 0.0)) {
            result.status = SolveStatus::INVALID_INPUT;
            result.message = "mprgp-coupled: precond=jacobi needs a positive diagonal of A";
            return m_loop.finish(result, result.status);
        }
        m_dinv = diag.cwiseInverse();
    }
    CoupledOperatorOptions opt;
    opt.global = m_st.operators == "global";
    opt.jacobi = m_jacobi;
    opt.dense_max_rows = m_st.dense_max_rows;
    opt.sparse_max_updates = m_st.sparse_max_updates;
    opt.lcp_max_pivots = m_st.lcp_max_pivots;
    opt.pgs_max_sweeps = m_st.pgs_max_sweeps;
    m_ops = m_choice.components
                ? std::make_unique<CoupledFaceOperators>(m_J, m_dinv, opt, std::move(*m_choice.components))
                : std::make_unique<CoupledFaceOperators>(m_J, m_dinv, opt);
    m_gram = SpMat(m_J * m_J.transpose());
    if (m_choice.name == "ichol" || m_st.deflation == "rigid") {
        m_precond = std::make_unique<CoupledPreconditioner>(m_A, m_J, m_dinv, *m_ops, m_choice.name);
        std::string error;
        if (!m_precond->setup(m_st.deflation == "rigid", m_qp.x0, error, m_cnt)) {
            result.status = SolveStatus::DIVERGED;
            result.message = "mprgp-coupled: precond=ichol: " + error;
            return m_loop.finish(result, result.status);
        }
    }
    m_s = m_ops->row_norm2();
    for (Eigen::Index i = 0; i < m_m; ++i)
        if (!(m_s[i] > 0.0) && m_c[i] > active_tolerance(m_c[i])) {
            result.status = SolveStatus::INFEASIBLE;
            result.message = "mprgp-coupled: row " + std::to_string(i) + " is zero but c > 0: empty feasible set";
            return m_loop.finish(result, result.status);
        }
    m_a_op.prepare(AFormat::BSR, static_cast<int>(m_st.common.threads));  // 3x3 blocks when A has them
    Vec eigenvector;
    const bool warm = m_ctx.eigenvector && m_ctx.eigenvector->size() == m_n;
    if (warm) eigenvector = *m_ctx.eigenvector;
    const PowerResult power =
        power_method(m_a_op, eigenvector, PowerRule::POWER, m_st.power_max, common.tol, warm, common.seed);
    if (m_ctx.eigenvector) *m_ctx.eigenvector = eigenvector;
    m_cnt.power_products = power.products;
    m_cnt.a_products += power.products;
    m_alpha_bar = power.estimate > 0.0 ? 2.0 / (1.01 * power.estimate) : 1.0;
    m_scale = accuracy_scale(m_original);
    m_cnt.a_products += m_scale.a_products;
    // precond = scaled: the residual in y is D^-1/2 that in x, so the measure's D^-1 weights act
    // on it as D^-1/2 = unscale; lengths, rows and multipliers are the same in both variables.
    if (m_unscale != nullptr) m_scale.inv_diag = m_scale.inv_diag.cwiseQuotient(*m_unscale);
    m_free_weight = m_scale.inv_diag;
    if (!m_loop.end_setup()) return m_loop.finish(result, SolveStatus::TIME_LIMIT);

    for (Vec* v : {&m_g, &m_phi, &m_z, &m_p, &m_Ap, &m_beta, &m_tmp, &m_x_ref, &m_g_ref}) v->setZero(m_n);
    m_d = Vec::Zero(m_n);
    for (Vec* v : {&m_jx, &m_jg, &m_jp, &m_jphi, &m_jdg, &m_q, &m_nu, &m_eta, &m_mu, &m_lam}) v->setZero(m_m);
    m_active.assign(static_cast<size_t>(m_m), 0);
    m_violated.assign(static_cast<size_t>(m_m), 0);
    m_mark.assign(static_cast<size_t>(m_n), 0);
    m_face_dof.assign(static_cast<size_t>(m_n), 0);
    m_face_dofs.reserve(static_cast<size_t>(m_J.nonZeros()));
    m_mu_bound.setZero(m_m);
    m_w_bound.setZero(m_m);
    m_touched.reserve(static_cast<size_t>(m_J.nonZeros()));

    // Translation invariance: positions enter only as differences from x_ref = P(x0), whose
    // gradient g_ref = A x_ref - b is formed once; F(v) - F(x_ref) and g(v) then round relative
    // to |A||v - x_ref|, not |A||v| (a scene 100 m from the origin gives the same decisions).
    m_x = m_qp.x0;
    project_x(true);
    m_x_ref = m_x;
    a_product(m_a_op, m_x, m_g_ref);
    ++m_cnt.a_products;
    m_g_ref -= m_qp.b;
    m_g = m_g_ref;
    restart(true);

    const double gamma2 = m_st.gamma * m_st.gamma;
    SolveStatus status = SolveStatus::NOT_RUN;
    std::string why;  // a breakdown's reason (the loop's own exits need none)
    StepKind last = StepKind::START;
    // m_error holds every part but the bodies' rigid motion (solvers/body_motion.hpp): added only
    // when the rest already meets the rule, the one time it can change the decision.
    auto error_with_bodies = [&]() {
        if (!m_loop.rule_holds(m_native, m_error)) return m_error;
        return std::max(m_error, m_scale.body_motion(original_x(m_x), m_mu));
    };
    auto criterion = [&]() { return m_x_feasible && m_loop.criterion_met(m_native, error_with_bodies); };
    while (true) {
        evaluate();
        bool converged = criterion();
        if (converged) {
            // Confirm at the exact gradient: the recurrence g -= alpha Ap drifts, and on
            // ill-conditioned problems the drift alone can fake convergence (stress case tiny-h2K).
            exact_gradient();
            restart();
            evaluate();
            converged = criterion();
            // The returned point is P(x) with the rows met exactly: judge that one, and go on
            // from it when the small move of the projection undid the rule.
            // project_x updates g by A J'lam over the moved DOFs, exactly: no second full product.
            if (converged && project_x(true)) {
                restart();
                evaluate(true);
                converged = criterion();
            }
        }
        IterationInfo info;
        info.iteration = m_cnt.iterations;
        info.step = last;
        info.x = &m_x;
        info.lambda = m_chopped_exact ? &m_mu : nullptr;
        info.native_residual = m_native;
        info.active_set_size = static_cast<long>(std::count(m_active.begin(), m_active.end(), 1));
        info.counters = &m_cnt;
        if (!m_loop.notify(info, [this](IterationInfo& shown) { monitor_view(shown); })) {
            status = SolveStatus::STOPPED_BY_MONITOR;
            break;
        }
        status = m_loop.check(m_cnt.iterations, std::isfinite(m_native), converged);
        if (status != SolveStatus::NOT_RUN) break;
        ++m_cnt.iterations;
        // An infeasible chain iterate whose face problem is solved cannot improve along the face.
        const bool face_done = !m_x_feasible && m_loop.rule_holds([&] { return std::sqrt(m_phi2); }, m_face_error);
        const bool proportional = !face_done && proportional_test(gamma2);
        bool do_expansion = false;
        if (proportional) {
            // --- CG trial step (Alg. 2), F(P(y)) - F(P(x)) in difference form ---
            double pg = 0.0;  // p'phi = p'g on the chain's face, summed in the product's pass
            const double pap = a_product_dots(m_a_op, m_p, m_Ap, m_phi, pg);
            ++m_cnt.a_products;
            if (!(pap > 0.0) || !std::isfinite(pap)) {
                status = pap == 0.0 ? SolveStatus::STALLED : SolveStatus::DIVERGED;
                why = "p'Ap <= 0";
                break;
            }
            const double alpha = m_zphi / pap;  // z'g = z'phi (z in null(J_A)), without cancellation
            const double df = -alpha * pg + 0.5 * alpha * alpha * pap;  // F(x - alpha p) - F(x)
            rows_times(m_p, m_jp);
            for (Eigen::Index i = 0; i < m_m; ++i) m_q[i] = m_c[i] - m_jx[i] + alpha * m_jp[i];
            ++m_cnt.projections;
            const long violated_rows = flag_violated(m_q, false);
            bool moved = violated_rows > 0;
            if (!moved && m_last_drift > 0) ++m_stats.chain.drift_only_trials;
            double corr_y = 0.0;
            if (moved) {
                const long pivots_before = m_cnt.lcp_iterations;
                moved = m_ops->projection_multipliers(m_q, m_violated, m_lam, m_cnt, nullptr, ProjectionUse::TRIAL) > 0;
                m_stats.lcp_by_use.trial += m_cnt.lcp_iterations - pivots_before;
            }
            if (moved) {
                // F(y + d) - F(y) = d'(g - alpha Ap) + 1/2 d'Ad, d = J' lam sparse.
                build_d(m_lam);
                double dg = 0.0;
                for (int j : m_touched) dg += m_d[j] * (m_g[j] - alpha * m_Ap[j]);
                corr_y = dg + 0.5 * d_a_d();
            }
            const double delta = df + corr_y - m_corr_x;
            const bool accept = moved ? delta < 0.0 : delta <= 0.0;
            clear_d();
            if (accept) {
                face_gradient(true, &m_Ap, alpha);  // x -= alpha p, g -= alpha Ap, then phi and z
                const double beta_cg = m_zap / pap;
                m_p = direction() - beta_cg * m_p;
                m_f_x += df;
                m_corr_x = corr_y;
                m_x_feasible = !moved;
                if (moved) {
                    ++m_stats.chain.accepted_infeasible_trials;
                    m_stats.chain.violated_rows_accepted += violated_rows;
                }
                ++m_cnt.cg_steps;
                last = StepKind::CG;
                continue;
            }
            ++(moved ? m_stats.chain.rejected_infeasible_trials : m_stats.chain.rejected_feasible_trials);
            if (moved) {
                m_stats.chain.violated_rows_rejected += violated_rows;
                m_stats.chain.rejected_gain -= df;
                m_stats.chain.rejected_cost += corr_y;
            }
            do_expansion = true;
        } else if (!m_x_feasible) {
            ++(face_done ? m_stats.chain.face_done_expansions : m_stats.chain.infeasible_not_proportional);
            do_expansion = true;
        }
        bool ok = true;
        if (do_expansion) {
            ok = expansion();
            last = StepKind::EXPANSION;
        } else {
            if (!proportioning()) {
                status = SolveStatus::STALLED;
                why = "beta'A beta <= 0";
                break;
            }
            last = StepKind::PROPORTIONING;
        }
        if (!ok) {
            status = SolveStatus::TIME_LIMIT;
            why = "time limit reached in a safeguard loop";
            break;
        }
    }
    // The returned point: P(x) with rows feasible exactly (no face tolerance), at an exact gradient.
    if (project_x(true) || status != SolveStatus::CONVERGED) {
        exact_gradient();
        restart();
        evaluate(true);
    }
    if (status == SolveStatus::CONVERGED && !criterion()) {
        status = SolveStatus::STALLED;
        why = "the criterion held before the final projection but not after it";
    }
    result.x = original_x(m_x);
    result.lambda = m_mu;
    result.counters = m_cnt;
    result.native_residual = m_native;
    result.info = {{"alpha_bar", m_alpha_bar},
                   {"power", {{"products", power.products}, {"estimate", power.estimate}, {"warm_start", power.warm}}},
                   {"precond", m_choice.name},
                   {"preconditioner", m_precond ? m_precond->stats() : nlohmann::json{{"precond", m_choice.name}}},
                   {"components", m_ops->stats()},
                   {"lcp_failures", m_ops->lcp_failures()},
                   {"safeguard_firings", m_cnt.safeguard_steps},
                   {"dependent_rows", "handled by a shift 1e-12 of the unit-diagonal-scaled Gram matrices"}};
    m_stats.fill(result.info);
    if (!m_choice.rule.empty()) result.info["precond_rule"] = m_choice.rule;
    // The loop writes the reason of its own exits; a breakdown is the solver's word.
    // The whole measure at the returned point (m_error leaves out the bodies' rigid motion); a
    // converged run's message already states it.
    std::string detail = "safeguard firings " + std::to_string(m_cnt.safeguard_steps);
    if (status != SolveStatus::CONVERGED)
        detail = "accuracy error " + format_e(std::max(m_error, m_scale.body_motion(original_x(m_x), m_mu)), 3) + ", " +
                 detail;
    if (!m_loop.owns(status)) detail = "mprgp-coupled: not converged: " + why + " (" + detail + ")";
    if (m_ops->lcp_failures() > 0)
        detail += "; " + std::to_string(m_ops->lcp_failures()) + " LCP solves missed their tolerance";
    return m_loop.finish(result, status, detail);
}

}  // namespace

SolverResult MprgpCoupledSolver::solve(const QpView& qp, const SolveContext& context)
{
    CoupledRun run(qp, m_settings, context);
    return run.run();
}

}  // namespace cb
