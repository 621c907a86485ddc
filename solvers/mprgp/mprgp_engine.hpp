#pragma once
/// The MPRGP iteration, written once (issue 44). `mprgp-box`, `mprgp` and `mprgp-coupled` run it
/// over their constraint sets; what differs between them (the projection, the feasible step, the
/// free and chopped gradients, the face and its operators) lives in the `Steps` class each one
/// passes; what differs in method (preconditioner, expansion direction, step length) is a part
/// chosen once at setup (solvers/mprgp/mprgp_parts.hpp).
///
/// One iteration: evaluate the point (and confirm a candidate at an exact gradient), report it to
/// the monitor, take the loop's exit checks, then
///     proportional (||beta||^2 <= Gamma^2 phitilde'phi)?  CG trial: accepted -> next iteration
///                                                                   rejected -> expansion
///     else, at an infeasible chain iterate:              expansion
///     else:                                              proportioning
/// Dostal's MPRGP keeps every iterate feasible, so its trial is rejected when the CG step would
/// leave the set (after it moved to the boundary); the paper's monotone variant (Li et al. 2015,
/// Alg. 2) may accept an infeasible trial while F(P(y)) decreases, and ends the chain with an
/// expansion from P(x) once it does not.
///
/// `Steps` provides (all called with the loop's own counters and reasons):
///   Evaluation evaluate(std::string& why);   the point's residuals; converged once confirmed
///   bool notify(StepKind last);              the monitor's view; false: the monitor stops
///   bool proportional();                     the proportioning test (false at a finished face)
///   bool feasible() const;                   the iterate lies in the set
///   Trial cg_trial(std::string& why);        one CG step (Alg. 2), accepted or not
///   SolveStatus expansion(std::string& why); NOT_RUN to go on, else a breakdown / time limit
///   SolveStatus proportioning(std::string& why);
/// References: Dostal, "Optimal Quadratic Programming Algorithms" (2009), Ch. 5 and 7; Li et al.,
/// CGF 2015, Alg. 1-3; PERMON's MPGP (one convergence call, then CG | expansion | proportioning).
#include "solvers/core/solve_loop.hpp"
#include "solvers/core/solver.hpp"

#include <cmath>
#include <string>

namespace cb {

/// One evaluation of the iterate.
struct Evaluation {
    bool finite = true;                        ///< the residual is a number (else the loop diverges)
    bool converged = false;                    ///< the stop rule holds, confirmed at an exact gradient
    SolveStatus broke = SolveStatus::NOT_RUN;  ///< a breakdown found before the iteration (why set)
};

/// One CG trial step: accepted (the chain goes on), rejected (an expansion follows) or a breakdown.
struct Trial {
    bool accepted = false;
    SolveStatus broke = SolveStatus::NOT_RUN;
};

/// Runs the MPRGP iteration until an exit; returns the status and, for a breakdown, its reason.
template <class Steps> SolveStatus run_mprgp(Steps& steps, SolveLoop& loop, Counters& cnt, std::string& why)
{
    StepKind last = StepKind::START;
    while (true) {
        const Evaluation point = steps.evaluate(why);
        if (point.broke != SolveStatus::NOT_RUN) return point.broke;
        if (!steps.notify(last)) return SolveStatus::STOPPED_BY_MONITOR;
        const SolveStatus exit = loop.check(cnt.iterations, point.finite, point.converged);
        if (exit != SolveStatus::NOT_RUN) return exit;
        ++cnt.iterations;
        SolveStatus step = SolveStatus::NOT_RUN;
        if (steps.proportional()) {
            const Trial trial = steps.cg_trial(why);
            if (trial.broke != SolveStatus::NOT_RUN) return trial.broke;
            if (trial.accepted) {
                last = StepKind::CG;
                continue;
            }
            step = steps.expansion(why);
            last = StepKind::EXPANSION;
        } else if (!steps.feasible()) {
            // No feasible point to proportion from: the expansion projects first.
            step = steps.expansion(why);
            last = StepKind::EXPANSION;
        } else {
            step = steps.proportioning(why);
            last = StepKind::PROPORTIONING;
        }
        if (step != SolveStatus::NOT_RUN) return step;
    }
}

/// Alg. 3's safeguard: while F rose above f_before (beyond rounding), one projected gradient step
/// `step()` (returning the new F), at most `max_repeats` times. A projected step with alpha_bar <=
/// 2/||A|| never increases F, so the loop ends; the cap only bounds a rounding-level cycle.
/// @return false when the time limit ran out inside the loop
template <class Step>
bool safeguard(double f_before, double& f_now, long max_repeats, Counters& cnt, const SolveLoop& loop, Step&& step)
{
    auto increased = [&](double f) { return f > f_before + 1e-12 * (std::abs(f_before) + std::abs(f)); };
    long repeats = 0;
    while (increased(f_now) && repeats < max_repeats) {
        f_now = step();
        ++cnt.safeguard_steps;
        ++repeats;
        if (loop.time_up()) return false;
    }
    return true;
}

}  // namespace cb
