// Fork, pipe, poll, waitpid: see child_process.hpp.
#include "solvers/peers/child_process.hpp"

#include "solvers/core/peak_memory.hpp"

#include <poll.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <sstream>
#include <stdexcept>

namespace cb {

ChildOutcome run_in_child(const std::function<std::vector<char>()>& work, const Stopwatch& watch, double time_limit_s)
{
    int fds[2];
    if (::pipe(fds) != 0) throw std::runtime_error(std::string("pipe: ") + std::strerror(errno));
    const pid_t pid = ::fork();
    if (pid < 0) throw std::runtime_error(std::string("fork: ") + std::strerror(errno));
    if (pid == 0) {
        ::close(fds[0]);
        const std::vector<char> out = work();
        size_t done = 0;
        while (done < out.size()) {
            const ssize_t k = ::write(fds[1], out.data() + done, out.size() - done);
            if (k <= 0) _exit(3);
            done += static_cast<size_t>(k);
        }
        ::close(fds[1]);
        _exit(0);  // no destructors or atexit handlers of the parent's libraries
    }
    ::close(fds[1]);
    ChildOutcome outcome;
    char buffer[65536];
    for (;;) {
        int wait_ms = -1;
        if (time_limit_s > 0.0) {
            const double left = time_limit_s - watch.seconds();
            if (left <= 0.0) {
                outcome.timed_out = true;
                break;
            }
            wait_ms = static_cast<int>(left * 1000.0) + 1;
        }
        pollfd p{fds[0], POLLIN, 0};
        const int ready = ::poll(&p, 1, wait_ms);
        if (ready < 0 && errno == EINTR) continue;
        if (ready == 0) continue;  // the loop head tests the limit
        const ssize_t k = ::read(fds[0], buffer, sizeof buffer);
        if (k < 0 && errno == EINTR) continue;
        if (k <= 0) break;  // EOF: the child finished or died
        outcome.bytes.insert(outcome.bytes.end(), buffer, buffer + k);
    }
    ::close(fds[0]);
    if (outcome.timed_out) ::kill(pid, SIGKILL);
    int wstatus = 0;
    rusage usage{};
    while (::wait4(pid, &wstatus, 0, &usage) < 0 && errno == EINTR) {}
    note_child_peak_memory(usage.ru_maxrss * 1024L);  // the child's own peak (kB on Linux)
    if (!outcome.timed_out) {
        std::ostringstream msg;
        if (WIFSIGNALED(wstatus)) {
            outcome.failed = true;
            msg << "was killed by signal " << WTERMSIG(wstatus) << " (" << strsignal(WTERMSIG(wstatus)) << ")";
        } else if (!WIFEXITED(wstatus) || WEXITSTATUS(wstatus) != 0) {
            outcome.failed = true;
            msg << "exited with status " << WEXITSTATUS(wstatus);
        }
        outcome.failure = msg.str();
    }
    return outcome;
}

std::optional<SolverResult> finish_failed_child(const ChildOutcome& child, size_t expected, const std::string& library,
                                                const SolveLoop& loop, SolverResult& result)
{
    if (child.timed_out) return loop.finish(result, SolveStatus::TIME_LIMIT, "the child process was killed");
    result.info["crashed"] = child.failed || child.bytes.size() != expected;
    if (!result.info["crashed"].get<bool>()) return std::nullopt;
    std::ostringstream msg;
    msg << loop.solver() << ": the " << library << " child process " << (child.failed ? child.failure : "sent") << " ("
        << child.bytes.size() << " of " << expected << " bytes received)";
    return loop.finish(result, SolveStatus::DIVERGED, msg.str());
}

}  // namespace cb
