// Format recognition by content (format_sniff.hpp): signatures, not file names.
#include "problems/format_sniff.hpp"

#include "problems/fclib_io.hpp"
#include "problems/io_util.hpp"

#include <cctype>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <sys/stat.h>
#include <unistd.h>

namespace cb {
namespace {

namespace fs = std::filesystem;

/// Up to `count` bytes at `offset` (fewer at the end of the file).
std::string bytes_at(int fd, off_t offset, size_t count)
{
    std::string out(count, '\0');
    const ssize_t got = ::pread(fd, &out[0], count, offset);
    out.resize(got > 0 ? size_t(got) : 0);
    return out;
}

const char HDF5_SIGNATURE[] = "\x89HDF\r\n\x1a\n";

/// One integer (signed) on the line starting at `pos`, then the line's end; advances `pos`.
bool integer_line(const std::string& head, size_t& pos)
{
    pos = head.find_first_not_of(" \t\r\n", pos);
    if (pos == std::string::npos) return false;
    const size_t stop = head.find_first_of("\r\n", pos);
    if (stop == std::string::npos) return false;
    size_t k = pos;
    if (head[k] == '-' || head[k] == '+') ++k;
    const size_t digits = k;
    while (k < stop && std::isdigit(static_cast<unsigned char>(head[k]))) ++k;
    if (k == digits) return false;
    while (k < stop && (head[k] == ' ' || head[k] == '\t')) ++k;
    pos = stop;
    return k == stop;
}

/// Text whose first four lines (blank ones skipped) hold one integer each: Siconos numerics'
/// printInFile layout of a friction-contact problem (dimension, contacts, the matrix's storage
/// type and first size). The values are not judged here: the .dat reader names a bad one.
bool looks_like_siconos_dat(const std::string& head)
{
    for (const char ch : head) {  // text: no control byte but white space (UTF-8 remarks allowed)
        const unsigned char c = static_cast<unsigned char>(ch);
        if ((c < 32 || c == 127) && !std::isspace(c)) return false;
    }
    size_t pos = 0;
    for (int line = 0; line < 4; ++line)
        if (!integer_line(head, pos)) return false;
    return true;
}

}  // namespace

FileFormat sniff_format(const std::string& path)
{
    std::error_code ec;
    const fs::file_status st = fs::status(path, ec);
    if (!ec && fs::is_directory(st))
        return fs::exists(fs::path(path) / "A.mtx", ec) ? FileFormat::MATRIX_MARKET_FOLDER : FileFormat::FOLDER;
    const int fd = open_regular_file(path);  // a FIFO or device: refused here, never waited on
    const std::string head = bytes_at(fd, 0, 2048);
    struct stat info {};
    ::fstat(fd, &info);
    // HDF5 allows a user block of 512, 1024, 2048 ... bytes before its signature.
    bool hdf5 = false;
    for (off_t at = 0; at < info.st_size && at <= (off_t(1) << 20) && !hdf5; at = at == 0 ? 512 : 2 * at)
        hdf5 = bytes_at(fd, at, 8) == std::string(HDF5_SIGNATURE, 8);
    ::close(fd);
    if (hdf5) {
        std::string kind;
        try {
            kind = fclib_kind(path);
        } catch (const InputError&) {
            // HDF5 cannot open it: a damaged HDF5 file
        }
        return kind == "fclib_global"  ? FileFormat::FCLIB_GLOBAL
               : kind == "fclib_local" ? FileFormat::FCLIB_LOCAL
                                       : FileFormat::HDF5;
    }
    if (head.compare(0, 6, "\x93NUMPY") == 0) return FileFormat::NPY;
    if (head.compare(0, 14, "%%MatrixMarket") == 0) return FileFormat::MATRIX_MARKET_FILE;
    if (head.size() >= 9) {
        std::uint64_t length = 0;
        for (int k = 7; k >= 0; --k) length = (length << 8) | static_cast<unsigned char>(head[size_t(k)]);
        if (length <= std::uint64_t(info.st_size) - 8 && head[8] == '{') return FileFormat::QPSNAP;
    }
    if (looks_like_siconos_dat(head)) return FileFormat::SICONOS_DAT;
    return FileFormat::UNKNOWN;
}

std::string format_name(FileFormat format)
{
    switch (format) {
    case FileFormat::QPSNAP:
        return "a .qpsnap snapshot";
    case FileFormat::FCLIB_GLOBAL:
        return "an FCLIB fclib_global problem (HDF5)";
    case FileFormat::FCLIB_LOCAL:
        return "an FCLIB fclib_local problem (HDF5)";
    case FileFormat::HDF5:
        return fclib_version().empty() ? "an HDF5 file (FCLIB support is not built)"
                                       : "an HDF5 file without an FCLIB problem";
    case FileFormat::SICONOS_DAT:
        return "a Siconos numerics text dump (.dat)";
    case FileFormat::MATRIX_MARKET_FOLDER:
        return "a Matrix Market folder";
    case FileFormat::MATRIX_MARKET_FILE:
        return "a single Matrix Market file";
    case FileFormat::NPY:
        return "a NumPy array (.npy)";
    case FileFormat::FOLDER:
        return "a folder without A.mtx";
    case FileFormat::UNKNOWN:
        break;
    }
    return "a file of unknown format";
}

void expect_qpsnap(const std::string& path, const std::string& command)
{
    const FileFormat format = sniff_format(path);
    if (format == FileFormat::QPSNAP || format == FileFormat::UNKNOWN) return;
    std::string how;
    switch (format) {
    case FileFormat::FCLIB_GLOBAL:  // convert keeps a 3-D global problem's friction (snapshot version 2)
        how = "convert it first: contactbench convert " + path +
              " OUT.qpsnap (a frictional problem keeps its friction; --drop-friction keeps only its normal part), "
              "or solve it with its friction: contactbench friction-solve " +
              path;
        break;
    case FileFormat::FCLIB_LOCAL:  // no A: a snapshot cannot hold a local problem's friction
        how = "convert it first: contactbench convert " + path +
              " OUT.qpsnap (a frictional problem needs --drop-friction: its normal part), or solve it with its "
              "friction: contactbench friction-solve " +
              path;
        break;
    case FileFormat::MATRIX_MARKET_FOLDER:
        how = "convert it first: contactbench convert " + path + " OUT.qpsnap";
        break;
    case FileFormat::SICONOS_DAT:
        how = "convert a local problem first: contactbench convert " + path +
              " OUT.qpsnap --drop-friction (its normal part), or solve it with its friction: contactbench "
              "friction-solve " +
              path;
        break;
    case FileFormat::MATRIX_MARKET_FILE:
        how = "a problem is a folder of them (A.mtx b.mtx J.mtx c.mtx x0.mtx): convert the folder";
        break;
    case FileFormat::NPY:
        how = "a snapshot holds a whole QP: write one from numpy/scipy arrays with plots/qpsnap.py's write_qpsnap";
        break;
    default:
        how = "not a problem contactbench reads";
        break;
    }
    const std::string reads =
        command == "convert"
            ? "convert reads .qpsnap snapshots, Matrix Market folders, FCLIB files and Siconos .dat files"
        : command == "info" ? "info reads .qpsnap snapshots and Matrix Market folders, and summarises FCLIB and "
                              "Siconos .dat files"
                            : command + " reads .qpsnap snapshots";
    throw_input_error(path, "format", format_name(format) + ", not a .qpsnap snapshot (" + reads + "); " + how);
}

}  // namespace cb
