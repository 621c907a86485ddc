#pragma once
/// The projected CG expansion of `mprgp` (expansion = projcg; Kruzik, Horak, Cermak, Pospisil,
/// Pecha 2020, "projcg"; PERMON's MPGP expansion type of that name): where the CG trial
/// y = x - alpha_cg p was rejected, the expansion takes x = P(y), the full CG step projected onto
/// the set, instead of P(P(x) - alpha_bar phi). The next chain then restarts from P(y) on its new
/// face, and Alg. 3's safeguard (projected gradient steps) plays the part of PERMON's fallback
/// when F(P(y)) rose. Without a rejected trial (an expansion from an infeasible chain iterate that
/// is not proportional) it falls back to the free gradient with the fixed step.
namespace cb {

/// The step length of the last rejected CG trial, consumed by the expansion that follows it.
class ProjectedCgStep {
public:
    /// Called when a CG trial with step `alpha` along p was rejected.
    void rejected(double alpha) { m_alpha = alpha; }

    /// The rejected trial's alpha_cg, once (0 when there is none: fall back).
    double take()
    {
        const double alpha = m_alpha;
        m_alpha = 0.0;
        return alpha;
    }

private:
    double m_alpha = 0.0;
};

}  // namespace cb
