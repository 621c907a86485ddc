#pragma once
/// The row parts of the accuracy measure (docs/accuracy.md), one constraint row at a time: the one
/// home of that arithmetic. solvers/measure/accuracy.cpp and the solvers' fused evaluations (mprgp,
/// mprgp-coupled, pgs) call it, so a solver's own stop test and the harness's recomputation are the
/// same code. Inline: it runs inside the solvers' per-row passes.
///
/// Per row i with slack s_i = J_i x - c_i, inv_norm = 1 / n_i and length_per_multiplier = n_i / k_i
/// (AccuracyScale):
///   primal           max(0, -s_i) / n_i
///   dual             max(0, -lambda_i) n_i / k_i
///   complementarity  min(|lambda_i| n_i / k_i, |s_i| / n_i)
///   gap              |lambda_i s_i|        (summed over rows; the others are maxima)
/// A frictional contact (Coulomb, issue 48: normal row i and its two tangent rows, tangential
/// slacks t_i = T_i x - cT_i, tangential multipliers lambda_T,i, coefficient mu_i) adds, with
/// w_i = n_i / k_i converting its forces and 1 / n_i its displacements into lengths:
///   friction         || F_i ||_2,  F_i = w_i r_i - P_K(w_i r_i - (u_i + mu_i ||u_iT|| e_n)),
///                    r_i = (lambda_i, lambda_T,i), u_i = (s_i, t_i) / n_i   (Coulomb's natural map)
///   gap              + |lambda_T,i . t_i + mu_i lambda_i ||t_i||| (the modified velocity's work)
/// (add_friction; docs/accuracy.md "e for Coulomb friction").
#include "solvers/measure/friction_error.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace cb {

/// The row parts accumulated over rows, in the problem's units: primal, dual and complementarity
/// are lengths, gap an energy. NaN reads as +inf (a NaN point is neither feasible nor
/// complementary): std::max would drop a NaN second argument.
struct RowParts {
    double primal = 0.0;
    double dual = 0.0;
    double complementarity = 0.0;
    double gap = 0.0;
    double friction = 0.0;  ///< Coulomb's natural map, largest over frictional contacts (0: none)

    static double sanitize(double v) { return std::isfinite(v) ? v : std::numeric_limits<double>::infinity(); }

    /// A row with n_i = 0: J_i x = 0 whatever x, so it holds iff c_i <= 0; its multiplier exerts
    /// no force (no dual, complementarity or gap part).
    void add_zero_row(double c)
    {
        if (!(c <= 0.0)) primal = std::numeric_limits<double>::infinity();
    }
    /// The feasibility of a row with n_i > 0. std::max(-slack, 0.0) keeps a NaN slack (the first
    /// argument is returned when the comparison fails) for sanitize to make +inf.
    void add_primal(double slack, double inv_norm)
    {
        primal = std::max(primal, sanitize(std::max(-slack, 0.0) * inv_norm));
    }
    /// The multiplier's parts of a row with n_i > 0.
    void add_multiplier(double slack, double lambda, double inv_norm, double length_per_multiplier)
    {
        const double push = lambda * length_per_multiplier;
        dual = std::max(dual, sanitize(std::max(-push, 0.0)));
        complementarity = std::max(complementarity, sanitize(std::min(std::abs(push), std::abs(slack) * inv_norm)));
        gap += std::abs(lambda * slack);
    }
    /// The Coulomb parts of a contact with n_i > 0 whose coefficient or tangential multipliers are
    /// not zero (a contact with both zero adds nothing: there the natural map's normal component is
    /// already bounded by the primal, dual and complementarity parts and its tangential one is 0).
    /// `tangent_slack` t_i and `lambda_t` are the contact's two tangential values.
    void add_friction(double slack, double lambda, const double tangent_slack[2], const double lambda_t[2], double mu,
                      double inv_norm, double length_per_multiplier)
    {
        const double w = length_per_multiplier;
        const double force[3] = {lambda * w, lambda_t[0] * w, lambda_t[1] * w};
        const double move[3] = {slack * inv_norm, tangent_slack[0] * inv_norm, tangent_slack[1] * inv_norm};
        // De Saxce's modified displacement u + mu ||u_T|| e_n makes the natural map one cone projection.
        double z[3] = {force[0] - (move[0] + mu * std::hypot(move[1], move[2])), force[1] - move[1],
                       force[2] - move[2]};
        project_on_coulomb_cone(z, mu);
        const double natural = std::sqrt((force[0] - z[0]) * (force[0] - z[0]) + (force[1] - z[1]) * (force[1] - z[1]) +
                                         (force[2] - z[2]) * (force[2] - z[2]));
        friction = std::max(friction, sanitize(natural));
        gap += std::abs(lambda_t[0] * tangent_slack[0] + lambda_t[1] * tangent_slack[1] +
                        mu * lambda * std::hypot(tangent_slack[0], tangent_slack[1]));
    }
    /// Every part of row i (c = c_i tells a zero row's feasibility).
    void add_row(double c, double slack, double lambda, double inv_norm, double length_per_multiplier)
    {
        if (inv_norm == 0.0) {
            add_zero_row(c);
            return;
        }
        add_primal(slack, inv_norm);
        add_multiplier(slack, lambda, inv_norm, length_per_multiplier);
    }
    /// The parts in the measure's units (AccuracyParts): lengths / l, gap / (d_ref l^2).
    RowParts scaled(double inv_length, double inv_energy) const
    {
        return {primal * inv_length, dual * inv_length, complementarity * inv_length, sanitize(gap * inv_energy),
                friction * inv_length};
    }
};

}  // namespace cb
