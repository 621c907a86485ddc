#pragma once
/// The one way contactbench writes a file (issue 27): every writer, a results record, summary.csv,
/// --json, --out, a convert target, a merged run, an sbatch file, goes through AtomicFile or
/// write_file_atomic, so these rules hold everywhere:
///  - a regular target (or none yet) is written as PATH.tmp.<pid> in the target's own folder,
///    every write checked, fsync'ed, and renamed over PATH; on any error the temporary is removed
///    and PATH is untouched ("PATH: write failed: ... (nothing written)");
///  - a target that exists and is not a regular file is never replaced: a FIFO (with a reader)
///    or a character device such as /dev/null or /dev/stdout is written to directly, a folder, a
///    block device or a socket is refused ("PATH: is a folder: not replaced"); a symlink counts as
///    what it points to. SpecialTarget::REFUSE refuses FIFOs and devices too (for writers that
///    need to seek, such as HDF5);
///  - nothing is created or renamed under /dev or /proc: /dev/stdout, /dev/fd/N, /proc/self/fd/N
///    are written to directly (a regular file behind them, as with `--json /dev/stdout > f`, is
///    appended to), and a name there that does not exist is refused;
///  - the temporary is created fresh (an entry of that name is unlinked first, never followed);
///  - PATH.tmp.<pid> files left by an interrupted earlier run (that process is gone, and the file
///    untouched for 10 minutes) are removed, with a note on stderr naming each, before the new
///    temporary is created; a younger one is named in a note and kept (on a shared file system
///    another machine's process of that pid may be writing it).
/// Errors are InputErrors naming PATH, so the command line exits 2.
#include <cstddef>
#include <string>

namespace cb {

/// What AtomicFile does with a target that exists and is a FIFO or a character device.
enum class SpecialTarget {
    WRITE_THROUGH,  ///< write to it directly (no temporary, no rename): `--json /dev/stdout`
    REFUSE,         ///< InputError: the writer needs a regular file
};

/// An output file written under a temporary name and renamed over PATH by commit() (see above).
/// Destroyed uncommitted, it removes the temporary, so a failed writer leaves no partial output.
class AtomicFile {
public:
    explicit AtomicFile(std::string path, SpecialTarget special = SpecialTarget::WRITE_THROUGH);
    ~AtomicFile();
    AtomicFile(const AtomicFile&) = delete;
    AtomicFile& operator=(const AtomicFile&) = delete;

    void write(const void* data, std::size_t bytes);
    void write(const std::string& text) { write(text.data(), text.size()); }
    /// fsync, close, rename (a direct target: close only).
    void commit();
    const std::string& path() const { return m_path; }
    /// True when writing straight into a FIFO or a device (no temporary).
    bool direct() const { return m_tmp.empty(); }

    /// For a library that writes by file name (libfclib): closes this object's descriptor and
    /// returns the temporary's name, which the library may recreate. commit() then fsyncs and
    /// renames whatever is there; destruction without commit() removes it. Needs a regular
    /// target (construct with SpecialTarget::REFUSE).
    const std::string& hand_over_temporary();

private:
    [[noreturn]] void fail(const std::string& what, int err);
    std::string m_path, m_tmp;
    int m_fd = -1;
    bool m_committed = false;
};

/// Writes `content` to `path` through an AtomicFile; creates missing parent folders.
void write_file_atomic(const std::string& path, const std::string& content);

/// Removes TARGET.tmp.<pid> entries beside `target` whose process is gone and that are untouched
/// for 10 minutes (a file, a link, or a folder such as DIR.tmp.<pid> of the Matrix Market
/// writer), printing "note: removed ..." for each, and names younger ones ("note: kept ...");
/// returns how many were removed. A temporary of a live process is left alone. The folder is
/// listed once per process (later calls look up what that listing found).
std::size_t remove_stale_temporaries(const std::string& target);

}  // namespace cb
