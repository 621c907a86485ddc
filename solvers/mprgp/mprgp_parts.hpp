#pragma once
/// The method parts of the MPRGP engine (solvers/mprgp/mprgp_engine.hpp), each chosen once at setup by an
/// enum: the diagonal (Jacobi) preconditioner's check, the expansion direction and the expansion's
/// step length. A new variant is a new enum value, its case in the function here, and one row of
/// EXPANSION_VARIANTS (docs/DESIGN.md "Adding an MPRGP variant").
/// Ref: Kruzik, Horak, Cermak, Pospisil, Pecha, "Active set expansion strategies in MPRGP
///      algorithm", Adv. Eng. Softw. 149 (2020): expansion directions and step lengths as parts.
#include "solvers/core/settings.hpp"
#include "solvers/core/solve_loop.hpp"
#include "solvers/core/solver.hpp"
#include "solvers/core/types.hpp"
#include "solvers/linalg/row_search.hpp"
#include "solvers/mprgp/mprgp_kernels.hpp"

#include <cmath>
#include <string>
#include <vector>

namespace cb {

/// D^-1 for the Jacobi preconditioner. @return false (and `error`, naming the first offending
/// entry) when a diagonal entry of A is not positive: D^-1 would not be SPD.
inline bool jacobi_inverse_diagonal(const SpMat& A, Vec& dinv, std::string& error)
{
    const Vec diag = sorted_rows_diagonal(A);  // A.diagonal()'s values, the rows ahead prefetched
    dinv.resize(diag.size());
    for (Eigen::Index j = 0; j < diag.size(); ++j) {
        if (!(diag[j] > 0.0)) {
            error = "precond=jacobi needs a positive diagonal of A; A(" + std::to_string(j) + "," + std::to_string(j) +
                    ") = " + std::to_string(diag[j]);
            return false;
        }
        dinv[j] = 1.0 / diag[j];
    }
    return true;
}

/// ||A|| by the power method for the fixed step length alpha_bar, warm-started from the context's
/// eigenvector when it has A's size (and leaving the last iterate there); counted in `cnt`.
/// @param deadline  when given, the power method stops at its time limit
inline PowerResult estimate_norm(const AOperator& a_op, const SolveContext& context, PowerRule rule, long max_products,
                                 const CommonSettings& common, Counters& cnt, SolveLoop* deadline = nullptr)
{
    Vec eigenvector;
    const bool warm = context.eigenvector != nullptr && context.eigenvector->size() == a_op.rows();
    if (warm) eigenvector = *context.eigenvector;
    const PowerResult power = deadline
                                  ? power_method(a_op, eigenvector, rule, max_products, common.tol, warm, common.seed,
                                                 &SolveLoop::time_up_callback, deadline)
                                  : power_method(a_op, eigenvector, rule, max_products, common.tol, warm, common.seed);
    if (context.eigenvector) *context.eigenvector = eigenvector;
    cnt.power_products = power.products;
    cnt.a_products += power.products;
    return power;
}

/// alpha_bar = 2 / rho with rho the estimate rounded up 1%: the estimate approaches ||A|| from
/// below, and alpha_bar must stay <= 2 / ||A|| for the projected steps to decrease F.
inline double fixed_step_length(const PowerResult& power)
{
    return power.estimate > 0.0 ? 2.0 / (1.01 * power.estimate) : 1.0;
}

/// The direction d of the expansion step x = P(x - a d).
enum class ExpansionDirection {
    FREE_GRADIENT,   ///< phi, the free gradient (Dostal; Li et al. Alg. 1)
    PRECONDITIONED,  ///< the preconditioner's face direction z (J_A z = 0)
    PROJECTED_CG,    ///< the rejected CG trial's p and alpha_cg: x = P(x - alpha_cg p) (mprgp_projcg_step.hpp)
};

/// The length a of the expansion step x = P(x - a d).
enum class StepLength {
    FIXED,             ///< alpha_bar = 2 / ||A|| (rounded up 1%): a projected step that never increases F
    LINE_MINIMUM,      ///< d'g / d'Ad, the minimiser of F along d before the projection (alpha_bar if not positive)
    BARZILAI_BORWEIN,  ///< s's / s'y from the last two iterates, safeguarded (mprgp_bb_step.hpp)
};

/// a for the direction d, from d'Ad and d'g (both read only for LINE_MINIMUM).
inline double expansion_step_length(StepLength rule, double alpha_bar, double dad, double dg)
{
    switch (rule) {
    case StepLength::LINE_MINIMUM:
        return dad > 0.0 && dg > 0.0 && std::isfinite(dad) ? dg / dad : alpha_bar;
    case StepLength::FIXED:
    case StepLength::BARZILAI_BORWEIN:  // from the iterates' history: BarzilaiBorweinStep
        break;
    }
    return alpha_bar;
}

/// A named expansion variant: the value of a solver's `expansion` setting.
struct ExpansionVariant {
    const char* name;
    ExpansionDirection direction;
    StepLength length;
};

/// The registered expansion variants (the first is the default).
inline const std::vector<ExpansionVariant>& expansion_variants()
{
    static const std::vector<ExpansionVariant> variants = {
        {"paper", ExpansionDirection::FREE_GRADIENT, StepLength::FIXED},
        {"precond", ExpansionDirection::PRECONDITIONED, StepLength::LINE_MINIMUM},
        {"bb", ExpansionDirection::FREE_GRADIENT, StepLength::BARZILAI_BORWEIN},
        {"projcg", ExpansionDirection::PROJECTED_CG, StepLength::FIXED},
    };
    return variants;
}

/// The names of expansion_variants(), for a settings table's choice.
inline std::vector<std::string> expansion_variant_names()
{
    std::vector<std::string> names;
    for (const ExpansionVariant& v : expansion_variants()) names.emplace_back(v.name);
    return names;
}

/// The variant of a (validated) setting value; the default when the name is unknown.
inline ExpansionVariant expansion_variant(const std::string& name)
{
    for (const ExpansionVariant& v : expansion_variants())
        if (name == v.name) return v;
    return expansion_variants().front();
}

}  // namespace cb
