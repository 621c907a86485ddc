#pragma once
/// Dostal's MPRGP steps over a separable convex set, every iterate feasible: the `Steps` of the
/// engine (solvers/mprgp/mprgp_engine.hpp) for bounds (`mprgp-box`, solvers/mprgp/bound_set.hpp) and for discs
/// (solvers/mprgp/disc_set.hpp). The set supplies the geometry:
///   bool contains(const Vec& x) const;                  x in the set
///   void project(Vec& x) const;                         x = P(x)
///   double feasible_step(const Vec& x, const Vec& p) const;  largest a >= 0 with x - a p feasible
///   bool classify(const Vec& x);                        the face at x; true when it changed
///   void gradients(const Vec& g, Vec& phi, Vec& beta) const;  free and chopped gradients (face)
///   double reduced_free_gradient_dot(const Vec& x, const Vec& phi, double alpha_bar) const;
///   double error(const Vec& x, const Vec& g);          the accuracy measure at x (multipliers too)
///   const Vec* multipliers() const;                     the last error()'s multipliers, or null
/// Ref: Dostal, "Optimal Quadratic Programming Algorithms" (2009), Ch. 5 (MPRGP), 7 (MPGP).
#include "solvers/linalg/a_product.hpp"
#include "solvers/mprgp/mprgp_engine.hpp"

#include <cmath>
#include <string>

namespace cb {

template <class Set> class FeasibleMprgpSteps {
public:
    /// @param dinv  the diagonal preconditioner (ones for none), applied on the free part of g
    FeasibleMprgpSteps(Set& set, const AOperator& a_op, const Vec& b, const Vec& dinv, double alpha_bar, double gamma,
                       SolveLoop& loop, Counters& cnt)
        : m_set(set), m_a_op(a_op), m_b(b), m_dinv(dinv), m_alpha_bar(alpha_bar), m_gamma2(gamma * gamma), m_loop(loop),
          m_cnt(cnt)
    {
    }

    /// x = P(x0) and the chain's start.
    void start(const Vec& x0)
    {
        m_x = x0;
        m_set.project(m_x);
        ++m_cnt.projections;
        exact_gradient();
        m_set.classify(m_x);
        gradients();
        m_p = m_z;
    }

    Evaluation evaluate(std::string&)
    {
        Evaluation e;
        m_native = (m_phi + m_beta).norm();
        m_error = m_set.error(m_x, m_g);
        e.converged = m_loop.criterion_met(m_native, m_error);
        if (e.converged) {  // confirm at an exact gradient
            exact_gradient();
            gradients();
            m_native = (m_phi + m_beta).norm();
            m_error = m_set.error(m_x, m_g);  // also the multipliers the monitor shows
            e.converged = m_loop.criterion_met(m_native, m_error);
            m_p = m_z;
        }
        e.finite = std::isfinite(m_native);
        return e;
    }

    bool notify(StepKind last)
    {
        IterationInfo info;
        info.iteration = m_cnt.iterations;
        info.step = last;
        info.x = &m_x;
        info.lambda = m_set.multipliers();
        info.native_residual = m_native;
        info.counters = &m_cnt;
        return m_loop.notify(info);
    }

    bool proportional() const
    {
        return m_beta.squaredNorm() <= m_gamma2 * m_set.reduced_free_gradient_dot(m_x, m_phi, m_alpha_bar);
    }
    bool feasible() const { return true; }

    /// The CG step, or (when it would leave the set) the step to the boundary: rejected then.
    Trial cg_trial(std::string& why)
    {
        Trial t;
        a_product(m_a_op, m_p, m_Ap);
        ++m_cnt.a_products;
        const double pap = m_p.dot(m_Ap);
        if (!(pap > 0.0)) {
            t.broke = pap == 0.0 ? SolveStatus::STALLED : SolveStatus::DIVERGED;
            why = "p'Ap <= 0";
            return t;
        }
        const double alpha_cg = m_z.dot(m_g) / pap;
        const double alpha_f = m_set.feasible_step(m_x, m_p);
        if (!(alpha_cg <= alpha_f)) {
            // The expansion starts from the boundary point; rounding at the bound hit is projected away.
            m_x -= alpha_f * m_p;
            m_g -= alpha_f * m_Ap;
            m_set.project(m_x);
            return t;
        }
        m_x -= alpha_cg * m_p;
        m_g -= alpha_cg * m_Ap;
        const bool face_changed = m_set.classify(m_x);
        gradients();
        if (face_changed)
            m_p = m_z;  // a new face: the conjugate directions restart
        else
            m_p = m_z - (m_z.dot(m_Ap) / pap) * m_p;
        ++m_cnt.cg_steps;
        t.accepted = true;
        return t;
    }

    /// x = P(x - alpha_bar phi) from the boundary point of the rejected trial.
    SolveStatus expansion(std::string&)
    {
        m_set.classify(m_x);
        gradients();
        m_x -= m_alpha_bar * m_phi;
        m_set.project(m_x);
        ++m_cnt.projections;
        exact_gradient();
        restart();
        ++m_cnt.expansion_steps;
        return SolveStatus::NOT_RUN;
    }

    /// The exact step along -beta when it stays in the set, else a projected gradient step.
    SolveStatus proportioning(std::string& why)
    {
        a_product(m_a_op, m_beta, m_Ap);
        ++m_cnt.a_products;
        const double dad = m_beta.dot(m_Ap);
        if (!(dad > 0.0)) {
            why = "beta'A beta <= 0";
            return SolveStatus::STALLED;
        }
        const double alpha_p = m_g.dot(m_beta) / dad;
        if (alpha_p <= m_set.feasible_step(m_x, m_beta)) {
            m_x -= alpha_p * m_beta;
            m_g -= alpha_p * m_Ap;
        } else {
            // -beta leaves a curved face (a disc's tangent) or overshoots a far bound: a projected
            // gradient step instead, which never increases F (alpha_bar <= 2/||A||).
            m_x -= m_alpha_bar * m_g;
            m_set.project(m_x);
            ++m_cnt.projections;
            exact_gradient();
        }
        restart();
        ++m_cnt.proportioning_steps;
        return SolveStatus::NOT_RUN;
    }

    /// The returned point's gradient, face, residual and error.
    void final_evaluation()
    {
        exact_gradient();
        m_set.classify(m_x);
        gradients();
        m_native = (m_phi + m_beta).norm();
        m_error = m_set.error(m_x, m_g);
    }

    const Vec& x() const { return m_x; }
    const Vec& g() const { return m_g; }
    double native_residual() const { return m_native; }
    double error() const { return m_error; }

private:
    void exact_gradient()
    {
        a_product(m_a_op, m_x, m_g);
        m_g -= m_b;
        ++m_cnt.a_products;
    }
    void gradients()
    {
        m_set.gradients(m_g, m_phi, m_beta);
        m_z = m_dinv.cwiseProduct(m_phi);
        ++m_cnt.precond_applications;
    }
    void restart()
    {
        m_set.classify(m_x);
        gradients();
        m_p = m_z;
    }

    Set& m_set;
    const AOperator& m_a_op;
    const Vec& m_b;
    const Vec& m_dinv;
    const double m_alpha_bar, m_gamma2;
    SolveLoop& m_loop;
    Counters& m_cnt;
    Vec m_x, m_g, m_phi, m_beta, m_z, m_p, m_Ap;
    double m_native = 0.0, m_error = 0.0;
};

}  // namespace cb
