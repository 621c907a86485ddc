// `mprgp`: extended monotone MPRGP on decoupled constraints (ALGORITHMS.md §3).
// Ref: Li et al., "Deformable Objects Collision Handling with Fast Convergence", CGF 2015,
//      Alg. 1 (outline), Alg. 2 (CG chain), Alg. 3 (safeguards), eq. (13)-(20), Appendix B.
// The hot loop is written for cost: one A-product per CG step (the projected objective
// F(P(y)) comes from scalar recurrences plus a sparse correction), O(nnz(J)) row work, and
// fused vector updates, so that an iteration costs about one Jacobi-PCG iteration.
#include "solvers/mprgp.hpp"
#include "solvers/solve_loop.hpp"

#include "solvers/a_product.hpp"
#include "solvers/accuracy.hpp"
#include "solvers/accuracy_rows.hpp"
#include "solvers/decouple.hpp"
#include "solvers/format_number.hpp"
#include "solvers/ichol.hpp"
#include "solvers/mprgp_deflation.hpp"
#include "solvers/mprgp_kernels.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

namespace cb {

namespace {

/// Every setting of `mprgp`, declared once (settings.hpp SettingsTable).
const SettingsTable<MprgpSettings>& mprgp_settings_table()
{
    static const SettingsTable<MprgpSettings> table =
        SettingsTable<MprgpSettings>()
            .choice(
                "precond", &MprgpSettings::precond, {"none", "jacobi", "ichol"},
                "none | jacobi: D-weighted projection of D^-1 g onto the face (J_A z = 0) | ichol: Q M^-1 Q g with M "
                "the incomplete Cholesky factor of the face matrix Q A Q + normal block, refactored when the face "
                "changes (docs/preconditioners.md)")
            .number("gamma", &MprgpSettings::gamma, 0.0, 1e300,
                    "proportioning constant Gamma > 0 (Alg. 1); default 10 with precond = ichol",
                    // With ichol the CG chains are short and cheap to restart; Gamma = 1 (the paper's)
                    // then spends most iterations proportioning (docs/preconditioners.md).
                    [](const MprgpSettings& s) { return s.precond == "ichol" ? 10.0 : s.gamma; })
            .choice("alpha", &MprgpSettings::alpha, {"power", "authors"},
                    "power (stop at rel. change 1e-3, warm start) | authors (||v_k+1 - v_k|| <= tol, <= 1001 products, "
                    "cold)")
            .integer("power_max", &MprgpSettings::power_max, 1, 1000000, "max power-method products (alpha = power)")
            .choice("objective", &MprgpSettings::objective, {"cheap", "recompute"},
                    "cheap: F(P(y)) without an extra A-product | recompute: the authors' 2 products per CG step")
            .integer("safeguard_max", &MprgpSettings::safeguard_max, 1, 100000000,
                     "max repeats of Alg. 3's safeguard after one step")
            .choice(
                "expansion", &MprgpSettings::expansion, {"paper", "precond"},
                "paper: x = P(x - alpha_bar phi), alpha_bar = 2/||A|| (Alg. 1) | precond: x = P(x - a z) with z the "
                "preconditioner's face direction and a = z'g / z'Az (one more A-product; Alg. 3's safeguard still "
                "guarantees descent); docs/preconditioners.md")
            .number("ichol_refactor", &MprgpSettings::ichol_refactor, -1e-300, 1.0,
                    "precond = ichol: refactor the face matrix when more than this fraction of the rows changed face "
                    "since the last factorization (0: at every face change; 1: factor once)")
            .choice("deflation", &MprgpSettings::deflation, {"none", "rigid"},
                    "none | rigid: each new face gets a Galerkin step over the slow rigid modes of each body (from "
                    "x0, projected on the face) and the preconditioner is balanced with them; default rigid with "
                    "precond = ichol (docs/preconditioners.md)",
                    // Measured on the whole stress suite: with ichol it never costs iterations and cuts the
                    // stiff dino's 3.4x cg to 1.3x; with jacobi the default stays the paper's (CI counters).
                    [](const MprgpSettings& s) { return s.precond == "ichol" ? std::string("rigid") : s.deflation; });
    return table;
}

}  // namespace

MprgpSettings MprgpSettings::from_json(const nlohmann::json& settings)
{
    return read_settings(settings, "mprgp", mprgp_settings_table());
}

nlohmann::json MprgpSettings::to_json() const { return write_settings(*this, mprgp_settings_table()); }

SolverEntry mprgp_entry()
{
    return solver_entry<MprgpSolver>("mprgp", mprgp_settings_table(),
                                     "extended monotone MPRGP on decoupled J (paper Alg. 1-3, closed-form operators)",
                                     "decoupled rows only (the harness decouples a coupled J first)");
}

namespace {

/// One solve: the workspace is allocated once, before the loop.
class MprgpRun {
public:
    MprgpRun(const QpView& qp, const MprgpSettings& settings, const SolveContext& context)
        : m_qp(qp), m_A(qp.A), m_a_op(qp.A), m_J(qp.J), m_b(qp.b), m_c(qp.c), m_st(settings), m_ctx(context),
          m_n(qp.n()), m_m(qp.m()), m_loop("mprgp", qp, settings.common, context)
    {
    }

    SolverResult run();

private:
    // --- products and objective ---
    void product(const Vec& v, Vec& out)
    {
        a_product(m_a_op, v, out);
        ++m_cnt.a_products;
    }
    /// out = A v; returns v'Av and sets vg = v'g (one pass over A).
    double product_dot(const Vec& v, Vec& out, double& vg)
    {
        double dot_g = 0.0;
        const double vav = a_product_dots(m_a_op, v, out, m_g, m_rows.dof_in_row.data(), dot_g);
        ++m_cnt.a_products;
        vg = dot_g + m_pg_rows;  // the row DOFs' part comes from evaluate_rows (face form, no cancellation)
        return vav;
    }
    double objective_from_gradient() const { return 0.5 * (m_x.dot(m_g) - m_b.dot(m_x)); }
    void refresh_gradient()
    {
        product(m_x, m_g);
        m_g -= m_b;
    }
    long project_x()
    {
        ++m_cnt.projections;
        return project_decoupled(m_J, m_c, m_rows, m_x, m_x);
    }
    bool over_time() const { return m_loop.time_up(); }

    /// a'g computed as a'phi on active rows (a in null(J_A)): no cancellation against J_A' lambda.
    double face_dot(const Vec& a) const;
    /// Chain start at a feasible x with an exact g: face, z, p, F. With `galerkin` (after a start,
    /// expansion or proportioning) and deflation = rigid, first the Galerkin steps on the face.
    void restart(bool galerkin = false);
    /// deflation = rigid: minimise F over x + V y (V the face's rigid modes), clipped to stay
    /// feasible; a blocking row joins the face and the step repeats on the new face.
    void galerkin_steps();
    /// deflation = rigid: V for the current face when it changed.
    void update_deflation_face();
    /// z = the face preconditioner applied to g (ichol or jacobi), balanced with V when
    /// deflation = rigid: z = P' M^-1 P g + V E^+ V'g. J_A z = 0.
    void face_precondition(Vec& z);
    /// Row pass at the current x: Jx, Jg, Jp, lambda, ||beta||^2, phitilde'phi, KKT pieces.
    void evaluate_rows();
    double error_with_bodies();  ///< m_error with the bodies' rigid motion, when the rest meets the rule
    /// Correction F(P(x - a p)) - F(x - a p) with the sparse d = J' lambda (Ap known).
    double projection_correction(double alpha);
    /// objective = recompute: the authors' F(P(x - alpha p)) from an explicit projection and a
    /// second A-product. Returns it; the decision stays the difference form's (delta, accept),
    /// and the direct comparison is only recorded (m_direct_*), to show where it would differ.
    double recompute_objective(double alpha, double delta, bool accept);
    /// Alg. 3 safeguard: repeat x = P(x - alpha_bar g) while F went up. Returns false on time out.
    bool safeguard(double f_before, double& f_now);
    bool expansion();
    bool proportioning();
    bool call_monitor(StepKind step);

    const QpView& m_qp;
    const SpMat& m_A;
    AOperator m_a_op;  // the product with A (prepared in the setup)
    const SpMat& m_J;
    const Vec& m_b;
    const Vec& m_c;
    const MprgpSettings& m_st;
    const SolveContext& m_ctx;
    const Eigen::Index m_n, m_m;

    SolveLoop m_loop;  ///< the clock (started with the run: setup included), limits, monitor
    Counters m_cnt;
    DecoupledRows m_rows;
    Vec m_dinv;
    bool m_ichol = false;
    bool m_precond_expansion = false;  // expansion = precond, resolved at setup
    IncompleteCholeskyPreconditioner m_ic;
    std::vector<char> m_face_factored;  // active set the ichol factor was built for
    bool m_face_factor_failed = false;
    std::string m_face_factor_error;
    bool m_deflate = false;
    RigidDeflation m_defl;
    std::vector<char> m_defl_face;  // active set V was built for
    long m_galerkin_steps = 0, m_deflation_faces = 0;
    Vec m_gd, m_gad;  // Galerkin direction and its A-product
    Vec m_work;
    double m_alpha_bar = 0.0;
    AccuracyScale m_scale;

    Vec m_x, m_g, m_z, m_p, m_Ap, m_tmp, m_d, m_lambda, m_jx, m_jg, m_jp;
    std::vector<char> m_active;
    std::vector<int> m_touched;

    // Scalars along the chain.
    double m_rz = 0.0;        // z'g
    double m_gg_out = 0.0;    // sum of g_j^2 over DOFs in no row
    double m_pg_rows = 0.0;   // p'phi over the DOFs of rows (from evaluate_rows)
    double m_ginf_free = 0;   // max |g_j| / D_jj over DOFs in no row (the measure's stationarity part)
    double m_f_x = 0.0;       // F(x)
    double m_corr_x = 0.0;    // F(P(x)) - F(x)
    double m_f_proj_x = 0.0;  // F(P(x)) (objective = recompute keeps it directly)
    // objective = recompute: what its direct F would have decided (reported in info).
    Vec m_a_proj_y;                   // A P(y)
    long m_trial_steps = 0;           // CG trial steps, each with the extra product
    long m_direct_disagreements = 0;  // trials where comparing direct F values decides otherwise
    double m_direct_gap = 0.0;        // max |(F(P(y)) - F(P(x)))_direct - delta|

    // Row pass results.
    double m_beta2 = 0.0, m_phitilde_phi = 0.0, m_native = 0.0, m_error = 0.0;
    double m_face_error = 0.0;  // accuracy error without the primal part (the face problem's residual)
    bool m_infeasible = false;
    long m_active_count = 0;
};

double MprgpRun::face_dot(const Vec& a) const
{
    double sum = 0.0;
    for (Eigen::Index j = 0; j < m_n; ++j)
        if (!m_rows.dof_in_row[static_cast<size_t>(j)]) sum += a[j] * m_g[j];
    const int* outer = m_J.outerIndexPtr();
    const int* inner = m_J.innerIndexPtr();
    const double* val = m_J.valuePtr();
    for (Eigen::Index i = 0; i < m_m; ++i) {
        const double t = m_active[static_cast<size_t>(i)] ? row_dot(m_J, i, m_g) * m_rows.inv_s[i] : 0.0;
        for (int k = outer[i]; k < outer[i + 1]; ++k)
            if (val[k] != 0.0) sum += a[inner[k]] * (m_g[inner[k]] - t * val[k]);
    }
    return sum;
}

void MprgpRun::update_deflation_face()
{
    if (!m_defl_face.empty() && m_defl_face == m_active) return;
    if (m_defl.set_face(m_A, m_J, m_rows, m_active, &m_cnt.work_flops)) m_cnt.a_products += RigidDeflation::MODES;
    ++m_deflation_faces;
    m_defl_face = m_active;
}

void MprgpRun::galerkin_steps()
{
    const int* outer = m_J.outerIndexPtr();
    const int* inner = m_J.innerIndexPtr();
    const double* val = m_J.valuePtr();
    // Each clipped step adds a row to the face: at most m repeats; a few suffice in practice.
    for (long repeat = 0; repeat <= m_m; ++repeat) {
        update_deflation_face();
        free_gradient(m_J, m_rows, m_active, m_g, m_tmp);  // phi: V'g in face form
        m_defl.coarse(m_tmp, m_gd, m_gad);
        m_cnt.work_flops += m_defl.apply_flops();
        const double dg = m_gd.dot(m_tmp);
        if (!(dg > 0.0) || !std::isfinite(dg)) return;
        // F(x - a d) decreases for a in (0, 2) (d'Ad = d'g): clip a <= 1 to the feasible set.
        double step = 1.0;
        long blocking = -1;
        for (Eigen::Index i = 0; i < m_m; ++i) {
            if (m_active[static_cast<size_t>(i)] || m_rows.s[i] <= 0.0) continue;
            double jd = 0.0, jx = 0.0;
            for (int k = outer[i]; k < outer[i + 1]; ++k) {
                jd += val[k] * m_gd[inner[k]];
                jx += val[k] * m_x[inner[k]];
            }
            if (jd > 0.0 && (jx - m_c[i]) < step * jd) {
                step = std::max(0.0, (jx - m_c[i]) / jd);
                blocking = i;
            }
        }
        if (step > 0.0) {
            m_x -= step * m_gd;
            m_g -= step * m_gad;
            ++m_galerkin_steps;
        }
        if (blocking < 0) return;
        active_rows(m_J, m_c, m_rows, m_x, m_active);
        m_active[static_cast<size_t>(blocking)] = 1;  // the row the step stopped at
        if (over_time()) return;
    }
}

void MprgpRun::face_precondition(Vec& z)
{
    const Vec* g = &m_g;
    if (m_deflate) {
        // P g = g - A V y1 with y1 = E^+ V'g (V'g in face form); the coarse part V y1 is added back.
        free_gradient(m_J, m_rows, m_active, m_g, m_tmp);
        m_defl.coarse(m_tmp, m_gd, m_gad);
        m_tmp = m_g - m_gad;
        g = &m_tmp;
        m_cnt.work_flops += m_defl.apply_flops();
    }
    if (m_ichol) {
        if (m_ic.ready())
            ichol_face_precondition(m_ic, m_J, m_rows, m_active, *g, m_work, z, &m_cnt.work_flops);
        else
            z.setZero(m_n);
    } else {
        jacobi_face_precondition(m_J, m_rows, m_active, m_dinv, *g, z);
    }
    if (m_deflate) {
        m_defl.deflate(z);  // P' M^-1 P g
        z += m_gd;
        m_cnt.work_flops += m_defl.apply_flops();
    }
}

void MprgpRun::restart(bool galerkin)
{
    active_rows(m_J, m_c, m_rows, m_x, m_active);
    if (m_deflate) {
        if (galerkin) {
            galerkin_steps();
            active_rows(m_J, m_c, m_rows, m_x, m_active);
        }
        update_deflation_face();
    }
    if (m_ichol) {
        // The factor belongs to one face: rebuild it only when the face changed.
        // Q M^-1 Q is a valid (SPD on the face) preconditioner for any SPD M, so a factor of an
        // older face only costs quality: rebuild it when the face drifted by more than
        // ichol_refactor of the rows.
        long changed = 0;
        if (m_ic.ready())
            for (size_t i = 0; i < m_active.size(); ++i) changed += m_active[i] != m_face_factored[i];
        if (!m_ic.ready() || static_cast<double>(changed) > m_st.ichol_refactor * static_cast<double>(m_m)) {
            if (!m_ic.factor(face_matrix(m_A, m_J, m_rows, m_active, &m_cnt.work_flops), m_face_factor_error,
                             &m_cnt.work_flops))
                m_face_factor_failed = true;
            m_face_factored = m_active;
            ++m_cnt.precond_factorizations;
        }
    }
    face_precondition(m_z);
    ++m_cnt.precond_applications;
    m_p = m_z;
    m_rz = face_dot(m_z);
    m_gg_out = 0.0;
    m_ginf_free = 0.0;
    for (Eigen::Index j = 0; j < m_n; ++j)
        if (!m_rows.dof_in_row[static_cast<size_t>(j)]) {
            m_ginf_free = std::max(m_ginf_free, std::abs(m_g[j]) * m_scale.inv_diag[j]);
            m_gg_out += m_g[j] * m_g[j];
        }
    m_f_x = objective_from_gradient();
    m_corr_x = 0.0;
    m_f_proj_x = m_f_x;
}

double MprgpRun::error_with_bodies()
{
    // m_error holds every part but the bodies' rigid motion (solvers/body_motion.hpp): added only
    // when the rest already meets the rule, the one time it can change the decision.
    if (!m_loop.rule_holds(m_native, m_error)) return m_error;
    return std::max(m_error, m_scale.body_motion(m_x, m_lambda));
}

void MprgpRun::evaluate_rows()
{
    const int* outer = m_J.outerIndexPtr();
    const int* inner = m_J.innerIndexPtr();
    const double* val = m_J.valuePtr();
    // Norms are summed part by part (DOFs outside every row, then each row's DOFs; rows share
    // no DOF), never as ||g||^2 minus the active part: that difference cancels catastrophically
    // when the active rows carry almost all of g near the solution.
    double beta2 = 0.0, pb2 = m_gg_out, phi2 = m_gg_out, ptp_corr = 0.0;
    double stat = m_ginf_free, pg_rows = 0.0;
    RowParts rows;  // the accuracy measure's row parts
    bool infeasible = false;
    long active_count = 0;
    for (Eigen::Index i = 0; i < m_m; ++i) {
        double jx = 0.0, jg = 0.0, jp = 0.0;
        for (int k = outer[i]; k < outer[i + 1]; ++k) {
            const int j = inner[k];
            jx += val[k] * m_x[j];
            jg += val[k] * m_g[j];
            jp += val[k] * m_p[j];
        }
        m_jx[i] = jx;
        m_jg[i] = jg;
        m_jp[i] = jp;
        double lambda = 0.0, t = 0.0;
        if (m_active[static_cast<size_t>(i)]) {
            ++active_count;
            t = jg * m_rows.inv_s[i];
            lambda = std::max(0.0, t);
            beta2 += std::min(0.0, t) * std::min(0.0, t) * m_rows.s[i];
        } else if (m_rows.s[i] > 0.0) {
            if (jx < m_c[i] - active_tolerance(m_c[i])) infeasible = true;
            // Projection of x - alpha_bar phi on a free row (J_i phi = J_i g there).
            const double l = (m_c[i] - jx + m_alpha_bar * jg) * m_rows.inv_s[i];
            if (l > 0.0) ptp_corr += l * jg;
        }
        m_lambda[i] = lambda;
        for (int k = outer[i]; k < outer[i + 1]; ++k) {
            if (val[k] == 0.0) continue;
            const double gk = m_g[inner[k]];
            const double r_pb = gk - val[k] * lambda;  // (phi + beta)_k
            const double r_phi = gk - val[k] * t;      // phi_k
            pb2 += r_pb * r_pb;
            phi2 += r_phi * r_phi;
            pg_rows += m_p[inner[k]] * r_phi;
            stat = std::max(stat, std::abs(r_pb) * m_scale.inv_diag[inner[k]]);
        }
        rows.add_row(m_c[i], jx - m_c[i], lambda, m_scale.inv_row_norm[i], m_scale.length_per_multiplier[i]);
    }
    m_beta2 = beta2;
    m_pg_rows = pg_rows;
    // phitilde = phi - J' l / alpha_bar (eq. 13 through one projection).
    m_phitilde_phi = phi2 - ptp_corr / m_alpha_bar;
    m_native = std::sqrt(pb2);
    m_infeasible = infeasible;
    m_active_count = active_count;
    const RowParts parts = rows.scaled(m_scale.inv_length, m_scale.inv_energy);
    const double face =
        std::max(std::max(stat * m_scale.inv_length, std::max(parts.dual, parts.complementarity)), parts.gap);
    const double error = std::max(face, parts.primal);
    m_error = std::isfinite(error) ? error : std::numeric_limits<double>::infinity();
    m_face_error = std::isfinite(face) ? face : std::numeric_limits<double>::infinity();
}

double MprgpRun::projection_correction(double alpha)
{
    // F(y + d) = F(y) + d'(Ay - b) + 1/2 d'Ad with d = J' lambda, lambda_i = max(0, (c_i - J_i y)/s_i).
    const int* outer = m_J.outerIndexPtr();
    const int* inner = m_J.innerIndexPtr();
    const double* val = m_J.valuePtr();
    double dg = 0.0;
    m_touched.clear();
    for (Eigen::Index i = 0; i < m_m; ++i) {
        // Active rows stay on their face (J_A p = 0 in exact arithmetic): their rounding-level
        // drift must not count as a violation, or it would swamp the tiny F decreases near
        // the solution.
        if (m_rows.s[i] <= 0.0 || m_active[static_cast<size_t>(i)]) continue;
        const double l = (m_c[i] - (m_jx[i] - alpha * m_jp[i])) * m_rows.inv_s[i];
        if (l <= 0.0) continue;
        double jgy = 0.0;
        for (int k = outer[i]; k < outer[i + 1]; ++k) {
            const int j = inner[k];
            jgy += val[k] * (m_g[j] - alpha * m_Ap[j]);
            m_d[j] += l * val[k];
            m_touched.push_back(j);
        }
        dg += l * jgy;
    }
    if (m_touched.empty()) return 0.0;
    ++m_cnt.projections;
    // d'Ad over the touched rows of A only (A symmetric, d sparse).
    const int* a_outer = m_A.outerIndexPtr();
    const int* a_inner = m_A.innerIndexPtr();
    const double* a_val = m_A.valuePtr();
    double dad = 0.0;
    for (int j : m_touched) {
        const double dj = m_d[j];
        if (dj == 0.0) continue;
        double s = 0.0;
        for (int k = a_outer[j]; k < a_outer[j + 1]; ++k) s += a_val[k] * m_d[a_inner[k]];
        dad += dj * s;
    }
    // Touched DOFs may repeat (explicit zeros, shared columns): clear after the sum.
    for (int j : m_touched) m_d[j] = 0.0;
    return dg + 0.5 * dad;
}

double MprgpRun::recompute_objective(double alpha, double delta, bool accept)
{
    m_tmp = m_x - alpha * m_p;
    const long moved = project_decoupled(m_J, m_c, m_rows, m_tmp, m_tmp);
    ++m_cnt.projections;
    product(m_tmp, m_a_proj_y);
    const double f_proj_y = 0.5 * m_tmp.dot(m_a_proj_y) - m_b.dot(m_tmp);
    ++m_trial_steps;
    // The authors' rule compares the two F values: both round at about eps |F|, which exceeds
    // the decrease of a CG step near the solution, so it rejects steps that decrease F.
    const double direct = f_proj_y - m_f_proj_x;
    const bool direct_accept = moved > 0 ? direct < 0.0 : direct <= 0.0;
    if (direct_accept != accept) ++m_direct_disagreements;
    m_direct_gap = std::max(m_direct_gap, std::abs(direct - delta));
    return f_proj_y;
}

bool MprgpRun::safeguard(double f_before, double& f_now)
{
    auto increased = [&](double f) { return f > f_before + 1e-12 * (std::abs(f_before) + std::abs(f)); };
    long repeats = 0;
    while (increased(f_now) && repeats < m_st.safeguard_max) {
        m_x -= m_alpha_bar * m_g;
        project_x();
        refresh_gradient();
        f_now = objective_from_gradient();
        ++m_cnt.safeguard_steps;
        ++repeats;
        if (over_time()) return false;
    }
    return true;
}

bool MprgpRun::expansion()
{
    const double f_before = m_f_x + m_corr_x;  // F(P(x))
    if (m_infeasible) {
        project_x();  // y = P(x)
        refresh_gradient();
    }
    active_rows(m_J, m_c, m_rows, m_x, m_active);
    if (m_precond_expansion) {
        // The preconditioned free gradient with its exact step: on stiff problems alpha_bar =
        // 2/||A|| moves the soft DOFs by almost nothing, so the face grows by a few rows per
        // expansion; this step reaches the rows the CG chain was heading for.
        if (m_ichol && m_ic.ready())
            ichol_face_precondition(m_ic, m_J, m_rows, m_active, m_g, m_work, m_tmp, &m_cnt.work_flops);
        else
            jacobi_face_precondition(m_J, m_rows, m_active, m_dinv, m_g, m_tmp);
        ++m_cnt.precond_applications;
        product(m_tmp, m_Ap);
        const double dad = m_tmp.dot(m_Ap);
        const double dg = face_dot(m_tmp);
        const double step = dad > 0.0 && dg > 0.0 && std::isfinite(dad) ? dg / dad : m_alpha_bar;
        m_x -= step * m_tmp;
    } else {
        free_gradient(m_J, m_rows, m_active, m_g, m_tmp);  // phi(y)
        m_x -= m_alpha_bar * m_tmp;
    }
    project_x();
    refresh_gradient();
    double f_now = objective_from_gradient();
    ++m_cnt.expansion_steps;
    const bool ok = safeguard(f_before, f_now);
    restart(true);
    return ok;
}

bool MprgpRun::proportioning()
{
    const double f_before = m_f_x;
    chopped_gradient(m_J, m_rows, m_active, m_g, m_tmp);  // d = beta
    product(m_tmp, m_Ap);
    const double dad = m_tmp.dot(m_Ap);
    const double gd = m_g.dot(m_tmp);
    if (!(dad > 0.0) || !std::isfinite(dad)) return false;
    const double alpha_p = gd / dad;
    m_x -= alpha_p * m_tmp;
    // -beta keeps active rows feasible and free rows untouched (rows share no DOF), so the
    // projection is a no-op in exact arithmetic; refresh g only when it did move x.
    if (project_x() > 0)
        refresh_gradient();
    else
        m_g -= alpha_p * m_Ap;
    double f_now = objective_from_gradient();
    ++m_cnt.proportioning_steps;
    const bool ok = safeguard(f_before, f_now);
    restart(true);
    return ok;
}

bool MprgpRun::call_monitor(StepKind step)
{
    IterationInfo info;
    info.iteration = m_cnt.iterations;
    info.step = step;
    info.x = &m_x;
    info.lambda = &m_lambda;
    info.native_residual = m_native;
    info.active_set_size = m_active_count;
    info.counters = &m_cnt;
    return m_loop.notify(info);
}

SolverResult MprgpRun::run()
{
    SolverResult result;
    const CommonSettings& common = m_st.common;
    result.info["precond"] = m_st.precond;
    result.info["objective"] = m_st.objective;
    if (!is_decoupled(m_J)) {
        result.status = SolveStatus::INVALID_INPUT;
        result.message = "mprgp: J is not decoupled (two rows touch the same vertex, vertex = column / 3); "
                         "decouple the problem first (decouple = authors | random | depth) or use mprgp-coupled";
        return m_loop.finish(result, result.status);
    }
    // --- setup: diagonal, row data, power method ---
    m_dinv = Vec::Ones(m_n);
    if (m_st.precond == "jacobi") {
        const Vec diag = m_A.diagonal();
        for (Eigen::Index j = 0; j < m_n; ++j) {
            if (!(diag[j] > 0.0)) {
                result.status = SolveStatus::INVALID_INPUT;
                result.message = "mprgp: precond=jacobi needs a positive diagonal of A; A(" + std::to_string(j) + "," +
                                 std::to_string(j) + ") = " + std::to_string(diag[j]);
                return m_loop.finish(result, result.status);
            }
            m_dinv[j] = 1.0 / diag[j];
        }
    }
    m_ichol = m_st.precond == "ichol";
    m_precond_expansion = m_st.expansion == "precond";
    if (m_st.deflation == "rigid") {
        m_deflate = m_defl.build(m_A, m_J, m_qp.x0, RigidDeflation::SLOW_RAYLEIGH);
        m_cnt.a_products += m_defl.build_products();
    }
    m_rows = make_decoupled_rows(m_J, m_dinv);
    for (Eigen::Index i = 0; i < m_m; ++i) {
        if (m_rows.s[i] <= 0.0 && m_c[i] > active_tolerance(m_c[i])) {
            result.status = SolveStatus::INFEASIBLE;
            result.message = "mprgp: row " + std::to_string(i) + " of J is zero but c_i = " + std::to_string(m_c[i]) +
                             " > 0: the feasible set is empty";
            return m_loop.finish(result, result.status);
        }
    }
    m_a_op.prepare(AFormat::BSR, static_cast<int>(m_st.common.threads));  // 3x3 blocks when A has them
    Vec eigenvector;
    const bool warm = m_ctx.eigenvector != nullptr && m_ctx.eigenvector->size() == m_n;
    if (warm) eigenvector = *m_ctx.eigenvector;
    const PowerRule rule = m_st.alpha == "authors" ? PowerRule::AUTHORS : PowerRule::POWER;
    const long power_max = rule == PowerRule::AUTHORS ? 1001 : m_st.power_max;
    const PowerResult power = power_method(m_a_op, eigenvector, rule, power_max, common.tol, warm, common.seed,
                                           &SolveLoop::time_up_callback, &m_loop);
    m_cnt.power_products = power.products;
    m_cnt.a_products += power.products;
    if (m_ctx.eigenvector) *m_ctx.eigenvector = eigenvector;
    // The power estimate approaches ||A|| from below; alpha_bar must stay <= 2 / ||A|| (Appendix B),
    // so our default rounds rho up by 1%. The authors' variant uses the estimate as is.
    const double rho = power.estimate * (rule == PowerRule::POWER ? 1.01 : 1.0);
    m_alpha_bar = rho > 0.0 ? 2.0 / rho : 1.0;
    result.info["power"] = {{"rule", m_st.alpha},
                            {"products", power.products},
                            {"estimate", power.estimate},
                            {"rho", rho},
                            {"warm_start", power.warm}};
    result.info["alpha_bar"] = m_alpha_bar;
    m_scale = accuracy_scale(m_qp);
    m_cnt.a_products += m_scale.a_products;
    const bool setup_in_time = m_loop.end_setup();
    result.info["power"]["seconds"] = m_loop.setup_s();
    if (!setup_in_time) {
        result.counters = m_cnt;
        return m_loop.finish(result, SolveStatus::TIME_LIMIT);
    }

    // --- solve ---
    m_x = m_qp.x0;
    m_g.resize(m_n);
    m_z.resize(m_n);
    m_p.resize(m_n);
    m_Ap.resize(m_n);
    m_tmp.resize(m_n);
    m_work.resize(m_n);
    m_d = Vec::Zero(m_n);
    m_lambda = Vec::Zero(m_m);
    m_jx.resize(m_m);
    m_jg.resize(m_m);
    m_jp.resize(m_m);
    m_touched.reserve(static_cast<size_t>(m_J.nonZeros()));
    project_x();  // x = P(x0)
    refresh_gradient();
    restart(true);

    const bool recompute = m_st.objective == "recompute";
    const double gamma2 = m_st.gamma * m_st.gamma;
    StepKind last_step = StepKind::START;
    SolveStatus status = SolveStatus::NOT_RUN;
    std::string why;  // a breakdown's reason (the loop's own exits need none)
    while (true) {
        if (m_face_factor_failed) {
            status = SolveStatus::DIVERGED;
            why = "precond=ichol: " + m_face_factor_error;
            break;
        }
        evaluate_rows();
        if (!std::isfinite(m_native)) {
            status = m_loop.check(m_cnt.iterations, false, false);  // DIVERGED: non-finite iterate
            break;
        }
        // Converged means at a feasible x (an infeasible chain iterate ends in an expansion).
        bool converged = !m_infeasible && m_loop.criterion_met(m_native, [&] { return error_with_bodies(); });
        if (converged) {
            // Confirm at an exact gradient (the recursive g drifts along long chains); the
            // accuracy rule is confirmed by the common measure itself.
            refresh_gradient();
            restart();
            evaluate_rows();
            converged = m_loop.criterion_met(
                m_native, [&] { return accuracy_from_gradient(m_qp, m_scale, m_x, m_g, m_lambda).max(); });
        }
        if (!call_monitor(last_step)) {
            status = SolveStatus::STOPPED_BY_MONITOR;
            break;
        }
        // Non-finite was tested above; converged, the cap and the time in the loop's order.
        status = m_loop.check(m_cnt.iterations, true, converged);
        if (status != SolveStatus::NOT_RUN) break;
        ++m_cnt.iterations;
        // An infeasible chain iterate whose face problem is already solved cannot improve
        // along the frozen face: end the chain (the expansion step projects).
        const bool face_done = m_infeasible && m_loop.rule_holds(m_native, m_face_error);
        const bool proportional = !face_done && m_beta2 <= gamma2 * m_phitilde_phi;
        if (proportional) {
            // --- CG trial step (Alg. 2) ---
            double pg = 0.0;
            const double pap = product_dot(m_p, m_Ap, pg);
            if (!(pap > 0.0) || !std::isfinite(pap)) {
                if (m_native == 0.0 || pap == 0.0) {
                    status = SolveStatus::STALLED;
                    why = "zero CG direction (p'Ap = 0) above tolerance";
                } else {
                    status = SolveStatus::DIVERGED;
                    why = "p'Ap <= 0 or non-finite: A is not SPD?";
                }
                break;
            }
            // Deflated directions: p'g = z'g only when V'g = 0 exactly; take the exact line minimiser.
            const double alpha = (m_deflate ? pg : m_rz) / pap;
            const double df = -alpha * pg + 0.5 * alpha * alpha * pap;  // F(x - alpha p) - F(x)
            // Both objectives decide on F(P(y)) - F(P(x)) formed from differences: its rounding
            // is relative to the decrease itself, not to |F| (docs/ALGORITHMS.md §3, setting `objective`).
            const double corr_y = projection_correction(alpha);
            const double delta = df + corr_y - m_corr_x;
            // An infeasible trial point must strictly decrease F(P(.)): otherwise a chain
            // converging to an infeasible face minimiser would never end.
            const bool accept = corr_y > 0.0 ? delta < 0.0 : delta <= 0.0;
            double f_proj_y = 0.0;
            if (recompute) f_proj_y = recompute_objective(alpha, delta, accept);
            if (accept) {
                // Fused update: x, g, z = D^-1 g and the dot products in one pass (DOFs in no
                // row; the rows' DOFs are summed below in face form, see face_dot).
                double gg = 0.0, zg = 0.0, zap = 0.0, ginf = 0.0;
                {
                    double* __restrict px = m_x.data();
                    double* __restrict pgr = m_g.data();
                    double* __restrict pz = m_z.data();
                    const double* __restrict pp = m_p.data();
                    const double* __restrict pap_v = m_Ap.data();
                    const double* __restrict pd = m_dinv.data();
                    const double* __restrict pw = m_scale.inv_diag.data();
                    const char* __restrict in_row = m_rows.dof_in_row.data();
                    for (Eigen::Index j = 0; j < m_n; ++j) {
                        px[j] -= alpha * pp[j];
                        const double gj = pgr[j] - alpha * pap_v[j];
                        pgr[j] = gj;
                        const double zj = pd[j] * gj;
                        pz[j] = zj;
                        if (!in_row[j]) {
                            zg += zj * gj;
                            zap += zj * pap_v[j];
                            ginf = std::max(ginf, std::abs(gj) * pw[j]);
                            gg += gj * gj;
                        }
                    }
                }
                if (m_ichol || m_deflate) {
                    // The fused pass computed z = D^-1 g; replace it by the face direction (IC and/or balanced).
                    face_precondition(m_z);
                    zg = face_dot(m_z);
                    zap = m_z.dot(m_Ap);
                } else {
                    // Face correction of z on active rows (J_A z = 0) and the rows' part of the dots.
                    const int* outer = m_J.outerIndexPtr();
                    const int* inner = m_J.innerIndexPtr();
                    const double* val = m_J.valuePtr();
                    for (Eigen::Index i = 0; i < m_m; ++i) {
                        double t = 0.0;
                        if (m_active[static_cast<size_t>(i)]) {
                            double wg = 0.0, jg = 0.0;  // (W g)_i = J_i D^-1 g; J_i g
                            for (int k = outer[i]; k < outer[i + 1]; ++k) {
                                wg += val[k] * m_z[inner[k]];
                                jg += val[k] * m_g[inner[k]];
                            }
                            const double mu = m_rows.r[i] * wg;
                            t = jg * m_rows.inv_s[i];
                            for (int k = outer[i]; k < outer[i + 1]; ++k)
                                m_z[inner[k]] -= mu * val[k] * m_dinv[inner[k]];
                        }
                        for (int k = outer[i]; k < outer[i + 1]; ++k) {
                            if (val[k] == 0.0) continue;
                            const int j = inner[k];
                            zg += m_z[j] * (m_g[j] - t * val[k]);
                            zap += m_z[j] * m_Ap[j];
                        }
                    }
                }
                ++m_cnt.precond_applications;
                const double beta_cg = zap / pap;
                {
                    double* __restrict pp = m_p.data();
                    const double* __restrict pz = m_z.data();
                    for (Eigen::Index j = 0; j < m_n; ++j) pp[j] = pz[j] - beta_cg * pp[j];
                }
                m_rz = zg;
                m_gg_out = gg;
                m_ginf_free = ginf;
                m_f_x += df;
                m_corr_x = corr_y;
                if (recompute) m_f_proj_x = f_proj_y;
                ++m_cnt.cg_steps;
                last_step = StepKind::CG;
                continue;
            }
            // F(P(y)) went up: the chain ends with an (infeasible) trial point -> expansion.
            if (!expansion()) {
                status = SolveStatus::TIME_LIMIT;
                why = "in a safeguard loop";
                break;
            }
            last_step = StepKind::EXPANSION;
        } else if (m_infeasible) {
            // Not proportional at an infeasible chain iterate: no feasible point to proportion from.
            if (!expansion()) {
                status = SolveStatus::TIME_LIMIT;
                why = "in a safeguard loop";
                break;
            }
            last_step = StepKind::EXPANSION;
        } else {
            if (!proportioning()) {
                if (over_time()) {
                    status = SolveStatus::TIME_LIMIT;
                    why = "in a safeguard loop";
                } else {
                    status = SolveStatus::STALLED;
                    why = "zero proportioning direction (beta'A beta = 0)";
                }
                break;
            }
            last_step = StepKind::PROPORTIONING;
        }
        if (recompute) m_f_proj_x = m_f_x;
    }

    // --- final: x = P(x), lambda of Section 2 at the returned x (with an exact gradient) ---
    if (status != SolveStatus::CONVERGED) {
        project_x();
        refresh_gradient();
        restart();
    }
    evaluate_rows();
    result.native_residual = m_native;
    // The loop writes the reason of its own exits; a breakdown is the solver's word.
    // The whole measure at the returned point (m_error leaves out the bodies' rigid motion); a
    // converged run's message already states it.
    const std::string error =
        status == SolveStatus::CONVERGED
            ? std::string()
            : "accuracy error " + format_e(std::max(m_error, m_scale.body_motion(m_x, m_lambda)), 3) + ", ";
    const std::string figures = error + "||phi+beta|| " + format_e(m_native, 3) + "; " +
                                std::to_string(m_cnt.cg_steps) + " cg, " + std::to_string(m_cnt.expansion_steps) +
                                " expansion, " + std::to_string(m_cnt.proportioning_steps) + " proportioning steps";
    const std::string detail = !m_loop.owns(status) ? "mprgp: not converged: " + why + " (" + figures + ")"
                                                    : (why.empty() ? "" : why + "; ") + figures;
    result.x = m_x;
    result.lambda = m_lambda;
    result.lambda_fitted = false;
    result.counters = m_cnt;
    result.info["safeguard_firings"] = m_cnt.safeguard_steps;
    result.info["alpha_bar"] = m_alpha_bar;
    result.info["active_rows"] = m_active_count;
    if (m_st.objective == "recompute")
        result.info["recompute"] = {{"trial_steps", m_trial_steps},
                                    {"direct_disagreements", m_direct_disagreements},
                                    {"direct_gap_max", m_direct_gap}};
    if (m_st.deflation != "none")
        result.info["deflation"] = {{"active", m_deflate},
                                    {"bodies", m_defl.components()},
                                    {"modes", m_defl.kept_modes()},
                                    {"rayleigh_min", m_defl.min_rayleigh_seen()},
                                    {"rayleigh_max", m_defl.max_rayleigh_seen()},
                                    {"galerkin_steps", m_galerkin_steps},
                                    {"faces", m_deflation_faces}};
    if (m_ichol)
        result.info["ichol"] = {{"factor_nonzeros", m_ic.factor_nonzeros()},
                                {"a_nonzeros", static_cast<long>(m_A.nonZeros())}};
    {
        IterationInfo info;
        info.iteration = m_cnt.iterations;
        info.step = StepKind::FINAL;
        info.x = &m_x;
        info.lambda = &m_lambda;
        info.native_residual = m_native;
        info.active_set_size = m_active_count;
        info.counters = &m_cnt;
        m_loop.notify(info);
    }
    return m_loop.finish(result, status, detail);
}

}  // namespace

SolverResult MprgpSolver::solve(const QpView& qp, const SolveContext& context)
{
    MprgpRun run(qp, m_settings, context);
    return run.run();
}

}  // namespace cb
