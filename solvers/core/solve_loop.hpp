#pragma once
/// The solve-loop protocol every solver follows (docs/DESIGN.md "The solve loop"): one stopwatch,
/// one rule for setup, the time limit on setup + solve, the stop rule and the exit checks in one
/// order, the monitor on a paused clock, one finisher that records the criterion and writes the
/// standard messages. No solver reads `stop` or writes those messages itself.
///
///   SolveLoop loop("my-solver", qp, settings.common, context);   // the clock starts: setup begins
///   ... factorise, estimate norms ...
///   if (!loop.end_setup()) return loop.finish(result, SolveStatus::TIME_LIMIT);
///   loop.notify(info);                                         // START, clock paused
///   while (true) {
///       status = loop.check(counters.iterations, x.allFinite(), native_residual,
///                           [&] { return accuracy_from_gradient(qp, scale, x, g, lambda).max(); });
///       if (status != SolveStatus::NOT_RUN) break;            // non-finite, converged, cap, time
///       ... one iteration; ++counters.iterations ...
///       if (!loop.notify(info)) ...                            // STOPPED_BY_MONITOR
///   }
///   return loop.finish(result, status, detail);                // criterion, message, times
///
/// Times: elapsed_s() runs from the start of setup with every monitor call (and the work done for
/// it, see notify) excluded; setup_s is elapsed_s at end_setup(); solve_s = elapsed_s - setup_s at
/// finish(). time_limit_s bounds elapsed_s, setup included: a limit reached during setup is
/// TIME_LIMIT with a message that says so. The monitor's IterationInfo::elapsed_s is elapsed_s,
/// so every history starts at the solver's setup time.
///
/// Messages: finish writes "<solver>: <standard reason>[; detail]" for the exits the loop owns
/// (converged, iteration cap, time limit, stopped by the monitor, and the non-finite and
/// not-met verdicts of check/verdict); any other status (a breakdown, a refused problem) keeps the
/// solver's own message.
#include "solvers/core/settings.hpp"
#include "solvers/core/solver.hpp"
#include "solvers/core/stopwatch.hpp"

#include <limits>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

namespace cb {

class SolveLoop {
public:
    /// Starts the stopwatch: everything after this line is the solver's time (setup first).
    SolveLoop(std::string solver, const QpView& qp, const CommonSettings& common, const SolveContext& context);

    /// Ends setup (setup_s = the time so far). @return false when the time limit was reached
    /// during setup: the solver then finishes with TIME_LIMIT and time_limit_message().
    bool end_setup();
    bool in_setup() const { return !m_setup_done; }
    /// Ends a named part of the setup: the time since the last mark (or the start) goes to
    /// `name` in the result's info.setup_phases_s (finish()), beside `other`, the setup time no
    /// mark covers. Marks after end_setup() are ignored.
    void setup_phase(const char* name);
    /// Seconds recorded under `name` so far (0 when none).
    double setup_phase_s(const std::string& name) const;

    double elapsed_s() const { return m_watch.seconds(); }  ///< since the start of setup, monitor excluded
    double setup_s() const { return m_setup_done ? m_setup_s : elapsed_s(); }
    double solve_s() const { return m_setup_done ? elapsed_s() - m_setup_s : 0.0; }
    /// time_limit_s > 0 and elapsed_s() >= time_limit_s (the one comparison every solver uses).
    bool time_up() const { return m_time_limit_s > 0.0 && elapsed_s() >= m_time_limit_s; }
    /// For a deadline callback in setup code that takes a function pointer (the power method).
    static bool time_up_callback(void* loop) { return static_cast<const SolveLoop*>(loop)->time_up(); }

    /// The stop rule: stop=native: native <= tol; stop=kkt: the accuracy error <= tol. `native`
    /// and `accuracy` are each a number or a callable returning one (or, for `native`, a library's
    /// own yes/no test at tol); only the one the rule reads is
    /// evaluated (an accuracy callable may return +inf when a cheaper screen already says "not
    /// met"). The value that met the rule is kept for finish's message.
    template <class Native, class Accuracy> bool criterion_met(Native&& native, Accuracy&& accuracy)
    {
        const double value = m_stop == StopRule::NATIVE ? evaluate(native) : evaluate(accuracy);
        const bool met = value <= m_tol;
        if (met) m_met_value = value;
        return met;
    }
    /// The stop rule on another measure of the same kind (a face's own error) without touching the
    /// value finish reports.
    template <class Native, class Accuracy> bool rule_holds(Native&& native, Accuracy&& accuracy) const
    {
        return (m_stop == StopRule::NATIVE ? evaluate(native) : evaluate(accuracy)) <= m_tol;
    }

    /// One call per iteration, the exit checks in the one order: non-finite -> DIVERGED, the stop
    /// rule (criterion_met) -> CONVERGED, iterations >= max_iterations -> MAX_ITERATIONS,
    /// time_up() -> TIME_LIMIT; else NOT_RUN (go on). The rule is evaluated only on a finite iterate.
    template <class Native, class Accuracy>
    SolveStatus check(long iterations, bool finite, Native&& native, Accuracy&& accuracy)
    {
        if (!finite) return decide(SolveStatus::DIVERGED);
        if (criterion_met(native, accuracy)) return decide(SolveStatus::CONVERGED);
        return limit_status(iterations);
    }
    /// Same order, with the rule already decided through criterion_met (a solver that confirms a
    /// candidate at an exact gradient, or asks for feasibility as well, before deciding).
    SolveStatus check(long iterations, bool finite, bool converged);
    /// The last two checks alone (iteration cap, then time), for loops whose convergence test
    /// sits elsewhere (e.g. inside a pivoting phase).
    SolveStatus limit_status(long iterations);
    /// The verdict on a returned point of a finite method or a peer: non-finite -> DIVERGED, the
    /// stop rule -> CONVERGED, else `otherwise`: STALLED (the rule does not hold at the point, a
    /// standard message) or the library's own outcome (MAX_ITERATIONS at its cap, INFEASIBLE ...).
    template <class Native, class Accuracy>
    SolveStatus verdict(bool finite, Native&& native, Accuracy&& accuracy, SolveStatus otherwise = SolveStatus::STALLED)
    {
        if (!finite) return decide(SolveStatus::DIVERGED);
        if (criterion_met(native, accuracy)) return decide(SolveStatus::CONVERGED);
        if (otherwise != SolveStatus::STALLED) return otherwise;  // the library's word (its cap, its limit ...)
        m_unmet_value = m_stop == StopRule::NATIVE ? evaluate(native) : evaluate(accuracy);
        return decide(SolveStatus::STALLED);
    }

    /// b, c and x0 all finite. For a peer, before it hands the problem to a library that would
    /// abort on a NaN: a non-finite input then ends as the loop's `diverged`.
    bool inputs_finite() const { return m_qp.b.allFinite() && m_qp.c.allFinite() && m_qp.x0.allFinite(); }

    bool monitored() const { return m_context.monitor != nullptr; }
    /// Calls the monitor with the clock paused and info.elapsed_s / info.setup_s filled in.
    /// @return false when the monitor asked to stop (always true without a monitor).
    bool notify(IterationInfo info)
    {
        return m_context.monitor ? notify_monitor(m_context, m_watch, info, setup_s()) : true;
    }
    /// As notify(info), with `prepare()` or `prepare(info)` run first inside the pause, only when
    /// a monitor listens and wants this iterate (Monitor::wants_iterate): work done only for the
    /// monitor (forming x from lambda, a residual only the history shows) is not solver time.
    template <class Prepare> bool notify(IterationInfo info, Prepare&& prepare)
    {
        if (!m_context.monitor) return true;  // no monitor: no preparation either
        using Callable = std::remove_reference_t<Prepare>;
        struct Bound {
            Callable* prepare;
            IterationInfo* info;
        } bound{&prepare, &info};
        return notify_monitor(
            m_context, m_watch, info, setup_s(),
            [](void* p) {
                Bound& b = *static_cast<Bound*>(p);
                if constexpr (std::is_invocable_v<Callable&, IterationInfo&>)
                    (*b.prepare)(*b.info);
                else
                    (*b.prepare)();
            },
            &bound);
    }

    /// "time limit of L s reached during setup (after T s of setup)" or "time limit of L s
    /// reached (setup S s + solve T s)".
    std::string time_limit_reason() const;
    /// time_limit_reason() prefixed with the solver's name and ": ".
    std::string time_limit_message() const { return m_solver + ": " + time_limit_reason(); }
    /// Fills status, criterion (the rule met when CONVERGED, else NONE), message, iterations (from
    /// result.counters), setup_s and solve_s; x and lambda default to x0 and zeros when the solver
    /// left them empty. The message: the standard one for the exits the loop owns, with `detail`
    /// appended after "; "; for any other status `detail` itself (kept as it is when empty).
    /// Returns the result moved out: call it once, in the return statement.
    SolverResult finish(SolverResult& result, SolveStatus status, const std::string& detail = "") const;
    /// The standard reason of an exit the loop owns ("iteration cap 10 reached"), or "" when
    /// `status` is the solver's own word.
    std::string standard_reason(SolveStatus status) const;
    /// Whether `status` is an exit the loop owns (its standard message applies).
    bool owns(SolveStatus status) const;

    const std::string& solver() const { return m_solver; }
    /// The raw stopwatch (for a child process's deadline); never reset it.
    const Stopwatch& stopwatch() const { return m_watch; }

private:
    static double evaluate(double value) { return value; }
    /// A library's own yes/no test (Ipopt's at tol): -inf when met, so the message says so.
    static double evaluate(bool met)
    {
        return met ? -std::numeric_limits<double>::infinity() : std::numeric_limits<double>::infinity();
    }
    template <class F, class = std::enable_if_t<std::is_invocable_v<F&>>> static double evaluate(F& f) { return f(); }
    SolveStatus decide(SolveStatus status)
    {
        if (status != SolveStatus::NOT_RUN) m_decided = status;
        return status;
    }

    std::string m_solver;
    QpView m_qp;  ///< a view (references): copied, so a temporary view may be passed
    double m_time_limit_s;
    long m_max_iterations;
    double m_tol;
    StopRule m_stop;
    SolveContext m_context;  ///< three pointers, copied
    Stopwatch m_watch;
    bool m_setup_done = false;
    double m_setup_s = 0.0;
    std::vector<std::pair<std::string, double>> m_phases;  ///< setup_phase()'s parts, in order
    double m_phase_mark = 0.0;                             ///< elapsed_s() at the last mark
    SolveStatus m_decided = SolveStatus::NOT_RUN;  ///< the last exit a check or verdict decided
    double m_met_value = 0.0;                      ///< the measure that met the rule last
    double m_unmet_value = 0.0;                    ///< the measure a STALLED verdict saw
};

}  // namespace cb
