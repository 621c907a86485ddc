#pragma once
/// The solve-loop protocol every solver follows (docs/DESIGN.md "The solve loop"): one stopwatch,
/// one rule for setup, the time limit on setup + solve, the exit checks in one order, the monitor
/// on a paused clock, one finisher.
///
///   SolveLoop loop("my-solver", qp, settings.common, context);   // the clock starts: setup begins
///   ... factorise, estimate norms ...
///   if (!loop.end_setup()) return loop.finish(result, SolveStatus::TIME_LIMIT, "", loop.time_limit_message());
///   loop.notify(info);                                         // START, clock paused
///   while (true) {
///       const SolveStatus exit = loop.exit_status(finite, converged, counters.iterations);
///       if (exit != SolveStatus::NOT_RUN) break;              // non-finite, converged, cap, time
///       ... one iteration; ++counters.iterations ...
///       if (!loop.notify(info)) ...                            // STOPPED_BY_MONITOR
///   }
///   return loop.finish(result, exit, criterion, message);     // setup_s, solve_s, iterations
///
/// Times: elapsed_s() runs from the start of setup with every monitor call (and the work done for
/// it, see notify) excluded; setup_s is elapsed_s at end_setup(); solve_s = elapsed_s - setup_s at
/// finish(). time_limit_s bounds elapsed_s, setup included: a limit reached during setup is
/// TIME_LIMIT with a message that says so. The monitor's IterationInfo::elapsed_s is elapsed_s,
/// so every history starts at the solver's setup time.
#include "solvers/settings.hpp"
#include "solvers/solver.hpp"
#include "solvers/stopwatch.hpp"

#include <string>
#include <type_traits>
#include <utility>

namespace cb {

class SolveLoop {
public:
    /// Starts the stopwatch: everything after this line is the solver's time (setup first).
    SolveLoop(std::string solver, const QpView& qp, const CommonSettings& common, const SolveContext& context);

    /// Ends setup (setup_s = the time so far). @return false when the time limit was reached
    /// during setup: the solver then finishes with TIME_LIMIT and time_limit_message().
    bool end_setup();
    bool in_setup() const { return !m_setup_done; }

    double elapsed_s() const { return m_watch.seconds(); }  ///< since the start of setup, monitor excluded
    double setup_s() const { return m_setup_done ? m_setup_s : elapsed_s(); }
    double solve_s() const { return m_setup_done ? elapsed_s() - m_setup_s : 0.0; }
    /// time_limit_s > 0 and elapsed_s() >= time_limit_s (the one comparison every solver uses).
    bool time_up() const { return m_time_limit_s > 0.0 && elapsed_s() >= m_time_limit_s; }
    /// For a deadline callback in setup code that takes a function pointer (the power method).
    static bool time_up_callback(void* loop) { return static_cast<const SolveLoop*>(loop)->time_up(); }

    /// The exit checks, in the one order: non-finite -> DIVERGED, converged -> CONVERGED,
    /// iterations >= max_iterations -> MAX_ITERATIONS, time_up() -> TIME_LIMIT; else NOT_RUN
    /// (go on). `converged` is evaluated only when the iterate is finite.
    template <class Converged>
    SolveStatus exit_status(bool finite, Converged&& converged, long iterations) const
    {
        if (!finite) return SolveStatus::DIVERGED;
        if (converged()) return SolveStatus::CONVERGED;
        return limit_status(iterations);
    }
    SolveStatus exit_status(bool finite, bool converged, long iterations) const
    {
        return exit_status(finite, [converged] { return converged; }, iterations);
    }
    /// The last two checks alone (iteration cap, then time), for loops whose convergence test
    /// sits elsewhere (e.g. inside a pivoting phase).
    SolveStatus limit_status(long iterations) const;

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
    template <class Prepare>
    bool notify(IterationInfo info, Prepare&& prepare)
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
    /// Fills status, criterion, message (kept when `message` is empty), iterations (from
    /// result.counters), setup_s and solve_s; x and lambda default to x0 and zeros when the
    /// solver left them empty. Returns the result moved out: call it once, in the return statement.
    SolverResult finish(SolverResult& result, SolveStatus status, std::string criterion = "",
                        std::string message = "") const;

    const std::string& solver() const { return m_solver; }
    /// The raw stopwatch (for a child process's deadline); never reset it.
    const Stopwatch& stopwatch() const { return m_watch; }

private:
    std::string m_solver;
    QpView m_qp;  ///< a view (references): copied, so a temporary view may be passed
    double m_time_limit_s;
    long m_max_iterations;
    SolveContext m_context;  ///< three pointers, copied
    Stopwatch m_watch;
    bool m_setup_done = false;
    double m_setup_s = 0.0;
};

}  // namespace cb
