#pragma once
/// `mprgp-coupled`'s steps on coupled rows: the constraint set of the MPRGP engine
/// (solvers/mprgp/mprgp_engine.hpp) whose face operators split over the components of J's row graph
/// (solvers/mprgp/coupled_face_operators.*); the steps, the proportioning test and the CG direction stay
/// global. F(P(y)) is formed in difference form from scalar recurrences plus the sparse correction
/// J'lambda of the projection, so a CG step costs one A-product, as in `mprgp` (objective=cheap).
/// solvers/mprgp/mprgp_coupled_face.cpp: the evaluation and the proportioning test;
/// solvers/mprgp/mprgp_coupled_steps.cpp: setup, the steps and the returned point.
/// Ref: Li et al., CGF 2015, eq. (15)-(16) free gradient, (17)-(18) chopped gradient, (19)-(20)
///      projection, Alg. 3.
#include "solvers/core/solve_loop.hpp"
#include "solvers/linalg/a_product.hpp"
#include "solvers/linalg/row_gather_prefetch.hpp"
#include "solvers/measure/accuracy.hpp"
#include "solvers/mprgp/coupled_face_operators.hpp"
#include "solvers/mprgp/coupled_preconditioner.hpp"
#include "solvers/mprgp/coupled_touched_rows.hpp"
#include "solvers/mprgp/mprgp_coupled_setup.hpp"
#include "solvers/mprgp/mprgp_engine.hpp"
#include "solvers/mprgp/mprgp_kernels.hpp"

#include <algorithm>
#include <cmath>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace cb {

/// One solve; every vector is allocated before the loop.
class CoupledRun {
public:
    /// With precond = scaled the run iterates on the QP in y = D^1/2 x (ScaledVariables, formed on
    /// the solver's clock) and measures, monitors and returns x of `qp`, the QP in the file.
    CoupledRun(const QpView& qp, const MprgpCoupledSettings& st, const SolveContext& context)
        : m_loop("mprgp-coupled", qp, st.common, context), m_original(qp), m_choice(PrecondChoice::make(qp, st)),
          m_scaled(ScaledVariables::make(qp, m_choice.name, st)),
          m_qp(m_scaled ? QpView{qp.A, m_scaled->b, m_scaled->J, qp.c, m_scaled->y0} : qp), m_A(m_qp.A), m_a_op(qp),
          m_J(m_qp.J), m_c(m_qp.c), m_st(st), m_ctx(context), m_n(qp.n()), m_m(qp.m()),
          m_unscale(m_scaled ? &m_scaled->unscale : nullptr)
    {
        m_a_op.scale_by(m_unscale);  // precond = scaled: products with U A U, A not copied
    }
    /// Setup, the engine's iteration (solvers/mprgp/mprgp_engine.hpp), the returned point.
    SolverResult run();

    // --- the engine's steps ---
    Evaluation evaluate(std::string& why);
    bool notify(StepKind last);
    bool proportional();
    bool feasible() const { return m_x_feasible; }
    Trial cg_trial(std::string& why);
    SolveStatus expansion(std::string& why);
    SolveStatus proportioning(std::string& why);

private:
    void rows_times(const Vec& v, Vec& out) const
    {
        const bool prefetch = row_gather_prefetches(m_n);
        const std::array<const double*, 1> read = {v.data()};
        for (Eigen::Index i = 0; i < m_m; ++i) {
            if (prefetch) prefetch_row_ahead(m_J, i, read);
            out[i] = row_dot(m_J, i, v);
        }
    }
    /// v += a J' coef over the rows with coef_i != 0.
    void add_rows_transpose(const Vec& coef, double a, Vec& v) const
    {
        const bool prefetch = row_gather_prefetches(m_n);
        const std::array<const double*, 1> written = {v.data()};
        for (Eigen::Index i = 0; i < m_m; ++i) {
            if (prefetch && coef[std::min(i + ROW_GATHER_AHEAD, m_m - 1)] != 0.0) prefetch_row_ahead(m_J, i, written);
            if (coef[i] != 0.0) row_axpy(m_J, i, a * coef[i], v);
        }
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
    /// d'Ad over the touched rows of A (A symmetric, d sparse); precond = scaled: d'UAUd.
    double d_a_d() const { return m_rows_of_a->d_a_d(m_touched, m_d); }
    /// The nonzeros of A's columns at the touched DOFs (the work of d_a_d or add_a_d).
    double touched_nonzeros() const
    {
        const int* outer = m_A.outerIndexPtr();
        long nz = 0;
        for (int j : m_touched) nz += outer[j + 1] - outer[j];
        return static_cast<double>(nz);
    }
    /// g += A d (columns of A = rows, A symmetric), O(nnz of the touched columns); precond =
    /// scaled: g += U A U d.
    void add_a_d(Vec& g) const { m_rows_of_a->add_a_d(m_touched, m_d, g); }
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
    /// coefficient). The step, phi = g and the free DOFs' stationarity share one pass; the dots stay
    /// Eigen's own (one fused pass over the ten vectors measured 3x slower than short passes,
    /// flank_press's n, cold cache; and the dots' order of summation decides the CG chains' rounding).
    void face_gradient(bool with_z, const Vec* ap = nullptr, double alpha = 0.0)
    {
        settle_direction();  // z changes below
        if (ap != nullptr) {
            // x -= alpha p, g -= alpha Ap, phi = g and the free DOFs' largest |phi_j| w_j in one pass
            m_stat_free = cg_step_pass(alpha, m_p, *ap, m_free_weight, m_x, m_g, m_phi);
            m_jx -= alpha * m_jp;  // J x by the step's own J p (the trial's); restarts form it afresh
        } else {
            m_phi = m_g;
            m_stat_free = m_n > 0 ? m_phi.cwiseAbs().cwiseProduct(m_free_weight).maxCoeff() : 0.0;
        }
        // m_stat_free: the free DOFs' stationarity for evaluate. Only the face DOFs change below, and
        // their weight is 0; a maximum is the same in any order.

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
        if (ap != nullptr) {
            two_dots(z, m_phi, *ap, m_zphi, m_zap);  // z'phi and z'Ap as Eigen's two dots, z read once
        } else {
            m_zphi = z.dot(m_phi);
            m_zap = 0.0;
        }
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
        if (with_z) m_p_pending = false;  // p = z below
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
    /// Alg. 3's safeguard after an expansion or a proportioning. Returns false on time out.
    bool safeguard_steps(double f_before, double& f_now);
    /// x = P(x - alpha_bar phi) (Alg. 1), from P(x) of an infeasible chain iterate; false on time out.
    bool expand();
    /// The exact step along -beta, then P; 0 when beta'A beta <= 0, -1 on time out, else 1.
    int proportion();
    /// The criterion at a feasible x (with the bodies' rigid motion when the rest meets the rule).
    bool criterion();

    /// The preconditioned face direction z: m_z, or phi itself without a preconditioner.
    const Vec& direction() const { return m_precond || m_jacobi ? m_z : m_phi; }
    /// p = z - beta p now, when an accepted CG step left it to the next product and z is to change.
    void settle_direction()
    {
        if (!m_p_pending) return;
        m_p = direction() - m_p_beta * m_p;
        m_p_pending = false;
    }
    /// The measure's rigid half at the iterate's x (precond = scaled: read through D^-1/2, not formed).
    double bodies_motion() const
    {
        return m_unscale != nullptr ? m_scale.body_motion_scaled(*m_unscale, m_x, m_mu)
                                    : m_scale.body_motion(m_x, m_mu);
    }
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
    const QpView m_qp;                          // the QP iterated on: m_original or m_scaled's (A: the original's)
    const SpMat& m_A;
    AOperator m_a_op;  // the product with A (prepared in the setup)
    std::unique_ptr<TouchedRowsOfA> m_rows_of_a;  // d'Ad and A d for sparse d (after m_a_op's prepare)
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
    double m_gamma2 = 1.0;  // Gamma^2
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
    bool m_p_pending = false;          // p = z - m_p_beta p is still to be formed (settle_direction)
    double m_p_beta = 0.0;
    bool m_x_feasible = true;
    double m_native = 0.0, m_error = 0.0, m_face_error = 0.0, m_beta2 = 0.0, m_phi2 = 0.0;
    double m_primal = 0.0, m_beta2_upper = 0.0;
    double m_stat_free = 0.0;  // max |phi_j| w_j over the DOFs no face row touches (face_gradient)
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

}  // namespace cb
