// An external program on a leash: see program_run.hpp.
#include "harness/program_run.hpp"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace cb {

std::string ProgramOutcome::failure() const
{
    if (timed_out) return "was killed at the time limit";
    if (exec_failed) return "could not be started (" + exec_error + ")";
    if (signal != 0) return "was killed by signal " + std::to_string(signal) + " (" + strsignal(signal) + ")";
    if (exit_status != 0) return "exited with status " + std::to_string(exit_status);
    return "";
}

void end_by_signal(int sig)
{
    struct sigaction dfl {};
    dfl.sa_handler = SIG_DFL;
    ::sigaction(sig, &dfl, nullptr);
    sigset_t set;
    sigemptyset(&set);
    sigaddset(&set, sig);
    ::sigprocmask(SIG_UNBLOCK, &set, nullptr);
    ::raise(sig);
    _exit(128 + sig);  // a signal whose default is not to end the process
}

namespace {

constexpr int FORWARDED[] = {SIGINT, SIGTERM, SIGHUP};

// ---- the guard process (after fork: async-signal-safe calls only, no allocation) ----

/// What the guard writes back to the harness (one write, well under PIPE_BUF).
struct GuardReport {
    int exec_stage = 0;  ///< 0 started, 1 chdir failed, 2 exec failed
    int exec_errno = 0;
    int wait_status = 0;
    int timed_out = 0;
    int interrupted = 0;
    int orphans = 0;
    long maxrss_kb = -1;
    double wall_s = 0.0;
};

volatile sig_atomic_t g_guard_signal = 0;  // in the guard: the signal to forward to the group
void guard_on_signal(int sig) { g_guard_signal = sig; }

double now_s()
{
    timespec ts{};
    ::clock_gettime(CLOCK_MONOTONIC, &ts);
    return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
}

void write_all(int fd, const void* data, size_t bytes)
{
    const char* p = static_cast<const char*>(data);
    while (bytes > 0) {
        const ssize_t n = ::write(fd, p, bytes);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) return;
        p += n;
        bytes -= size_t(n);
    }
}

/// SIGKILLs every child of the guard (the program's orphans, re-parented to this subreaper);
/// returns how many were signalled, or -1 when the kernel does not list children.
int kill_children()
{
    const int fd = ::open("/proc/thread-self/children", O_RDONLY | O_CLOEXEC);
    if (fd < 0) return -1;
    char buffer[4096];
    ssize_t got = 0;
    for (;;) {
        const ssize_t n = ::read(fd, buffer + got, sizeof buffer - size_t(got));
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) break;
        got += n;
        if (got == ssize_t(sizeof buffer)) break;  // the rest are killed in the next round
    }
    ::close(fd);
    int count = 0;
    long pid = 0;
    bool digits = false;
    for (ssize_t i = 0; i < got; ++i) {
        if (buffer[i] >= '0' && buffer[i] <= '9') {
            pid = pid * 10 + (buffer[i] - '0');
            digits = true;
        } else {
            if (digits && pid > 0 && ::kill(pid_t(pid), SIGKILL) == 0) ++count;
            pid = 0;
            digits = false;
        }
    }
    return count;
}

struct GuardArgs {
    char* const* argv;
    const char* workdir;  // nullptr: stay
    int null_fd, out_fd, err_fd, report_fd;
    double time_limit_s, grace_s;
    pid_t harness;
};

[[noreturn]] void guard_main(const GuardArgs& a)
{
    struct sigaction act {};
    act.sa_handler = guard_on_signal;  // no SA_RESTART: a blocking call returns EINTR
    sigemptyset(&act.sa_mask);
    for (int sig : FORWARDED) ::sigaction(sig, &act, nullptr);
    sigset_t set;
    sigemptyset(&set);
    for (int sig : FORWARDED) sigaddset(&set, sig);
    ::sigprocmask(SIG_UNBLOCK, &set, nullptr);
    ::prctl(PR_SET_CHILD_SUBREAPER, 1, 0, 0, 0);
    ::prctl(PR_SET_PDEATHSIG, SIGTERM, 0, 0, 0);  // the harness dies (even by SIGKILL): end the program
    if (::getppid() != a.harness) g_guard_signal = SIGTERM;

    GuardReport report;
    int exec_pipe[2];
    if (::pipe2(exec_pipe, O_CLOEXEC) != 0) {
        report.exec_stage = 2;
        report.exec_errno = errno;
        write_all(a.report_fd, &report, sizeof report);
        _exit(0);
    }
    const double t0 = now_s();
    const pid_t pid = ::fork();
    if (pid == 0) {  // the program
        struct sigaction dfl {};
        dfl.sa_handler = SIG_DFL;
        for (int sig : FORWARDED) ::sigaction(sig, &dfl, nullptr);
        ::sigaction(SIGPIPE, &dfl, nullptr);
        sigset_t none;
        sigemptyset(&none);
        ::sigprocmask(SIG_SETMASK, &none, nullptr);
        ::setpgid(0, 0);
        int failure[2] = {0, 0};
        if (a.workdir && ::chdir(a.workdir) != 0) {
            failure[0] = 1;
            failure[1] = errno;
        } else {
            ::dup2(a.null_fd, 0);
            ::dup2(a.out_fd, 1);
            ::dup2(a.err_fd, 2);
            ::execvp(a.argv[0], a.argv);
            failure[0] = 2;
            failure[1] = errno;
        }
        write_all(exec_pipe[1], failure, sizeof failure);
        _exit(127);
    }
    ::close(exec_pipe[1]);
    for (int fd : {a.null_fd, a.out_fd, a.err_fd}) ::close(fd);  // the harness sees EOF once the program's are gone
    if (pid < 0) {
        report.exec_stage = 2;
        report.exec_errno = errno;
        write_all(a.report_fd, &report, sizeof report);
        _exit(0);
    }
    ::setpgid(pid, pid);  // also here: no window in which a kill of the group misses the program
    int failure[2] = {0, 0};
    size_t got = 0;
    while (got < sizeof failure) {  // EOF at exec (CLOEXEC), or the reason it failed
        const ssize_t n = ::read(exec_pipe[0], reinterpret_cast<char*>(failure) + got, sizeof failure - got);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) break;
        got += size_t(n);
    }
    ::close(exec_pipe[0]);
    if (got == sizeof failure) {
        report.exec_stage = failure[0];
        report.exec_errno = failure[1];
    }

#ifdef SYS_pidfd_open
    const int pfd = static_cast<int>(::syscall(SYS_pidfd_open, pid, 0));
#else
    const int pfd = -1;
#endif
    double kill_at = -1.0;  // after a forwarded signal: when the group is killed
    for (;;) {
        // WNOWAIT: the program stays unreaped, so its group id cannot be reused before the kill below.
        siginfo_t info{};
        const int rc = ::waitid(P_PID, id_t(pid), &info, WEXITED | WNOHANG | WNOWAIT);
        if (rc == 0 && info.si_pid == pid) break;
        const double now = now_s();
        if (g_guard_signal != 0 && report.interrupted == 0) {
            report.interrupted = g_guard_signal;
            ::kill(-pid, g_guard_signal);
            kill_at = now + a.grace_s;
        }
        if (kill_at >= 0.0 && now >= kill_at) ::kill(-pid, SIGKILL);
        double left = a.time_limit_s > 0.0 ? a.time_limit_s - (now - t0) : 1.0;
        if (a.time_limit_s > 0.0 && left <= 0.0 && report.interrupted == 0) {
            report.timed_out = 1;
            break;
        }
        left = std::min(left, 1.0);
        if (kill_at >= 0.0) left = std::min(left, std::max(0.0, kill_at - now) + 0.001);
        const int wait_ms = std::max(1, int(left * 1000.0 + 1.0));
        if (pfd >= 0) {
            pollfd p{pfd, POLLIN, 0};
            ::poll(&p, 1, wait_ms);  // a signal interrupts it (EINTR): the loop forwards it
        } else {
            const timespec ts{0, 2000000};  // no pidfd: look every 2 ms
            ::nanosleep(&ts, nullptr);
        }
    }
    report.wall_s = now_s() - t0;
    if (pfd >= 0) ::close(pfd);
    ::kill(-pid, SIGKILL);  // at the deadline the program, and in any case what it left in its group
    rusage usage{};
    while (::wait4(pid, &report.wait_status, 0, &usage) < 0 && errno == EINTR) {}
    report.maxrss_kb = usage.ru_maxrss;
    // Orphans: descendants that left the group are our children now; kill and reap until none is left.
    for (;;) {
        if (kill_children() < 0) {  // no list of children: reap what has ended, leave the rest
            while (::waitpid(-1, nullptr, WNOHANG) > 0) ++report.orphans;
            break;
        }
        const pid_t reaped = ::waitpid(-1, nullptr, 0);
        if (reaped > 0)
            ++report.orphans;
        else if (errno == ECHILD)
            break;
    }
    rusage children{};
    if (::getrusage(RUSAGE_CHILDREN, &children) == 0) report.maxrss_kb = std::max(report.maxrss_kb, children.ru_maxrss);
    write_all(a.report_fd, &report, sizeof report);
    _exit(0);
}

// ---- the harness side ----

int g_wake_fd = -1;                          // write end of the self-pipe
volatile sig_atomic_t g_harness_signal = 0;  // the last signal received while the program ran
void harness_on_signal(int sig)
{
    g_harness_signal = sig;
    const int saved = errno;
    const char byte = 1;
    (void)!::write(g_wake_fd, &byte, 1);
    errno = saved;
}

/// One of the program's streams into its file: the first `cap` bytes, the rest counted, the last
/// PROGRAM_OUTPUT_TAIL_BYTES kept for the end.
class CappedSink {
public:
    CappedSink(int fd, size_t cap) : m_fd(fd), m_cap(cap) {}
    void add(const char* data, size_t n)
    {
        if (m_total < m_cap) {
            const size_t keep = std::min<std::uint64_t>(n, m_cap - m_total);
            write_all(m_fd, data, keep);
        }
        m_total += n;
        m_tail.append(data, n);
        if (m_tail.size() > 2 * PROGRAM_OUTPUT_TAIL_BYTES) m_tail.erase(0, m_tail.size() - PROGRAM_OUTPUT_TAIL_BYTES);
    }
    /// Appends the note and the tail when capped; closes the file.
    void finish()
    {
        if (capped()) {
            const std::string tail = m_tail.substr(m_tail.size() - std::min(m_tail.size(), PROGRAM_OUTPUT_TAIL_BYTES));
            const std::string note = "\n[contactbench: the program wrote " + std::to_string(m_total) +
                                     " bytes here; only the first " + std::to_string(m_cap) + " (above) and the last " +
                                     std::to_string(tail.size()) + " (below) are kept]\n";
            write_all(m_fd, note.data(), note.size());
            write_all(m_fd, tail.data(), tail.size());
        }
        ::close(m_fd);
        m_fd = -1;
    }
    bool capped() const { return m_total > m_cap; }
    std::uint64_t total() const { return m_total; }

private:
    int m_fd;
    size_t m_cap;
    std::uint64_t m_total = 0;
    std::string m_tail;
};

/// Installs the forwarding handlers for the life of one run_program and restores the old ones.
class SignalForwarding {
public:
    explicit SignalForwarding(int wake_fd)
    {
        g_harness_signal = 0;
        g_wake_fd = wake_fd;
        struct sigaction act {};
        act.sa_handler = harness_on_signal;
        act.sa_flags = SA_RESTART;
        sigemptyset(&act.sa_mask);
        for (size_t i = 0; i < 3; ++i) ::sigaction(FORWARDED[i], &act, &m_old[i]);
    }
    ~SignalForwarding()
    {
        for (size_t i = 0; i < 3; ++i) ::sigaction(FORWARDED[i], &m_old[i], nullptr);
        g_wake_fd = -1;
    }
    SignalForwarding(const SignalForwarding&) = delete;
    SignalForwarding& operator=(const SignalForwarding&) = delete;

private:
    struct sigaction m_old[3];
};

/// RssAnon of this process in bytes, or -1: the part of its resident memory a forked child holds
/// page tables for (file-backed pages are faulted in afresh), so the part that counts in its peak.
long resident_bytes()
{
    std::ifstream status("/proc/self/status");
    std::string line;
    while (std::getline(status, line))
        if (line.rfind("RssAnon:", 0) == 0) {
            long kib = -1;
            std::istringstream(line.substr(8)) >> kib;
            return kib >= 0 ? kib * 1024 : -1;
        }
    return -1;
}

/// Closes the descriptors it holds unless released.
struct Fds {
    std::vector<int> fds;
    ~Fds()
    {
        for (int fd : fds)
            if (fd >= 0) ::close(fd);
    }
};

}  // namespace

ProgramOutcome run_program(const std::vector<std::string>& argv, const std::string& stdout_path,
                           const std::string& stderr_path, const ProgramOptions& options)
{
    if (argv.empty() || argv[0].empty()) throw std::invalid_argument("run_program: empty argv");
    // Everything the guard and the program need is prepared before fork: after it, no allocation.
    std::vector<char*> args;
    args.reserve(argv.size() + 1);
    for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    Fds held;
    auto pipe_or_throw = [&](int p[2]) {
        if (::pipe2(p, O_CLOEXEC) != 0)
            throw std::runtime_error(std::string("run_program: pipe: ") + std::strerror(errno));
        held.fds.push_back(p[0]);
        held.fds.push_back(p[1]);
    };
    int out_pipe[2], err_pipe[2], report_pipe[2], wake_pipe[2];
    pipe_or_throw(out_pipe);
    pipe_or_throw(err_pipe);
    pipe_or_throw(report_pipe);
    pipe_or_throw(wake_pipe);
    for (int fd : {wake_pipe[0], wake_pipe[1]}) ::fcntl(fd, F_SETFL, O_NONBLOCK);
    const int null_fd = ::open("/dev/null", O_RDONLY | O_CLOEXEC);
    held.fds.push_back(null_fd);
    const int out_fd = ::open(stdout_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC | O_NOFOLLOW, 0644);
    held.fds.push_back(out_fd);
    const int err_fd = ::open(stderr_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC | O_NOFOLLOW, 0644);
    held.fds.push_back(err_fd);
    if (out_fd < 0 || err_fd < 0 || null_fd < 0)
        throw std::runtime_error("run_program: cannot open " + stdout_path + " or " + stderr_path + ": " +
                                 std::strerror(errno));

    const GuardArgs guard_args{args.data(),
                               options.workdir.empty() ? nullptr : options.workdir.c_str(),
                               null_fd,
                               out_pipe[1],
                               err_pipe[1],
                               report_pipe[1],
                               options.time_limit_s,
                               options.grace_s,
                               ::getpid()};
    const long start_rss = resident_bytes();
    const SignalForwarding forwarding(wake_pipe[1]);
    // The guard must not run our handler before it installs its own: block the signals over fork.
    sigset_t block, old_mask;
    sigemptyset(&block);
    for (int sig : FORWARDED) sigaddset(&block, sig);
    ::pthread_sigmask(SIG_BLOCK, &block, &old_mask);
    const pid_t guard = ::fork();
    if (guard == 0) guard_main(guard_args);
    const int fork_errno = errno;
    ::pthread_sigmask(SIG_SETMASK, &old_mask, nullptr);
    if (guard < 0) throw std::runtime_error(std::string("fork: ") + std::strerror(fork_errno));
    // Only the guard and the program hold the write ends now.
    auto close_held = [&](int fd) {
        for (int& h : held.fds)
            if (h == fd) {
                ::close(h);
                h = -1;
            }
    };
    close_held(out_pipe[1]);
    close_held(err_pipe[1]);
    close_held(report_pipe[1]);
    close_held(null_fd);

    CappedSink sinks[2] = {CappedSink(out_fd, options.output_cap_bytes), CappedSink(err_fd, options.output_cap_bytes)};
    for (int& h : held.fds)
        if (h == out_fd || h == err_fd) h = -1;  // the sinks close them
    const int streams[2] = {out_pipe[0], err_pipe[0]};
    bool open_stream[2] = {true, true};
    GuardReport report;
    size_t report_got = 0;
    bool guard_done = false;
    double drain_until = -1.0;  // after the guard: orphans it could not kill may hold a pipe open
    int forwarded = 0;
    std::vector<char> buffer(1 << 16);
    while (!guard_done || open_stream[0] || open_stream[1]) {
        if (g_harness_signal != 0 && forwarded != g_harness_signal && !guard_done) {
            forwarded = g_harness_signal;
            ::kill(guard, forwarded);  // the guard forwards it to the program's group
        }
        if (guard_done && now_s() > drain_until) break;
        pollfd p[4];
        int n = 0;
        for (int s = 0; s < 2; ++s)
            if (open_stream[s]) p[n++] = {streams[s], POLLIN, 0};
        if (!guard_done) p[n++] = {report_pipe[0], POLLIN, 0};
        p[n++] = {wake_pipe[0], POLLIN, 0};
        if (::poll(p, nfds_t(n), guard_done ? 100 : 1000) < 0 && errno != EINTR)
            throw std::runtime_error(std::string("run_program: poll: ") + std::strerror(errno));
        for (int i = 0; i < n; ++i) {
            if (!(p[i].revents & (POLLIN | POLLHUP | POLLERR))) continue;
            if (p[i].fd == wake_pipe[0]) {
                char drain[64];
                while (::read(wake_pipe[0], drain, sizeof drain) > 0) {}
                continue;
            }
            if (p[i].fd == report_pipe[0]) {
                const ssize_t got =
                    ::read(report_pipe[0], reinterpret_cast<char*>(&report) + report_got, sizeof report - report_got);
                if (got > 0) report_got += size_t(got);
                if (got == 0 || (got < 0 && errno != EINTR && errno != EAGAIN)) {
                    guard_done = true;
                    drain_until = now_s() + 2.0;
                }
                continue;
            }
            const int s = p[i].fd == streams[0] ? 0 : 1;
            const ssize_t got = ::read(streams[s], buffer.data(), buffer.size());
            if (got > 0) sinks[s].add(buffer.data(), size_t(got));
            if (got == 0 || (got < 0 && errno != EINTR && errno != EAGAIN)) open_stream[s] = false;
        }
    }
    int guard_status = 0;
    while (::waitpid(guard, &guard_status, 0) < 0 && errno == EINTR) {}
    for (CappedSink& sink : sinks) sink.finish();

    ProgramOutcome outcome;
    outcome.stdout_bytes = sinks[0].total();
    outcome.stderr_bytes = sinks[1].total();
    outcome.stdout_capped = sinks[0].capped();
    outcome.stderr_capped = sinks[1].capped();
    outcome.interrupted = g_harness_signal != 0 ? int(g_harness_signal) : 0;
    if (report_got != sizeof report)
        throw std::runtime_error("run_program: the guard process of " + argv[0] + " ended without a report (" +
                                 (WIFSIGNALED(guard_status) ? "signal " + std::to_string(WTERMSIG(guard_status))
                                                            : "status " + std::to_string(WEXITSTATUS(guard_status))) +
                                 ")");
    if (report.interrupted != 0) outcome.interrupted = report.interrupted;
    outcome.wall_s = report.wall_s;
    outcome.timed_out = report.timed_out != 0;
    outcome.orphans_killed = report.orphans;
    outcome.peak_rss_bytes = report.maxrss_kb >= 0 ? report.maxrss_kb * 1024L : -1;  // kB on Linux
    outcome.start_rss_bytes = start_rss;
    if (report.exec_stage != 0) {
        outcome.exec_failed = true;
        outcome.exec_error = std::string(report.exec_stage == 1 ? "chdir " + options.workdir : "exec " + argv[0]) +
                             ": " + std::strerror(report.exec_errno);
        return outcome;
    }
    if (!outcome.timed_out) {
        if (WIFSIGNALED(report.wait_status)) outcome.signal = WTERMSIG(report.wait_status);
        if (WIFEXITED(report.wait_status)) outcome.exit_status = WEXITSTATUS(report.wait_status);
    }
    return outcome;
}

}  // namespace cb
