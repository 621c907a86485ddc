#pragma once
/// A pausable wall-clock stopwatch: solvers time themselves with it and the monitor call
/// runs with it paused, so harness bookkeeping never counts as solver time.
#include <chrono>

namespace cb {

class Stopwatch {
public:
    using Clock = std::chrono::steady_clock;

    void start()
    {
        if (!m_running) {
            m_started = Clock::now();
            m_running = true;
        }
    }
    void pause()
    {
        if (m_running) {
            m_elapsed += Clock::now() - m_started;
            m_running = false;
        }
    }
    void reset()
    {
        m_elapsed = Clock::duration::zero();
        m_running = false;
    }
    /// Seconds accumulated while running (including the current run, if any).
    double seconds() const
    {
        auto total = m_elapsed;
        if (m_running) total += Clock::now() - m_started;
        return std::chrono::duration<double>(total).count();
    }
    bool running() const { return m_running; }

private:
    Clock::time_point m_started{};
    Clock::duration m_elapsed = Clock::duration::zero();
    bool m_running = false;
};

/// Pauses a stopwatch for the lifetime of the guard (used around monitor calls).
class PausedScope {
public:
    explicit PausedScope(Stopwatch& watch) : m_watch(watch), m_was_running(watch.running()) { m_watch.pause(); }
    ~PausedScope()
    {
        if (m_was_running) m_watch.start();
    }
    PausedScope(const PausedScope&) = delete;
    PausedScope& operator=(const PausedScope&) = delete;

private:
    Stopwatch& m_watch;
    bool m_was_running;
};

}  // namespace cb
