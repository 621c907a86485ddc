#pragma once
/// `mprgp`'s steps on decoupled rows (JJ' diagonal): the constraint set of the MPRGP engine
/// (solvers/mprgp/mprgp_engine.hpp) with closed-form operators, the paper's monotone CG chain and
/// Alg. 3's safeguards. solvers/mprgp/mprgp_decoupled_face.cpp: the row pass, the face and its
/// preconditioners; solvers/mprgp/mprgp_decoupled_steps.cpp: setup and the steps.
/// Ref: Li et al., "Deformable Objects Collision Handling with Fast Convergence", CGF 2015,
///      Alg. 1 (outline), Alg. 2 (CG chain), Alg. 3 (safeguards), eq. (13)-(20), Appendix B.
/// The hot loop is written for cost: one A-product per CG step (the projected objective F(P(y))
/// comes from scalar recurrences plus a sparse correction), O(nnz(J)) row work, and fused vector
/// updates, so that an iteration costs about one Jacobi-PCG iteration.
#include "solvers/core/solve_loop.hpp"
#include "solvers/linalg/a_product.hpp"
#include "solvers/linalg/ichol.hpp"
#include "solvers/measure/accuracy.hpp"
#include "solvers/mprgp/mprgp.hpp"
#include "solvers/mprgp/mprgp_bb_step.hpp"
#include "solvers/mprgp/mprgp_deflation.hpp"
#include "solvers/mprgp/mprgp_engine.hpp"
#include "solvers/mprgp/mprgp_kernels.hpp"
#include "solvers/mprgp/mprgp_parts.hpp"
#include "solvers/mprgp/mprgp_projcg_step.hpp"

#include <string>
#include <vector>

namespace cb {

/// One solve: the workspace is allocated once, before the loop.
class DecoupledMprgp {
public:
    DecoupledMprgp(const QpView& qp, const MprgpSettings& settings, const SolveContext& context)
        : m_qp(qp), m_A(qp.A), m_a_op(qp), m_J(qp.J), m_b(qp.b), m_c(qp.c), m_st(settings), m_ctx(context), m_n(qp.n()),
          m_m(qp.m()), m_loop("mprgp", qp, settings.common, context)
    {
    }

    /// Setup, the engine's iteration (solvers/mprgp/mprgp_engine.hpp), the returned point.
    SolverResult run();

    // --- the engine's steps ---
    Evaluation evaluate(std::string& why);
    bool notify(StepKind step);
    bool proportional();
    bool feasible() const { return !m_infeasible; }
    Trial cg_trial(std::string& why);
    SolveStatus expansion(std::string& why);
    SolveStatus proportioning(std::string& why);

private:
    // --- products and objective ---
    void product(const Vec& v, Vec& out)
    {
        a_product(m_a_op, v, out);
        ++m_cnt.a_products;
    }
    /// The CG trial's product with v = p (out = A p, p'Ap returned, p'g in vg), forming a pending p
    /// first (v then changes with m_p).
    double product_dot(const Vec& v, Vec& out, double& vg);
    /// p_j as the pending update will form it (the same operations: the same bits).
    double p_at(int j) const { return m_p_pending ? m_z[j] - m_p_beta * m_p[j] : m_p[j]; }
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
    /// Alg. 3's safeguard after an expansion or a proportioning. Returns false on time out.
    bool safeguard_steps(double f_before, double& f_now);
    /// After an expansion or a proportioning: the safeguard, then the next chain's start.
    SolveStatus end_step(double f_before, double f_now, std::string& why);
    /// The step x = P(x - a d) of the expansion variant (direction d, length a) from P(x).
    void expansion_step();
    /// The fused CG update after an accepted trial: x, g, z, p and the chain's scalars.
    void cg_update(double alpha, double pap, double df, double corr_y, double f_proj_y);

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
    ExpansionVariant m_expansion;  // the expansion's direction and step length (solvers/mprgp/mprgp_parts.hpp)
    bool m_bb = false;             // expansion = bb: record the iterates for m_bb_step
    BarzilaiBorweinStep m_bb_step;
    long m_bb_fallbacks = 0;   // BB steps that raised F, repeated with alpha_bar
    ProjectedCgStep m_projcg;  // expansion = projcg: the rejected trial's step length
    bool m_recompute = false;  // objective = recompute
    double m_gamma2 = 1.0;     // Gamma^2
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
    /// The measure's 1 / D, or m_dinv when the two hold the same values (precond = jacobi on a
    /// positive diagonal): the CG step pass then streams one vector for both.
    const Vec* m_stat_weight = nullptr;

    Vec m_x, m_g, m_z, m_p, m_Ap, m_tmp, m_d, m_lambda, m_jx, m_jg, m_jp;
    std::vector<char> m_active;
    std::vector<int> m_touched;

    // Scalars along the chain.
    double m_rz = 0.0;        // z'g
    double m_gg_out = 0.0;    // sum of g_j^2 over DOFs in no row
    double m_pg_rows = 0.0;   // p'phi over the DOFs of rows (from evaluate_rows)
    bool m_p_pending = false;  // p = z - m_p_beta p is still to be formed (by the next product; p_at)
    double m_p_beta = 0.0;
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

}  // namespace cb
