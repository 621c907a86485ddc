#include "harness/process_pool.hpp"

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <iostream>
#include <stdexcept>
#include <sys/wait.h>
#include <unistd.h>

namespace cb {

ProcessPool::ProcessPool(long limit) : m_limit(limit < 1 ? 1 : limit) {}

ProcessPool::~ProcessPool()
{
    if (!m_in_child) wait_all();
}

void ProcessPool::reap_one()
{
    int status = 0;
    pid_t pid = -1;
    do {
        pid = ::waitpid(-1, &status, 0);
    } while (pid < 0 && errno == EINTR);
    if (pid < 0) {
        m_children.clear();  // ECHILD: nothing left to wait for
        return;
    }
    if (!m_children.erase(pid)) return;
    if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) ++m_failed;
}

bool ProcessPool::delegate()
{
    if (!parallel() || m_in_child) return false;
    while (static_cast<long>(m_children.size()) >= m_limit) reap_one();
    std::cout.flush();
    std::cerr.flush();
    std::fflush(nullptr);  // no buffered output duplicated into the child
    const pid_t pid = ::fork();
    if (pid < 0) throw std::runtime_error(std::string("fork failed: ") + std::strerror(errno));
    if (pid == 0) {
        m_in_child = true;
        m_children.clear();
        return false;
    }
    m_children.insert(pid);
    return true;
}

void ProcessPool::job_done() const
{
    if (!m_in_child) return;
    std::cout.flush();
    std::cerr.flush();
    std::fflush(nullptr);
    std::_Exit(0);  // the parent's atexit handlers and static objects are the parent's business
}

size_t ProcessPool::wait_all()
{
    while (!m_children.empty()) reap_one();
    const size_t failed = m_failed;
    m_failed = 0;
    return failed;
}

long concurrent_jobs(long jobs, bool suite_timed, bool chain, bool jobs_timed, std::string& note)
{
    note.clear();
    if (jobs <= 1) return 1;
    const std::string n = std::to_string(jobs);
    if (chain) {
        note = "--jobs " + n + ": a chain carries warm state from job to job, so its jobs run one at a time";
        return 1;
    }
    if (suite_timed && !jobs_timed) {
        note = "--jobs " + n +
               ": this suite's times are judged, so its runs go one at a time (\"timed\": false in "
               "the suite, or --jobs-timed, runs them " +
               n + " at a time)";
        return 1;
    }
    note = "--jobs " + n + ": runs go " + n + " at a time in child processes" +
           (suite_timed ? " (--jobs-timed: their times share the machine and are not comparable)"
                        : " (\"timed\": false: counters as in a serial run, times not judged)");
    return jobs;
}

std::string oversubscription_warning(long jobs, long threads, long cores)
{
    if (cores <= 0 || jobs * threads <= cores) return "";
    return "warning: " + std::to_string(jobs) + " job(s) at a time x " + std::to_string(threads) +
           " thread(s) = " + std::to_string(jobs * threads) + " threads on " + std::to_string(cores) +
           " core(s): runs share cores, so their times are slower than on a machine to themselves";
}

}  // namespace cb
