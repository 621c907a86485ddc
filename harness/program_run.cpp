// fork + execvp with a deadline: see program_run.hpp.
#include "harness/program_run.hpp"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/syscall.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <stdexcept>
#include <thread>

namespace cb {

std::string ProgramOutcome::failure() const
{
    if (timed_out) return "was killed at the time limit";
    if (exec_failed) return "could not be started";
    if (signal != 0) return "was killed by signal " + std::to_string(signal) + " (" + strsignal(signal) + ")";
    if (exit_status != 0) return "exited with status " + std::to_string(exit_status);
    return "";
}

namespace {

/// A descriptor that becomes readable when process `pid` ends (Linux >= 5.3), or -1.
int process_fd(pid_t pid)
{
#ifdef SYS_pidfd_open
    return static_cast<int>(::syscall(SYS_pidfd_open, pid, 0));
#else
    (void)pid;
    return -1;
#endif
}

}  // namespace

ProgramOutcome run_program(const std::vector<std::string>& argv, const std::string& stdout_path,
                           const std::string& stderr_path, double time_limit_s)
{
    if (argv.empty() || argv[0].empty()) throw std::invalid_argument("run_program: empty argv");
    // Everything the child needs is prepared before fork: after it, only async-signal-safe calls.
    std::vector<char*> args;
    args.reserve(argv.size() + 1);
    for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    const int out_fd = ::open(stdout_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    const int err_fd = ::open(stderr_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    const int null_fd = ::open("/dev/null", O_RDONLY | O_CLOEXEC);
    if (out_fd < 0 || err_fd < 0 || null_fd < 0) {
        const int err = errno;
        for (int fd : {out_fd, err_fd, null_fd})
            if (fd >= 0) ::close(fd);
        throw std::runtime_error("run_program: cannot open " + stdout_path + " or " + stderr_path + ": " +
                                 std::strerror(err));
    }
    const auto start = std::chrono::steady_clock::now();
    const pid_t pid = ::fork();
    if (pid < 0) {
        const int err = errno;
        for (int fd : {out_fd, err_fd, null_fd}) ::close(fd);
        throw std::runtime_error(std::string("fork: ") + std::strerror(err));
    }
    if (pid == 0) {
        ::setpgid(0, 0);
        ::dup2(null_fd, 0);
        ::dup2(out_fd, 1);
        ::dup2(err_fd, 2);
        ::execvp(args[0], args.data());
        static const char msg[] = "contactbench: execvp failed: ";
        (void)!::write(2, msg, sizeof msg - 1);
        const char* why = std::strerror(errno);
        (void)!::write(2, why, std::strlen(why));
        (void)!::write(2, "\n", 1);
        _exit(127);
    }
    ::setpgid(pid, pid);  // also here: no window in which a kill of the group misses the child
    for (int fd : {out_fd, err_fd, null_fd}) ::close(fd);

    ProgramOutcome outcome;
    const int pfd = process_fd(pid);
    auto elapsed = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(); };
    for (;;) {
        // WNOWAIT: the child stays unreaped, so its process group id cannot be reused before
        // the group is killed below.
        siginfo_t info{};
        const int rc = ::waitid(P_PID, static_cast<id_t>(pid), &info, WEXITED | WNOHANG | WNOWAIT);
        if (rc == 0 && info.si_pid == pid) break;
        if (rc < 0 && errno != EINTR) throw std::runtime_error(std::string("waitid: ") + std::strerror(errno));
        const double left = time_limit_s > 0.0 ? time_limit_s - elapsed() : 1e9;
        if (left <= 0.0) {
            outcome.timed_out = true;
            break;
        }
        const int wait_ms = static_cast<int>(std::min(left * 1000.0 + 1.0, 1e6));
        if (pfd >= 0) {
            pollfd p{pfd, POLLIN, 0};
            ::poll(&p, 1, wait_ms);
        } else {  // no pidfd: poll the child every 2 ms
            std::this_thread::sleep_for(std::chrono::milliseconds(std::min(wait_ms, 2)));
        }
    }
    outcome.wall_s = elapsed();
    if (pfd >= 0) ::close(pfd);
    // At the deadline the program, and in any case whatever it left running in its group, goes.
    ::kill(-pid, SIGKILL);
    int wstatus = 0;
    while (::waitpid(pid, &wstatus, 0) < 0 && errno == EINTR) {}
    if (!outcome.timed_out) {
        if (WIFSIGNALED(wstatus)) outcome.signal = WTERMSIG(wstatus);
        if (WIFEXITED(wstatus)) outcome.exit_status = WEXITSTATUS(wstatus);
        outcome.exec_failed = outcome.exit_status == 127;
    }
    return outcome;
}

}  // namespace cb
