// The one output path of contactbench (rules in safe_output.hpp).
#include "problems/safe_output.hpp"

#include "problems/io_util.hpp"  // fsync_dir
#include "solvers/core/types.hpp"

#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <fcntl.h>
#include <filesystem>
#include <iostream>
#include <map>
#include <mutex>
#include <set>
#include <sys/stat.h>
#include <unistd.h>

namespace cb {

namespace fs = std::filesystem;

namespace {

/// A temporary of a gone process untouched for this long is a leftover (see remove_stale_temporaries).
constexpr long STALE_AFTER_SECONDS = 600;

/// N for /dev/stdout (1), /dev/stderr (2), /dev/fd/N and /proc/self/fd/N; -1 for any other name.
int own_descriptor(const std::string& absolute)
{
    if (absolute == "/dev/stdout") return 1;
    if (absolute == "/dev/stderr") return 2;
    for (const std::string& prefix :
         {std::string("/dev/fd/"), std::string("/proc/self/fd/"), "/proc/" + std::to_string(::getpid()) + "/fd/"}) {
        if (absolute.rfind(prefix, 0) != 0) continue;
        const std::string digits = absolute.substr(prefix.size());
        if (digits.empty() || digits.size() > 6 || digits.find_first_not_of("0123456789") != std::string::npos)
            return -1;
        return std::stoi(digits);
    }
    return -1;
}

std::string folder_of(const std::string& path)
{
    const fs::path parent = fs::path(path).parent_path();
    return parent.empty() ? "." : parent.string();
}

/// The pid of NAME when it is "<base>.tmp.<digits>", else -1.
long temporary_pid(const std::string& name, std::string* base)
{
    const size_t dot = name.rfind(".tmp.");
    if (dot == std::string::npos || dot == 0) return -1;
    const std::string digits = name.substr(dot + 5);
    if (digits.empty() || digits.size() > 9 || digits.find_first_not_of("0123456789") != std::string::npos) return -1;
    *base = name.substr(0, dot);
    return std::stol(digits);
}

/// A process that no longer exists (EPERM: it exists but belongs to someone else).
bool process_gone(long pid) { return pid > 0 && pid != ::getpid() && ::kill(pid_t(pid), 0) != 0 && errno == ESRCH; }

/// Per folder, the stale temporaries found by its one listing: base name -> entry names.
using StaleByBase = std::map<std::string, std::set<std::string>>;

StaleByBase& stale_in(const std::string& folder)
{
    static std::map<std::string, StaleByBase> listed;
    auto it = listed.find(folder);
    if (it != listed.end()) return it->second;
    StaleByBase stale;
    std::error_code ec;
    for (fs::directory_iterator entry(folder, ec), end; !ec && entry != end; entry.increment(ec)) {
        std::string base;
        const std::string name = entry->path().filename().string();
        if (process_gone(temporary_pid(name, &base))) stale[base].insert(name);
    }
    return listed.emplace(folder, std::move(stale)).first->second;
}

std::string kind_of(mode_t mode)
{
    if (S_ISDIR(mode)) return "a folder";
    if (S_ISFIFO(mode)) return "a FIFO";
    if (S_ISSOCK(mode)) return "a socket";
    if (S_ISBLK(mode)) return "a block device";
    if (S_ISCHR(mode)) return "a device";
    return "not a regular file";
}

}  // namespace

std::size_t remove_stale_temporaries(const std::string& target)
{
    static std::mutex mutex;
    const std::lock_guard<std::mutex> lock(mutex);
    const std::string folder = folder_of(target);
    StaleByBase& stale = stale_in(folder);
    const auto it = stale.find(fs::path(target).filename().string());
    if (it == stale.end()) return 0;
    std::size_t removed = 0;
    for (const auto& name : it->second) {
        const fs::path entry = fs::path(folder) / name;
        const std::string pid = name.substr(name.rfind(".tmp.") + 5);
        struct stat st {};
        if (::lstat(entry.c_str(), &st) != 0) continue;  // already gone
        // The pid is only known gone on this machine: a young temporary may be another machine's
        // write in progress on a shared file system (a cache written by two array tasks). Ours are
        // written within seconds, so one untouched for STALE_AFTER_SECONDS is left over.
        if (std::time(nullptr) - st.st_mtime < STALE_AFTER_SECONDS) {
            std::cerr << "note: kept " << entry.string() << ": process " << pid
                      << " is gone here, but the file is younger than " << STALE_AFTER_SECONDS / 60
                      << " minutes (another machine may be writing it); remove it if not\n";
            continue;
        }
        std::error_code ec;
        const fs::file_status status = fs::symlink_status(entry, ec);
        if (ec || !fs::exists(status)) continue;
        // A folder is removed as a whole only when it is a real folder (never through a link).
        if (fs::is_directory(status))
            fs::remove_all(entry, ec);
        else
            fs::remove(entry, ec);
        if (ec) continue;
        ++removed;
        std::cerr << "note: removed " << entry.string() << ", left by an interrupted earlier run (process " << pid
                  << " is gone)\n";
    }
    stale.erase(it);  // each is removed or named once per process
    return removed;
}

AtomicFile::AtomicFile(std::string path, SpecialTarget special) : m_path(std::move(path))
{
    if (m_path.empty()) throw_input_error("(empty path)", "", "an output file name is required, got \"\"");
    const fs::path target(m_path);
    if (target.filename().empty() || target.filename() == "." || target.filename() == "..")
        throw_input_error(m_path, "", "names a folder, not a file");
    std::error_code ec;
    // /dev/stdout, /dev/fd/N, /proc/self/fd/N: links to whatever the shell opened. A rename would
    // replace the system's link itself (as root), so nothing is created or renamed there.
    const std::string absolute = fs::absolute(target, ec).lexically_normal().string();
    const bool system_folder = absolute.rfind("/dev/", 0) == 0 || absolute.rfind("/proc/", 0) == 0;
    if (!system_folder && target.has_parent_path()) fs::create_directories(target.parent_path(), ec);
    if (ec) throw_input_error(m_path, "", "cannot create the folder: " + ec.message());

    struct stat st {};
    const bool exists = ::stat(m_path.c_str(), &st) == 0;
    if (system_folder && (!exists || S_ISREG(st.st_mode))) {
        if (!exists || special == SpecialTarget::REFUSE)
            throw_input_error(m_path, "",
                              std::string("is under /dev or /proc: ") +
                                  (exists ? "this output needs a regular file of its own"
                                          : "only an existing device or stream is written there"));
        // A regular file behind /dev/stdout (`> out.txt`): written through this process's own
        // descriptor when the name is one (sharing its offset, after what the command printed),
        // else appended to.
        std::cout.flush();
        std::cerr.flush();
        std::fflush(nullptr);
        const int own = own_descriptor(absolute);
        m_fd = own >= 0 ? ::fcntl(own, F_DUPFD_CLOEXEC, 3)
                        : ::open(m_path.c_str(), O_WRONLY | O_APPEND | O_CLOEXEC | O_NOCTTY);
        if (m_fd < 0) throw_input_error(m_path, "", std::string("cannot write: ") + std::strerror(errno));
        return;
    }
    if (exists && !S_ISREG(st.st_mode)) {
        // Never replaced: a rename would turn the FIFO or device into a regular file.
        const bool streamable = S_ISFIFO(st.st_mode) || S_ISCHR(st.st_mode);
        if (!streamable || special == SpecialTarget::REFUSE)
            throw_input_error(m_path, "",
                              "is " + kind_of(st.st_mode) + ": not replaced (" +
                                  (streamable ? "this output needs a regular file" : "name a file") + ")");
        // O_NONBLOCK: a FIFO without a reader fails at once (ENXIO) instead of waiting forever.
        m_fd = ::open(m_path.c_str(), O_WRONLY | O_NONBLOCK | O_CLOEXEC | O_NOCTTY);
        if (m_fd < 0) {
            const int err = errno;
            throw_input_error(m_path, "",
                              err == ENXIO ? std::string("is a FIFO with no reader: nothing written")
                                           : std::string("cannot write: ") + std::strerror(err));
        }
        struct stat opened {};
        if (::fstat(m_fd, &opened) != 0 || (S_ISREG(opened.st_mode) && !system_folder)) {  // swapped: refuse
            ::close(m_fd);
            m_fd = -1;
            throw_input_error(m_path, "", "changed while being opened: nothing written");
        }
        const int flags = ::fcntl(m_fd, F_GETFL);
        if (flags >= 0) ::fcntl(m_fd, F_SETFL, flags & ~O_NONBLOCK);
        return;
    }

    remove_stale_temporaries(m_path);
    m_tmp = m_path + ".tmp." + std::to_string(::getpid());
    // A leftover or planted entry of this name is removed, never followed (O_EXCL | O_NOFOLLOW).
    ::unlink(m_tmp.c_str());
    m_fd = ::open(m_tmp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0644);
    if (m_fd < 0) {
        const int err = errno;
        m_tmp.clear();  // not ours: nothing to remove
        m_committed = true;
        throw_input_error(m_path, "", std::string("cannot write: ") + std::strerror(err));
    }
}

AtomicFile::~AtomicFile()
{
    if (m_fd >= 0) ::close(m_fd);
    if (!m_committed && !m_tmp.empty()) ::unlink(m_tmp.c_str());
}

void AtomicFile::fail(const std::string& what, int err)
{
    if (m_fd >= 0) ::close(m_fd);
    m_fd = -1;
    if (!m_tmp.empty()) ::unlink(m_tmp.c_str());
    m_committed = true;  // nothing left to clean up
    throw_input_error(m_path, "",
                      what + ": " + std::strerror(err) + (m_tmp.empty() ? std::string() : " (nothing written)"));
}

void AtomicFile::write(const void* data, std::size_t bytes)
{
    const char* p = static_cast<const char*>(data);
    while (bytes > 0) {
        const ssize_t got = ::write(m_fd, p, bytes);
        if (got < 0 && errno == EINTR) continue;
        if (got <= 0) fail("write failed", got < 0 ? errno : ENOSPC);
        p += got;
        bytes -= std::size_t(got);
    }
}

const std::string& AtomicFile::hand_over_temporary()
{
    if (direct()) throw_input_error(m_path, "", "needs a regular file");
    if (m_fd >= 0) ::close(m_fd);
    m_fd = -1;
    return m_tmp;
}

void AtomicFile::commit()
{
    if (direct()) {
        const int fd = m_fd;
        m_fd = -1;
        m_committed = true;
        if (::close(fd) != 0) throw_input_error(m_path, "", std::string("write failed: ") + std::strerror(errno));
        return;
    }
    if (m_fd < 0) {  // handed over: the library wrote and closed the temporary by name
        m_fd = ::open(m_tmp.c_str(), O_RDONLY | O_NOFOLLOW | O_CLOEXEC);
        if (m_fd < 0) fail("the temporary file vanished", errno);
    }
    if (::fsync(m_fd) != 0) fail("write failed", errno);
    const int fd = m_fd;
    m_fd = -1;
    if (::close(fd) != 0) fail("write failed", errno);
    // Checked again just before the rename: a FIFO or device put there meanwhile is not replaced.
    struct stat st {};
    if (::stat(m_path.c_str(), &st) == 0 && !S_ISREG(st.st_mode)) {
        ::unlink(m_tmp.c_str());
        m_committed = true;
        throw_input_error(m_path, "", "became " + kind_of(st.st_mode) + " while being written: not replaced");
    }
    if (::rename(m_tmp.c_str(), m_path.c_str()) != 0) {
        const int err = errno;
        ::unlink(m_tmp.c_str());
        m_committed = true;
        throw_input_error(m_path, "", std::string("cannot rename into place: ") + std::strerror(err));
    }
    m_committed = true;
    fsync_dir(folder_of(m_path));
}

void write_file_atomic(const std::string& path, const std::string& content)
{
    AtomicFile out(path);
    out.write(content);
    out.commit();
}

}  // namespace cb
