#pragma once
/// A CSV table written as PATH.partial while a run (`simulate`, `chains`) goes on, renamed to PATH
/// when whole; an interrupted run's table is reopened for appending after its whole frames.
#include "problems/io_util.hpp"
#include "problems/output_folder.hpp"

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fcntl.h>
#include <filesystem>
#include <set>
#include <string>
#include <unistd.h>

namespace cb::sim {

/// A table written as PATH.partial while the simulation runs: rows are appended a frame at a
/// time, each append flushed and checked (a full disk or file-size limit is an error naming the
/// file), and finish() fsyncs and renames it to PATH. An interrupted run leaves only .partial
/// tables (clearly incomplete); a failed one leaves none.
class PartialTable {
public:
    void open(const std::string& path, const std::string& header)
    {
        set_paths(path);
        // Created fresh: an entry of that name is removed, never followed (O_EXCL | O_NOFOLLOW).
        ::unlink(m_partial.c_str());
        const int fd = ::open(m_partial.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0644);
        m_file = fd < 0 ? nullptr : ::fdopen(fd, "w");
        if (!m_file) {
            const int err = errno;
            if (fd >= 0) ::close(fd);
            throw_input_error(m_path, "", std::string("cannot write: ") + std::strerror(err));
        }
        append(header);
    }
    /// Reopens the table of an interrupted (or finished, to be extended) run for appending, with
    /// the rows of frames >= keep_frames dropped (a frame stepped after the last resume state).
    /// Refused (InputError) when the header differs or a frame below keep_frames has no row.
    void resume(const std::string& path, const std::string& header, long keep_frames)
    {
        set_paths(path);
        namespace fs = std::filesystem;
        std::error_code ec;
        const bool partial = fs::exists(fs::symlink_status(m_partial, ec));
        const std::string source = partial ? m_partial : path;
        const std::string text = read_regular_file(source);
        if (text.compare(0, header.size(), header) != 0)
            throw_input_error(source, "",
                              "another header than this simulator writes: not resumed (--fresh discards it)");
        std::string kept = header;
        std::set<long> frames;
        for (size_t at = header.size(); at < text.size();) {
            size_t end = text.find('\n', at);
            if (end == std::string::npos) break;  // a row cut short by the interruption
            const long frame = std::strtol(text.c_str() + at, nullptr, 10);
            if (frame < keep_frames) {
                kept.append(text, at, end + 1 - at);
                frames.insert(frame);
            }
            at = end + 1;
        }
        if (static_cast<long>(frames.size()) != keep_frames)
            throw_input_error(source, "",
                              "has rows of " + std::to_string(frames.size()) + " frames where the resume state says " +
                                  std::to_string(keep_frames) + " are whole: not resumed (--fresh discards it)");
        write_file_atomic(m_partial, kept);
        if (!partial) fs::remove(path, ec);  // a finished table being extended is .partial again
        const int fd = ::open(m_partial.c_str(), O_WRONLY | O_APPEND | O_NOFOLLOW | O_CLOEXEC);
        m_file = fd < 0 ? nullptr : ::fdopen(fd, "a");
        if (!m_file) {
            const int err = errno;
            if (fd >= 0) ::close(fd);
            throw_input_error(m_path, "", std::string("cannot write: ") + std::strerror(err));
        }
    }
    /// Reopens a table of another writer (`chains`) whose state records its first keep_bytes
    /// bytes as whole (PATH.partial when a run was killed, else PATH), for appending after them.
    void resume_prefix(const std::string& path, const std::string& header, size_t keep_bytes)
    {
        set_paths(path);
        namespace fs = std::filesystem;
        std::error_code ec;
        const bool partial = fs::exists(fs::symlink_status(m_partial, ec));
        const std::string source = partial ? m_partial : path;
        if (!partial && !fs::exists(fs::symlink_status(path, ec)))
            throw_input_error(path, "", "missing: not resumed (--fresh discards the run)");
        std::string text = read_regular_file(source);
        if (text.compare(0, header.size(), header) != 0 || text.size() < keep_bytes)
            throw_input_error(source, "",
                              "another header, or shorter than the whole frames its state records: not resumed "
                              "(--fresh discards it)");
        text.resize(keep_bytes);
        write_file_atomic(m_partial, text);
        if (!partial) fs::remove(path, ec);
        const int fd = ::open(m_partial.c_str(), O_WRONLY | O_APPEND | O_NOFOLLOW | O_CLOEXEC);
        m_file = fd < 0 ? nullptr : ::fdopen(fd, "a");
        if (!m_file) {
            const int err = errno;
            if (fd >= 0) ::close(fd);
            throw_input_error(m_path, "", std::string("cannot write: ") + std::strerror(err));
        }
    }
    void append(const std::string& rows)
    {
        if (std::fwrite(rows.data(), 1, rows.size(), m_file) != rows.size() || std::fflush(m_file) != 0) fail();
    }
    void finish()
    {
        if (::fsync(::fileno(m_file)) != 0) fail();
        const int rc = std::fclose(m_file);
        m_file = nullptr;
        if (rc != 0 || std::rename(m_partial.c_str(), m_path.c_str()) != 0) fail();
    }
    void abandon()
    {
        if (m_file) std::fclose(m_file);
        m_file = nullptr;
        if (!m_partial.empty()) std::remove(m_partial.c_str());
    }
    ~PartialTable()
    {
        if (m_file) std::fclose(m_file);
    }

private:
    /// The table and its .partial are replaced by rename and unlink: neither may be a link or a
    /// special file (the output-folder rule, problems/output_folder.hpp), refused before any write.
    void set_paths(const std::string& path)
    {
        check_output_entry(path);
        check_output_entry(path + ".partial");
        m_path = path;
        m_partial = path + ".partial";
    }
    [[noreturn]] void fail()
    {
        const std::string why = std::strerror(errno);
        abandon();
        throw_input_error(m_path, "", "write failed: " + why + " (the tables are incomplete; nothing kept)");
    }
    std::string m_path, m_partial;
    std::FILE* m_file = nullptr;
};

}  // namespace cb::sim
