#include "harness/run_lock.hpp"

#include "solvers/core/types.hpp"

#include <cerrno>
#include <cstring>
#include <fcntl.h>
#include <filesystem>
#include <sstream>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

namespace cb {

namespace {
int g_lock_fd = -1;  // the descriptor holding the flock of lock_output_folder
}  // namespace

void release_output_folder_lock()
{
    if (g_lock_fd >= 0) ::close(g_lock_fd);  // closing the last descriptor drops the flock
    g_lock_fd = -1;
}

void lock_output_folder(const std::string& out, const std::string& command)
{
    namespace fs = std::filesystem;
    std::error_code ec;
    fs::create_directories(out, ec);
    if (ec) throw_input_error(out, "--out", "cannot create the output folder: " + ec.message());
    const std::string path = (fs::path(out) / ".lock").string();
    // O_NOFOLLOW: a symlink planted as .lock would make the ftruncate below empty its target.
    const int fd = ::open(path.c_str(), O_RDWR | O_CREAT | O_NOFOLLOW | O_NONBLOCK | O_CLOEXEC, 0644);
    if (fd < 0) throw_input_error(path, "", std::string("cannot create the lock file: ") + std::strerror(errno));
    struct stat st {};
    if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
        ::close(fd);
        throw_input_error(path, "", "not a regular file: not used as the lock");
    }
    if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
        char text[64] = {0};
        const ssize_t got = ::pread(fd, text, sizeof text - 1, 0);
        ::close(fd);
        std::istringstream holder(got > 0 ? std::string(text, size_t(got)) : std::string());
        std::string pid, other;
        holder >> pid >> other;  // a lock written before the command was recorded holds the pid only
        throw_input_error(out, "",
                          "another `contactbench " + (other.empty() ? command : other) + "` (pid " +
                              (pid.empty() ? "?" : pid) +
                              ") is writing to this folder; wait for it to finish or use another --out");
    }
    const std::string me = std::to_string(::getpid()) + " " + command + "\n";
    if (::ftruncate(fd, 0) == 0 && ::pwrite(fd, me.data(), me.size(), 0) < 0) {
        // the pid is only for the message of a second command
    }
    g_lock_fd = fd;  // stays open (and locked) until exit or release_output_folder_lock()
}

}  // namespace cb
