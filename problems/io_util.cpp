#include "problems/io_util.hpp"

#include "solvers/core/types.hpp"

#include <cerrno>
#include <cstring>
#include <fcntl.h>
#include <filesystem>
#include <set>
#include <stdio.h>  // renameat2
#include <sys/stat.h>
#include <unistd.h>
#include <vector>

namespace cb {

namespace fs = std::filesystem;

namespace {

std::string kind_of(mode_t mode)
{
    if (S_ISDIR(mode)) return "a folder";
    if (S_ISFIFO(mode)) return "a FIFO";
    if (S_ISSOCK(mode)) return "a socket";
    if (S_ISCHR(mode) || S_ISBLK(mode)) return "a device";
    return "not a plain file";
}

}  // namespace

int open_regular_file(const std::string& path)
{
    // O_NONBLOCK: opening a FIFO without a writer would otherwise wait forever.
    const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0) throw_input_error(path, "", std::string("cannot open: ") + std::strerror(errno));
    struct stat st {};
    if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
        const mode_t mode = st.st_mode;
        ::close(fd);
        throw_input_error(path, "", "not a regular file (" + kind_of(mode) + ")");
    }
    const int flags = ::fcntl(fd, F_GETFL);
    if (flags >= 0) ::fcntl(fd, F_SETFL, flags & ~O_NONBLOCK);
    return fd;
}

void require_regular_file(const std::string& path) { ::close(open_regular_file(path)); }

std::string regular_file_problem(const std::string& path)
{
    struct stat st {};
    if (::stat(path.c_str(), &st) != 0)
        return errno == ENOENT || errno == ENOTDIR ? "not found" : std::string("cannot open: ") + std::strerror(errno);
    return S_ISREG(st.st_mode) ? "" : "not a regular file (" + kind_of(st.st_mode) + ")";
}

std::string read_regular_file(const std::string& path, std::uint64_t max_bytes)
{
    const int fd = open_regular_file(path);
    struct stat st {};
    ::fstat(fd, &st);
    if (std::uint64_t(st.st_size) > max_bytes) {
        ::close(fd);
        throw_input_error(path, "",
                          "too large: " + std::to_string(st.st_size) + " bytes (at most " + std::to_string(max_bytes) +
                              ")");
    }
    std::string text(std::size_t(st.st_size), '\0');
    std::size_t done = 0;
    while (done < text.size()) {
        const ssize_t got = ::read(fd, &text[done], text.size() - done);
        if (got < 0 && errno == EINTR) continue;
        if (got < 0) {
            const int err = errno;
            ::close(fd);
            throw_input_error(path, "", std::string("read failed: ") + std::strerror(err));
        }
        if (got == 0) break;  // the file shrank while we read it
        done += std::size_t(got);
    }
    ::close(fd);
    text.resize(done);
    return text;
}

void check_json_depth(const char* begin, const char* end, const std::string& where, const std::string& field,
                      int max_depth)
{
    int depth = 0;
    bool in_string = false, escaped = false;
    for (const char* p = begin; p < end; ++p) {
        const char ch = *p;
        if (in_string) {
            if (escaped)
                escaped = false;
            else if (ch == '\\')
                escaped = true;
            else if (ch == '"')
                in_string = false;
            continue;
        }
        if (ch == '"')
            in_string = true;
        else if (ch == '[' || ch == '{') {
            if (++depth > max_depth)
                throw_input_error(where, field,
                                  "JSON nested deeper than " + std::to_string(max_depth) + " levels (at byte " +
                                      std::to_string(p - begin) + ")");
        } else if ((ch == ']' || ch == '}') && depth > 0) {
            --depth;
        }
    }
}

namespace {

/// Refuses a key given twice in one object (nlohmann keeps the last silently, so a second
/// "solvers" or "time_limit_s" would override the first unseen). Tracks the open objects and
/// arrays to name the place as a JSON pointer ("/solvers/2/name").
class DuplicateKeyCheck {
public:
    explicit DuplicateKeyCheck(const std::string& where) : m_where(where) {}
    bool operator()(int, nlohmann::json::parse_event_t event, const nlohmann::json& parsed)
    {
        using E = nlohmann::json::parse_event_t;
        switch (event) {
        case E::object_start:
        case E::array_start:
            m_frames.push_back({event == E::object_start, {}, "", 0});
            break;
        case E::key: {
            Frame& f = m_frames.back();
            f.key = parsed.get<std::string>();
            if (!f.keys.insert(f.key).second)
                throw_input_error(m_where, pointer(), "key given twice in one object (each key once)");
            break;
        }
        case E::object_end:
        case E::array_end:
            m_frames.pop_back();
            next_element();
            break;
        case E::value:
            next_element();
            break;
        }
        return true;
    }

private:
    struct Frame {
        bool object;
        std::set<std::string> keys;
        std::string key;
        size_t index;
    };
    void next_element()
    {
        if (!m_frames.empty() && !m_frames.back().object) ++m_frames.back().index;
    }
    std::string pointer() const
    {
        std::string p;
        for (const auto& f : m_frames) p += "/" + (f.object ? f.key : std::to_string(f.index));
        return p;
    }
    std::string m_where;
    std::vector<Frame> m_frames;
};

}  // namespace

nlohmann::json parse_json_text(const std::string& text, const std::string& where, bool allow_comments)
{
    check_json_depth(text.data(), text.data() + text.size(), where);
    try {
        return nlohmann::json::parse(text, DuplicateKeyCheck(where), true, allow_comments);
    } catch (const nlohmann::json::exception& e) {
        throw_input_error(where, "", std::string("not valid JSON: ") + e.what());
    }
}

nlohmann::json read_json_checked(const std::string& path, bool allow_comments)
{
    return parse_json_text(read_regular_file(path, std::uint64_t(256) << 20), path, allow_comments);
}

void fsync_dir(const std::string& dir)
{
    const int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (fd < 0) return;
    ::fsync(fd);
    ::close(fd);
}

void replace_dir(const std::string& staged, const std::string& target)
{
    std::error_code ec;
    const fs::path parent = fs::path(target).parent_path();
    const std::string parent_dir = parent.empty() ? "." : parent.string();
    if (!fs::exists(fs::symlink_status(target))) {
        if (::rename(staged.c_str(), target.c_str()) != 0) {
            const int err = errno;
            fs::remove_all(staged, ec);
            throw_input_error(target, "", std::string("cannot rename into place: ") + std::strerror(err));
        }
        fsync_dir(parent_dir);
        return;
    }
#ifdef RENAME_EXCHANGE
    if (::renameat2(AT_FDCWD, staged.c_str(), AT_FDCWD, target.c_str(), RENAME_EXCHANGE) == 0) {
        fsync_dir(parent_dir);
        fs::remove_all(staged, ec);  // now the old content
        return;
    }
#endif
    // Two renames; the old folder goes back when the second fails.
    const std::string old = target + ".old." + std::to_string(::getpid());
    if (::rename(target.c_str(), old.c_str()) != 0) {
        const int err = errno;
        fs::remove_all(staged, ec);
        throw_input_error(target, "", std::string("cannot replace: ") + std::strerror(err));
    }
    if (::rename(staged.c_str(), target.c_str()) != 0) {
        const int err = errno;
        ::rename(old.c_str(), target.c_str());
        fs::remove_all(staged, ec);
        throw_input_error(target, "", std::string("cannot replace: ") + std::strerror(err) + " (old content kept)");
    }
    fsync_dir(parent_dir);
    fs::remove_all(old, ec);
}

}  // namespace cb
