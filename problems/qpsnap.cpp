// The .qpsnap reader and writer (version 1; version 2 adds the friction fields). The reader
// takes the whole file in one read, checks the header, every array's place, size and CRC32, then
// the CSR structure and values, and builds the Eigen matrices straight from the arrays (no
// triplets): a 10M-nonzero A loads in a fraction of a second. Nothing is returned unless
// everything passed.
#include "problems/qpsnap.hpp"

#include "problems/io_util.hpp"
#include "solvers/linalg/prefault.hpp"

#include <zlib.h>

#include <algorithm>
#include <cerrno>
#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fcntl.h>
#include <functional>
#include <memory>
#include <sys/mman.h>
#include <sys/stat.h>
#include <thread>
#include <type_traits>
#include <unistd.h>

namespace cb {
namespace {

constexpr std::uint64_t MAX_INT32 = 2147483647ULL;

std::string fmt_double(double v)
{
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.17g", v);
    return buf;
}

std::string str(std::uint64_t v) { return std::to_string(v); }
std::string str(std::int64_t v) { return std::to_string(v); }

/// The file's bytes, read at once.
struct FileBytes {
    std::unique_ptr<unsigned char[]> data;
    std::uint64_t size = 0;       ///< bytes read
    std::uint64_t file_size = 0;  ///< bytes in the file
};

void refuse_sparse(const std::string& path, int fd, std::uint64_t size);

FileBytes read_all(const std::string& path, std::uint64_t limit = ~0ULL)
{
    const int fd = open_regular_file(path);  // a FIFO or folder is refused, not waited on
    struct stat st {};
    ::fstat(fd, &st);
    try {
        refuse_sparse(path, fd, std::uint64_t(st.st_size));  // a header length into a hole: no 4 GB buffer
    } catch (...) {
        ::close(fd);
        throw;
    }
    FileBytes f;
    f.file_size = std::uint64_t(st.st_size);
    f.size = std::min<std::uint64_t>(f.file_size, limit);
    f.data.reset(new unsigned char[std::max<std::uint64_t>(f.size, 1)]);
    std::uint64_t done = 0;
    while (done < f.size) {
        const ssize_t got = ::read(fd, f.data.get() + done, std::min<std::uint64_t>(f.size - done, 1ULL << 30));
        if (got < 0 && errno == EINTR) continue;
        if (got <= 0) {
            ::close(fd);
            throw_input_error(path, "", "read failed after " + str(done) + " bytes");
        }
        done += std::uint64_t(got);
    }
    ::close(fd);
    return f;
}

/// Bytes of `fd` that are holes (never written: a sparse file reads them as zeros without
/// storing them). Our writer leaves none; a declared array that lies in a hole would make the
/// reader commit memory for data the file does not hold, so more than a little is refused.
void refuse_sparse(const std::string& path, int fd, std::uint64_t size)
{
    std::uint64_t holes = 0, first_hole = size;
    off_t pos = 0;
    while (std::uint64_t(pos) < size) {
        const off_t hole = ::lseek(fd, pos, SEEK_HOLE);
        if (hole < 0 || std::uint64_t(hole) >= size) break;  // no (more) holes, or not supported
        off_t data = ::lseek(fd, hole, SEEK_DATA);
        if (data < 0) data = off_t(size);  // a hole up to the end
        if (holes == 0) first_hole = std::uint64_t(hole);
        holes += std::uint64_t(data - hole);
        pos = data;
    }
    ::lseek(fd, 0, SEEK_SET);
    const std::uint64_t allowed = std::max<std::uint64_t>(std::uint64_t(64) << 20, (size - holes));
    if (holes > allowed)
        throw_input_error(path, "data",
                          "sparse file: " + str(holes) + " of its " + str(size) + " bytes (from byte " +
                              str(first_hole) + ") are holes, not data written to the file");
}

/// The whole file mapped read-only (no copy out of the page cache); empty files are not mapped.
/// Populated up front: the checks walk it all; the copy into the matrices gives its pages back
/// behind it (PageRelease), so the file never sits whole beside the matrices built from it.
class MappedFile {
public:
    explicit MappedFile(const std::string& path)
    {
        const int fd = open_regular_file(path);  // a FIFO or folder is refused, not waited on
        struct stat st {};
        ::fstat(fd, &st);
        m_size = std::uint64_t(st.st_size);
        try {
            refuse_sparse(path, fd, m_size);
        } catch (...) {
            ::close(fd);
            throw;
        }
        if (m_size > 0) {
            void* p = ::mmap(nullptr, m_size, PROT_READ, MAP_PRIVATE | MAP_POPULATE, fd, 0);
            if (p == MAP_FAILED) {
                ::close(fd);
                throw_input_error(path, "", std::string("cannot map: ") + std::strerror(errno));
            }
            m_data = static_cast<const unsigned char*>(p);
        }
        ::close(fd);
    }
    ~MappedFile()
    {
        if (m_data) ::munmap(const_cast<unsigned char*>(m_data), m_size);
    }
    MappedFile(const MappedFile&) = delete;
    MappedFile& operator=(const MappedFile&) = delete;
    const unsigned char* data() const { return m_data ? m_data : &m_empty; }
    std::uint64_t size() const { return m_size; }

private:
    const unsigned char* m_data = nullptr;
    std::uint64_t m_size = 0;
    unsigned char m_empty = 0;
};

/// Gives the pages of a read-only file mapping back once the copy out of them is done
/// (MADV_DONTNEED: they stay in the page cache; nothing was written, so nothing is lost). The 760 MB
/// file of a million DOFs held whole beside the 550 MB matrix built from it made the load the
/// process's peak. Only the last pass releases: releasing after each of the checks too (checksum,
/// structure, values) halved that peak again but mapped the pages anew each time, 0.2 s more per
/// load. Default-constructed (bytes in memory): releases nothing.
class PageRelease {
public:
    /// Bytes the copy handles before it releases them.
    static constexpr std::uint64_t CHUNK = std::uint64_t(8) << 20;

    PageRelease() = default;
    bool releases() const { return m_begin != nullptr; }
    PageRelease(const unsigned char* begin, std::uint64_t size) : m_begin(begin), m_end(begin + size) {}

    /// Releases the pages that [from, to) covers inside the mapping (a page shared with bytes
    /// still to be read is mapped again when they are: safe, at the cost of a fault).
    void release(const void* from, const void* to) const
    {
        const auto* lo = std::max(static_cast<const unsigned char*>(from), m_begin);
        const auto* hi = std::min(static_cast<const unsigned char*>(to), m_end);
        if (lo >= hi) return;
        const std::uintptr_t page = std::uintptr_t(::sysconf(_SC_PAGESIZE));
        const std::uintptr_t first = reinterpret_cast<std::uintptr_t>(lo) & ~(page - 1);
        const std::uintptr_t last = reinterpret_cast<std::uintptr_t>(hi);
        // The address is only rounded as an integer; the advised pointer is lo's own moved back.
        ::madvise(const_cast<unsigned char*>(lo) - (reinterpret_cast<std::uintptr_t>(lo) - first), last - first,
                  MADV_DONTNEED);
    }

    /// Calls work(offset, bytes) over [p, p + nbytes) in CHUNK pieces, releasing each when done.
    template <typename Work> void in_chunks(const unsigned char* p, std::uint64_t nbytes, Work&& work) const
    {
        for (std::uint64_t offset = 0; offset < nbytes; offset += CHUNK) {
            const std::uint64_t bytes = std::min(CHUNK, nbytes - offset);
            work(offset, bytes);
            release(p + offset, p + offset + bytes);
        }
    }

private:
    const unsigned char* m_begin = nullptr;
    const unsigned char* m_end = nullptr;
};

std::uint64_t load_u64_le(const unsigned char* p)
{
    std::uint64_t v = 0;
    for (int i = 7; i >= 0; --i) v = (v << 8) | p[i];
    return v;
}

/// Parses and checks the header (everything but the arrays).
nlohmann::json parse_header(const std::string& path, const unsigned char* bytes, std::uint64_t file_size,
                            std::uint64_t* header_len)
{
    if (file_size < 8)
        throw_input_error(path, "header",
                          "file too short: " + str(file_size) +
                              " bytes, a .qpsnap starts with an 8-byte header length");
    const std::uint64_t N = load_u64_le(bytes);
    if (N > file_size - 8)
        throw_input_error(path, "header",
                          "header length " + str(N) + " exceeds the file (" + str(file_size - 8) +
                              " bytes after the length field)");
    // Deep nesting would overflow the stack of the parser (and of the JSON destructor).
    check_json_depth(reinterpret_cast<const char*>(bytes + 8), reinterpret_cast<const char*>(bytes + 8 + N), path,
                     "header");
    nlohmann::json h;
    try {
        h = nlohmann::json::parse(bytes + 8, bytes + 8 + N);
    } catch (const nlohmann::json::parse_error& e) {
        throw_input_error(path, "header",
                          "not valid UTF-8 JSON (parse error at header byte " + str(std::uint64_t(e.byte)) + ")");
    } catch (const nlohmann::json::exception& e) {
        // e.g. out_of_range 406: a number literal too large for a double (found by the fuzzer)
        throw_input_error(path, "header", std::string("not a valid JSON header: ") + e.what());
    }
    if (!h.is_object()) throw_input_error(path, "header", "expected a JSON object, got " + std::string(h.type_name()));
    if (!h.contains("format")) throw_input_error(path, "format", "missing (expected \"qpsnap\")");
    if (h["format"] != "qpsnap") throw_input_error(path, "format", "expected \"qpsnap\", got " + h["format"].dump());
    if (!h.contains("version")) throw_input_error(path, "version", "missing (expected 1 or 2)");
    if (h["version"] != 1 && h["version"] != 2)
        throw_input_error(path, "version",
                          "unsupported version " + h["version"].dump() + " (this reader knows versions 1 and 2)");
    for (const char* key : {"n", "m"}) {
        if (!h.contains(key)) throw_input_error(path, key, "missing");
        const auto& v = h[key];
        if (!v.is_number_integer() || (v.is_number_integer() && !v.is_number_unsigned() && v.get<std::int64_t>() < 0))
            throw_input_error(path, key, "expected a non-negative integer, got " + v.dump());
        if (v.get<std::uint64_t>() > MAX_INT32)
            throw_input_error(path, key, "too large: " + v.dump() + " > 2147483647 (indices are 32-bit)");
    }
    require_unknowns(path, h["n"].get<std::uint64_t>());
    if (!h.contains("arrays") || !h["arrays"].is_object())
        throw_input_error(path, "arrays", "missing or not an object");
    if (h.contains("meta") && !h["meta"].is_object())
        throw_input_error(path, "meta", "expected an object, got " + h["meta"].dump());
    if (h.contains("h")) {
        if (h["version"] == 1) throw_input_error(path, "h", "a version 2 field in a version 1 snapshot");
        const auto& step = h["h"];
        if (!step.is_number() || !(step.get<double>() > 0) || !std::isfinite(step.get<double>()))
            throw_input_error(path, "h", "expected a positive finite time step, got " + step.dump());
    }
    if (header_len) *header_len = N;
    return h;
}

struct ArraySpec {
    const char* name;
    const char* dtype;
    bool required;
};

const ArraySpec ARRAYS[] = {
    {"A.indptr", "int64", true},
    {"A.indices", "int64", true},
    {"A.data", "float64", true},
    {"b", "float64", true},
    {"x0", "float64", true},
    {"J.indptr", "int64", true},
    {"J.indices", "int64", true},
    {"J.data", "float64", true},
    {"c", "float64", true},
    {"contact.kind", "int64", false},
    {"contact.depth", "float64", false},
    {"contact.vertex", "int64", false},
    {"x_ref", "float64", false},
    {"lambda_ref", "float64", false},
    // version 2: Coulomb friction (solvers/core/qp.hpp Friction)
    {"mu", "float64", false},
    {"T.indptr", "int64", false},
    {"T.indices", "int64", false},
    {"T.data", "float64", false},
    {"cT", "float64", false},
    {"v0", "float64", false},
};

/// The arrays only version 2 may hold.
bool version2_array(const std::string& name)
{
    return name == "mu" || name == "T.indptr" || name == "T.indices" || name == "T.data" || name == "cT" ||
           name == "v0";
}

/// One array, located and CRC-checked.
struct Located {
    const unsigned char* ptr = nullptr;
    std::uint64_t count = 0;  ///< elements
    std::vector<std::uint64_t> shape;
    bool present = false;
    const std::int64_t* i64() const { return reinterpret_cast<const std::int64_t*>(ptr); }
    const double* f64() const { return reinterpret_cast<const double*>(ptr); }
};

std::uint64_t get_uint(const std::string& path, const std::string& field, const nlohmann::json& v)
{
    if (!v.is_number_integer() || (!v.is_number_unsigned() && v.get<std::int64_t>() < 0))
        throw_input_error(path, field, "expected a non-negative integer, got " + v.dump());
    return v.get<std::uint64_t>();
}

/// zlib CRC32; a large array is split in two halves checked on two threads and combined.
std::uint64_t crc32_of(const unsigned char* p, std::uint64_t nbytes)
{
    const std::uint64_t init = crc32_z(0L, Z_NULL, 0);
    if (nbytes < (16u << 20)) return crc32_z(init, p, nbytes);
    const std::uint64_t half = nbytes / 2;
    std::uint64_t second = 0;
    std::thread worker([&] { second = crc32_z(init, p + half, nbytes - half); });
    const std::uint64_t first = crc32_z(init, p, half);
    worker.join();
    return crc32_combine(first, second, z_off_t(nbytes - half));
}

Located locate(const std::string& path, const std::string& name, const char* dtype, const nlohmann::json& entry,
               const unsigned char* buffer, std::uint64_t buffer_size)
{
    Located a;
    a.present = true;
    if (!entry.is_object()) throw_input_error(path, name, "expected an object {dtype, shape, offset, nbytes, crc32}");
    for (const char* key : {"dtype", "shape", "offset", "nbytes", "crc32"})
        if (!entry.contains(key)) throw_input_error(path, name + "." + key, "missing");
    if (entry["dtype"] != dtype)
        throw_input_error(path, name + ".dtype",
                          std::string("expected \"") + dtype + "\", got " + entry["dtype"].dump());
    const auto& shape = entry["shape"];
    if (!shape.is_array())
        throw_input_error(path, name + ".shape", "expected an array of integers, got " + shape.dump());
    a.count = 1;
    for (const auto& s : shape) {
        const std::uint64_t d = get_uint(path, name + ".shape", s);
        if (d > (1ULL << 40)) throw_input_error(path, name + ".shape", "dimension " + str(d) + " too large");
        a.shape.push_back(d);
        a.count *= d;
    }
    const std::uint64_t offset = get_uint(path, name + ".offset", entry["offset"]);
    const std::uint64_t nbytes = get_uint(path, name + ".nbytes", entry["nbytes"]);
    const std::uint64_t crc = get_uint(path, name + ".crc32", entry["crc32"]);
    if (nbytes != a.count * 8)
        throw_input_error(path, name + ".nbytes",
                          str(nbytes) + " does not match shape " + shape.dump() + " (expected " + str(a.count * 8) +
                              ")");
    if (offset % 8 != 0) throw_input_error(path, name + ".offset", str(offset) + " is not 8-byte aligned");
    if (offset > buffer_size || nbytes > buffer_size - offset)
        throw_input_error(path, name + ".offset",
                          "bytes [" + str(offset) + ", " + str(offset + nbytes) + ") lie outside the data buffer of " +
                              str(buffer_size) + " bytes");
    a.ptr = buffer + offset;
    const std::uint64_t actual = crc32_of(a.ptr, nbytes);
    if (actual != crc)
        throw_input_error(path, name + ".crc32", "mismatch: header says " + str(crc) + ", data has " + str(actual));
    return a;
}

void expect_shape(const std::string& path, const std::string& name, const Located& a,
                  const std::vector<std::uint64_t>& shape, const std::string& why)
{
    if (a.shape == shape) return;
    auto show = [](const std::vector<std::uint64_t>& s) {
        std::string o = "[";
        for (size_t i = 0; i < s.size(); ++i) o += (i ? ", " : "") + str(s[i]);
        return o + "]";
    };
    throw_input_error(path, name + ".shape", "expected " + show(shape) + " (" + why + "), got " + show(a.shape));
}

void check_finite(const std::string& path, const std::string& name, const double* v, std::uint64_t count)
{
    // One pass without branches; locate the culprit only on failure.
    double acc[4] = {0, 0, 0, 0};  // NaN or Inf times 0 is NaN; finite times 0 is 0
    std::uint64_t i = 0;
    for (; i + 4 <= count; i += 4)
        for (int k = 0; k < 4; ++k) acc[k] += v[i + k] * 0.0;
    for (; i < count; ++i) acc[0] += v[i] * 0.0;
    if (acc[0] + acc[1] + acc[2] + acc[3] == 0.0) return;
    for (i = 0; i < count; ++i)
        if (!std::isfinite(v[i]))
            throw_input_error(path, name, "non-finite value " + fmt_double(v[i]) + " at index " + str(i));
}

/// Checks a CSR structure (indptr, indices) of `rows` rows with `cols` columns.
void check_csr(const std::string& path, const std::string& mat, const Located& indptr, const Located& indices,
               std::uint64_t rows, std::uint64_t cols)
{
    const std::int64_t* p = indptr.i64();
    const std::int64_t* ix = indices.i64();
    const std::int64_t nnz = std::int64_t(indices.count);
    if (p[0] != 0) throw_input_error(path, mat + ".indptr", "must start at 0, starts at " + str(p[0]));
    for (std::uint64_t r = 0; r < rows; ++r)
        if (p[r + 1] < p[r])
            throw_input_error(path, mat + ".indptr",
                              "decreases at row " + str(r) + " (" + str(p[r]) + " then " + str(p[r + 1]) + ")");
    if (p[rows] != nnz)
        throw_input_error(path, mat + ".indptr",
                          "ends at " + str(p[rows]) + ", expected nnz = " + str(nnz) + " (the length of " + mat +
                              ".indices)");
    const std::int64_t ncols = std::int64_t(cols);
    for (std::uint64_t r = 0; r < rows; ++r) {
        std::int64_t prev = -1;
        for (std::int64_t e = p[r]; e < p[r + 1]; ++e) {
            const std::int64_t j = ix[e];
            if (j < 0 || j >= ncols)
                throw_input_error(path, mat + ".indices",
                                  "column " + str(j) + " out of range [0, " + str(ncols) + ") in row " + str(r));
            if (j <= prev)
                throw_input_error(path, mat + ".indices",
                                  "columns not strictly increasing in row " + str(r) + " (" + str(prev) + " then " +
                                      str(j) + ")");
            prev = j;
        }
    }
}

/// Builds a compressed row-major matrix from checked CSR arrays.
void build_csr(SpMat& M, std::uint64_t rows, std::uint64_t cols, const Located& indptr, const Located& indices,
               const Located& data, const PageRelease& pages)
{
    M.resize(Eigen::Index(rows), Eigen::Index(cols));
    M.resizeNonZeros(Eigen::Index(indices.count));
    advise_huge_pages(M.innerIndexPtr(), indices.count * sizeof(int));
    advise_huge_pages(M.valuePtr(), indices.count * sizeof(double));
    int* outer = M.outerIndexPtr();
    const std::int64_t* p = indptr.i64();
    for (std::uint64_t r = 0; r <= rows; ++r) outer[r] = int(p[r]);
    pages.release(p, p + rows + 1);
    int* inner = M.innerIndexPtr();
    const std::int64_t* ix = indices.i64();
    pages.in_chunks(indices.ptr, indices.count * 8, [&](std::uint64_t offset, std::uint64_t bytes) {
        for (std::uint64_t e = offset / 8; e < (offset + bytes) / 8; ++e) inner[e] = int(ix[e]);
    });
    auto* values = reinterpret_cast<unsigned char*>(M.valuePtr());
    pages.in_chunks(data.ptr, data.count * 8, [&](std::uint64_t offset, std::uint64_t bytes) {
        std::memcpy(values + offset, data.ptr + offset, bytes);
    });
}

/// Symmetry check and exact symmetrisation of A (row-major, sorted rows). Fast path: the
/// pattern is symmetric and each mirrored pair is averaged in place; a one-sided entry makes the
/// pattern grow, handled by (A + A') / 2 through Eigen.
void symmetrise(const std::string& path, SpMat& A)
{
    const Eigen::Index n = A.rows();
    const int* outer = A.outerIndexPtr();
    const int* inner = A.innerIndexPtr();
    double* val = A.valuePtr();
    double max_abs = 0.0;
    for (Eigen::Index e = 0; e < A.nonZeros(); ++e) max_abs = std::max(max_abs, std::abs(val[e]));
    const double tol = 1e-12 * max_abs;
    // cursor[j]: the next not yet matched entry of row j right of the diagonal. Rows are visited
    // in order, so the mirror of (i, j), j < i, is always the next entry at cursor[j].
    std::vector<int> cursor(n);
    for (Eigen::Index r = 0; r < n; ++r) {
        const int* begin = inner + outer[r];
        const int* end = inner + outer[r + 1];
        cursor[r] = int(std::upper_bound(begin, end, int(r)) - inner);
    }
    double worst = -1.0;
    Eigen::Index wi = 0, wj = 0;
    double wa = 0, wb = 0;
    bool one_sided = false;
    auto note = [&](Eigen::Index i, Eigen::Index j, double a, double b) {
        const double d = std::abs(a - b);
        if (d > worst) {
            worst = d;
            wi = i, wj = j, wa = a, wb = b;
        }
    };
    for (Eigen::Index i = 0; i < n; ++i) {
        for (int e = outer[i]; e < outer[i + 1]; ++e) {
            const int j = inner[e];
            if (j >= i) break;
            // Upper entries (j, k) with k < i were skipped by every row k: one-sided.
            while (cursor[j] < outer[j + 1] && inner[cursor[j]] < i) {
                note(j, inner[cursor[j]], val[cursor[j]], 0.0);
                one_sided = true;
                ++cursor[j];
            }
            if (cursor[j] < outer[j + 1] && inner[cursor[j]] == i) {
                double& upper = val[cursor[j]];
                double& lower = val[e];
                note(j, i, upper, lower);
                if (upper != lower) upper = lower = 0.5 * upper + 0.5 * lower;
                ++cursor[j];
            } else {
                note(i, j, val[e], 0.0);
                one_sided = true;
            }
        }
    }
    for (Eigen::Index j = 0; j < n; ++j)
        for (int e = cursor[j]; e < outer[j + 1]; ++e) {
            note(j, inner[e], val[e], 0.0);
            one_sided = true;
        }
    if (worst > tol) {
        // Report the stored pair as (i, j) with A(i, j) the stored value and A(j, i) its mirror.
        throw_input_error(path, "A",
                          "not symmetric: A(" + str(std::int64_t(wi)) + ", " + str(std::int64_t(wj)) +
                              ") = " + fmt_double(wa) + " but A(" + str(std::int64_t(wj)) + ", " +
                              str(std::int64_t(wi)) + ") = " + fmt_double(wb) + " (difference " + fmt_double(worst) +
                              " > 1e-12 * max|A_ij| = " + fmt_double(tol) + ")");
    }
    if (one_sided) {
        SpMat At = A.transpose();
        SpMat S = (0.5 * A + 0.5 * At).pruned(0.0, 0.0);  // a tiny one-sided entry is mirrored at half
        S.makeCompressed();
        A = S;  // Eigen 3.4 SparseMatrix has no move assignment: a copy either way
    }
}

void check_diagonal(const std::string& path, const SpMat& A)
{
    for (Eigen::Index i = 0; i < A.rows(); ++i) {
        const int* begin = A.innerIndexPtr() + A.outerIndexPtr()[i];
        const int* end = A.innerIndexPtr() + A.outerIndexPtr()[i + 1];
        const int* at = std::lower_bound(begin, end, int(i));
        const std::string entry = "A(" + str(std::int64_t(i)) + ", " + str(std::int64_t(i)) + ")";
        if (at == end || *at != i)
            throw_input_error(path, "A", "diagonal entry " + entry + " is missing (A must be SPD)");
        const double d = A.valuePtr()[at - A.innerIndexPtr()];
        if (!(d > 0))
            throw_input_error(path, "A",
                              "diagonal entry " + entry + " = " + fmt_double(d) + " is not positive (A must be SPD)");
    }
}

/// The rules of the friction fields (solvers/core/qp.hpp Friction) on a QP in memory, as the reader
/// applies them to a file: mu and T together, sizes, finite values, mu >= 0, h > 0 with v0.
void check_friction(const std::string& where, const Qp& qp)
{
    const Friction& f = qp.friction;
    const std::int64_t n = qp.A.rows(), m = qp.J.rows();
    const auto size_text = [](Eigen::Index r, Eigen::Index c) {
        return str(std::int64_t(r)) + " x " + str(std::int64_t(c));
    };
    if (f.mu.size() == 0) {
        if (f.T.rows() != 0 || f.T.cols() != 0)
            throw_input_error(where, "mu", "missing: T is given without friction coefficients");
        if (f.cT.size() != 0) throw_input_error(where, "cT", "given without the tangent rows T");
    } else {
        if (f.mu.size() != m)
            throw_input_error(where, "mu",
                              "expected size m = " + str(m) + " (one per contact row), got " +
                                  str(std::int64_t(f.mu.size())));
        if (f.T.rows() == 0 && f.T.cols() == 0 && m > 0)
            throw_input_error(where, "T", "missing: mu needs the two tangent rows per contact (T, 2m x n)");
        if (f.T.rows() != 2 * m || f.T.cols() != n)
            throw_input_error(where, "T",
                              "expected 2m x n = " + size_text(2 * m, n) + " (two tangent rows per contact), got " +
                                  size_text(f.T.rows(), f.T.cols()));
        if (f.cT.size() != 0 && f.cT.size() != 2 * m)
            throw_input_error(where, "cT",
                              "expected size 2m = " + str(2 * m) + ", got " + str(std::int64_t(f.cT.size())));
        check_finite(where, "mu", f.mu.data(), std::uint64_t(m));
        for (std::int64_t r = 0; r < m; ++r)
            if (f.mu[r] < 0)
                throw_input_error(where, "mu",
                                  "negative friction coefficient " + fmt_double(f.mu[r]) + " at contact " + str(r));
        for (Eigen::Index r = 0; r < f.T.outerSize(); ++r)
            for (SpMat::InnerIterator it(f.T, r); it; ++it)
                if (!std::isfinite(it.value()))
                    throw_input_error(where, "T.data",
                                      "non-finite value " + fmt_double(it.value()) + " in tangent row " +
                                          str(std::int64_t(r)));
        check_finite(where, "cT", f.cT.data(), std::uint64_t(f.cT.size()));
    }
    if (f.h != 0.0 && !(f.h > 0 && std::isfinite(f.h)))
        throw_input_error(where, "h", "expected a positive finite time step, got " + fmt_double(f.h));
    if (f.v0.size() != 0) {
        if (f.h == 0.0) throw_input_error(where, "h", "missing: v0 is given without the step h");
        if (f.v0.size() != n)
            throw_input_error(where, "v0", "expected size n = " + str(n) + ", got " + str(std::int64_t(f.v0.size())));
        check_finite(where, "v0", f.v0.data(), std::uint64_t(n));
    }
}

}  // namespace

void require_unknowns(const std::string& where, std::uint64_t n)
{
    // The solvers index x[0] and build factors of A: an empty problem is no problem to solve.
    if (n == 0) throw_input_error(where, "n", "no unknowns (n = 0): an empty problem has nothing to solve");
}

void validate_qp(const std::string& where, Qp& qp)
{
    const Eigen::Index n = qp.A.rows(), m = qp.J.rows();
    require_unknowns(where, std::uint64_t(std::max<Eigen::Index>(n, 0)));
    auto size_error = [&](const std::string& field, const std::string& what, Eigen::Index expected, Eigen::Index got) {
        throw_input_error(where, field,
                          "expected " + what + " = " + str(std::int64_t(expected)) + ", got " + str(std::int64_t(got)));
    };
    if (qp.A.cols() != n) size_error("A", "columns = n", n, qp.A.cols());
    if (qp.b.size() != n) size_error("b", "size n", n, qp.b.size());
    if (qp.x0.size() != n) size_error("x0", "size n", n, qp.x0.size());
    if (qp.J.cols() != n) size_error("J", "columns = n", n, qp.J.cols());
    if (qp.c.size() != m) size_error("c", "size m", m, qp.c.size());
    if (!qp.contacts.kind.empty() && Eigen::Index(qp.contacts.kind.size()) != m)
        size_error("contact.kind", "size m", m, Eigen::Index(qp.contacts.kind.size()));
    if (!qp.contacts.depth.empty() && Eigen::Index(qp.contacts.depth.size()) != m)
        size_error("contact.depth", "size m", m, Eigen::Index(qp.contacts.depth.size()));
    if (!qp.contacts.vertex.empty() && Eigen::Index(qp.contacts.vertex.size()) != 4 * m)
        size_error("contact.vertex", "size 4 m", 4 * m, Eigen::Index(qp.contacts.vertex.size()));
    qp.A.makeCompressed();
    qp.J.makeCompressed();
    qp.friction.T.makeCompressed();
    check_friction(where, qp);
    check_finite(where, "A.data", qp.A.valuePtr(), std::uint64_t(qp.A.nonZeros()));
    check_finite(where, "b", qp.b.data(), std::uint64_t(n));
    check_finite(where, "x0", qp.x0.data(), std::uint64_t(n));
    check_finite(where, "J.data", qp.J.valuePtr(), std::uint64_t(qp.J.nonZeros()));
    check_finite(where, "c", qp.c.data(), std::uint64_t(m));
    for (const SpMat* M : {&qp.A, &qp.J, &qp.friction.T})
        for (Eigen::Index r = 0; r < M->rows(); ++r)
            for (int e = M->outerIndexPtr()[r] + 1; e < M->outerIndexPtr()[r + 1]; ++e)
                if (M->innerIndexPtr()[e] <= M->innerIndexPtr()[e - 1])
                    throw_input_error(where,
                                      M == &qp.A   ? "A"
                                      : M == &qp.J ? "J"
                                                   : "T",
                                      "columns not strictly increasing in row " + str(std::int64_t(r)));
    symmetrise(where, qp.A);
    qp.a_symmetric = true;  // symmetrise made A equal A' to the bit (or refused it); rows sorted above
    check_diagonal(where, qp.A);
}

nlohmann::json read_qpsnap_header(const std::string& path)
{
    // Read the length field, then exactly the header; the checks are those of read_qpsnap.
    const FileBytes head = read_all(path, 8);
    if (head.size < 8) return parse_header(path, head.data.get(), head.size, nullptr);
    const std::uint64_t N = load_u64_le(head.data.get());
    if (N > head.file_size - 8) return parse_header(path, head.data.get(), head.file_size, nullptr);
    const FileBytes f = read_all(path, 8 + N);
    return parse_header(path, f.data.get(), f.size, nullptr);
}

namespace {

QpsnapPassObserver g_pass_observer = nullptr;

/// Tells the test hook (if any) that a pass over the arrays is done.
void pass_done(const char* pass, const PageRelease& pages, const unsigned char* bytes, std::uint64_t size)
{
    if (g_pass_observer && pages.releases()) g_pass_observer(pass, bytes, size);
}

Qp read_snapshot(const std::string& path, const unsigned char* bytes, std::uint64_t size, SnapshotExtras* extras,
                 const PageRelease& pages);

}  // namespace

void set_qpsnap_pass_observer(QpsnapPassObserver observer) { g_pass_observer = observer; }

Qp read_qpsnap(const std::string& path, SnapshotExtras* extras)
{
    const MappedFile f(path);
    return read_snapshot(path, f.data(), f.size(), extras, PageRelease(f.data(), f.size()));
}

Qp read_qpsnap_bytes(const std::string& path, const unsigned char* bytes, std::uint64_t size, SnapshotExtras* extras)
{
    return read_snapshot(path, bytes, size, extras, PageRelease());
}

namespace {

Qp read_snapshot(const std::string& path, const unsigned char* bytes, std::uint64_t size, SnapshotExtras* extras,
                 const PageRelease& pages)
{
    std::uint64_t N = 0;
    const nlohmann::json h = parse_header(path, bytes, size, &N);
    const std::uint64_t n = h["n"].get<std::uint64_t>(), m = h["m"].get<std::uint64_t>();
    const unsigned char* buffer = bytes + 8 + N;
    const std::uint64_t buffer_size = size - 8 - N;
    std::unique_ptr<std::uint64_t[]> aligned;  // a writer that did not pad its header: copy once
    if (reinterpret_cast<std::uintptr_t>(buffer) % 8 != 0) {
        aligned.reset(new std::uint64_t[buffer_size / 8 + 1]);
        std::memcpy(aligned.get(), buffer, buffer_size);
        buffer = reinterpret_cast<const unsigned char*>(aligned.get());
    }
    const nlohmann::json& arrays = h["arrays"];
    for (auto it = arrays.begin(); it != arrays.end(); ++it) {
        bool known = false;
        for (const auto& spec : ARRAYS) known = known || it.key() == spec.name;
        if (!known) throw_input_error(path, "arrays." + it.key(), "unknown array name");
        if (h["version"] == 1 && version2_array(it.key()))
            throw_input_error(path, "arrays." + it.key(), "a version 2 array in a version 1 snapshot");
    }
    std::map<std::string, Located> a;
    for (const auto& spec : ARRAYS) {
        if (!arrays.contains(spec.name)) {
            if (spec.required) throw_input_error(path, spec.name, "required array missing");
            a[spec.name] = Located{};
            continue;
        }
        a[spec.name] = locate(path, spec.name, spec.dtype, arrays[spec.name], buffer, buffer_size);
    }
    pass_done("checksums", pages, bytes, size);
    // Shapes.
    const std::string nn = "n = " + str(n), mm = "m = " + str(m);
    expect_shape(path, "A.indptr", a["A.indptr"], {n + 1}, nn + ", n + 1 entries");
    if (a["A.indices"].shape.size() != 1)
        expect_shape(path, "A.indices", a["A.indices"], {a["A.indices"].count}, "one dimension");
    const std::uint64_t nnz_a = a["A.indices"].count;
    if (nnz_a > MAX_INT32)
        throw_input_error(path, "A.indices", "nnz " + str(nnz_a) + " > 2147483647 (indices are 32-bit)");
    expect_shape(path, "A.data", a["A.data"], {nnz_a}, "the length of A.indices");
    expect_shape(path, "b", a["b"], {n}, nn);
    expect_shape(path, "x0", a["x0"], {n}, nn);
    expect_shape(path, "J.indptr", a["J.indptr"], {m + 1}, mm + ", m + 1 entries");
    if (a["J.indices"].shape.size() != 1)
        expect_shape(path, "J.indices", a["J.indices"], {a["J.indices"].count}, "one dimension");
    const std::uint64_t nnz_j = a["J.indices"].count;
    if (nnz_j > MAX_INT32)
        throw_input_error(path, "J.indices", "nnz " + str(nnz_j) + " > 2147483647 (indices are 32-bit)");
    expect_shape(path, "J.data", a["J.data"], {nnz_j}, "the length of J.indices");
    expect_shape(path, "c", a["c"], {m}, mm);
    if (a["contact.kind"].present) expect_shape(path, "contact.kind", a["contact.kind"], {m}, mm);
    if (a["contact.depth"].present) expect_shape(path, "contact.depth", a["contact.depth"], {m}, mm);
    if (a["contact.vertex"].present)
        expect_shape(path, "contact.vertex", a["contact.vertex"], {m, 4}, mm + ", 4 vertices per row");
    if (a["x_ref"].present) expect_shape(path, "x_ref", a["x_ref"], {n}, nn);
    if (a["lambda_ref"].present) expect_shape(path, "lambda_ref", a["lambda_ref"], {m}, mm);
    // Friction: mu and the three T arrays come together; cT needs T, v0 needs h.
    const bool has_t = a["T.indptr"].present || a["T.indices"].present || a["T.data"].present;
    if (has_t)
        for (const char* name : {"T.indptr", "T.indices", "T.data"})
            if (!a[name].present) throw_input_error(path, name, "missing (T is given as T.indptr, T.indices, T.data)");
    if (a["mu"].present && !has_t)
        throw_input_error(path, "T", "missing: mu needs the two tangent rows per contact (T, 2m x n)");
    if (has_t && !a["mu"].present) throw_input_error(path, "mu", "missing: T is given without friction coefficients");
    if (a["cT"].present && !has_t) throw_input_error(path, "cT", "given without the tangent rows T");
    if (a["v0"].present && !h.contains("h")) throw_input_error(path, "h", "missing: v0 is given without the step h");
    const std::uint64_t mt = 2 * m;
    if (a["mu"].present) expect_shape(path, "mu", a["mu"], {m}, mm + ", one per contact row");
    if (has_t) {
        expect_shape(path, "T.indptr", a["T.indptr"], {mt + 1}, mm + ", two tangent rows per contact, 2m + 1 entries");
        if (a["T.indices"].shape.size() != 1)
            expect_shape(path, "T.indices", a["T.indices"], {a["T.indices"].count}, "one dimension");
        if (a["T.indices"].count > MAX_INT32)
            throw_input_error(path, "T.indices",
                              "nnz " + str(a["T.indices"].count) + " > 2147483647 (indices are 32-bit)");
        expect_shape(path, "T.data", a["T.data"], {a["T.indices"].count}, "the length of T.indices");
    }
    if (a["cT"].present) expect_shape(path, "cT", a["cT"], {mt}, mm + ", two per contact");
    if (a["v0"].present) expect_shape(path, "v0", a["v0"], {n}, nn);
    // Structure and values.
    check_csr(path, "A", a["A.indptr"], a["A.indices"], n, n);
    check_csr(path, "J", a["J.indptr"], a["J.indices"], m, n);
    if (has_t) check_csr(path, "T", a["T.indptr"], a["T.indices"], mt, n);
    pass_done("structure", pages, bytes, size);
    for (const char* name :
         {"A.data", "b", "x0", "J.data", "c", "contact.depth", "x_ref", "lambda_ref", "mu", "T.data", "cT", "v0"})
        if (a[name].present) check_finite(path, name, a[name].f64(), a[name].count);
    pass_done("values", pages, bytes, size);
    if (a["mu"].present)
        for (std::uint64_t r = 0; r < m; ++r)
            if (a["mu"].f64()[r] < 0)
                throw_input_error(path, "mu",
                                  "negative friction coefficient " + fmt_double(a["mu"].f64()[r]) + " at contact " +
                                      str(r));
    if (a["contact.kind"].present)
        for (std::uint64_t r = 0; r < m; ++r) {
            const std::int64_t k = a["contact.kind"].i64()[r];
            if (k < 0 || k > std::int64_t(ContactKind::OTHER))
                throw_input_error(path, "contact.kind",
                                  "value " + str(k) + " at row " + str(r) + " is not a contact kind (0..4)");
        }
    if (a["contact.depth"].present)
        for (std::uint64_t r = 0; r < m; ++r)
            if (a["contact.depth"].f64()[r] < 0)
                throw_input_error(path, "contact.depth",
                                  "negative depth " + fmt_double(a["contact.depth"].f64()[r]) + " at row " + str(r));
    if (a["contact.vertex"].present)
        for (std::uint64_t e = 0; e < 4 * m; ++e) {
            const std::int64_t v = a["contact.vertex"].i64()[e];
            if (v < -1 || v > std::int64_t(MAX_INT32))
                throw_input_error(path, "contact.vertex",
                                  "value " + str(v) + " at row " + str(e / 4) + " is not a vertex id or -1");
        }

    Qp qp;
    build_csr(qp.A, n, n, a["A.indptr"], a["A.indices"], a["A.data"], pages);
    pass_done("A built", pages, bytes, size);
    symmetrise(path, qp.A);
    qp.a_symmetric = true;  // symmetrise made A equal A' to the bit (or refused it); rows sorted above
    check_diagonal(path, qp.A);
    build_csr(qp.J, m, n, a["J.indptr"], a["J.indices"], a["J.data"], pages);
    qp.b = Eigen::Map<const Vec>(a["b"].f64(), Eigen::Index(n));
    qp.x0 = Eigen::Map<const Vec>(a["x0"].f64(), Eigen::Index(n));
    qp.c = Eigen::Map<const Vec>(a["c"].f64(), Eigen::Index(m));
    if (a["contact.kind"].present) qp.contacts.kind.assign(a["contact.kind"].i64(), a["contact.kind"].i64() + m);
    if (a["contact.depth"].present) qp.contacts.depth.assign(a["contact.depth"].f64(), a["contact.depth"].f64() + m);
    if (a["contact.vertex"].present)
        qp.contacts.vertex.assign(a["contact.vertex"].i64(), a["contact.vertex"].i64() + 4 * m);
    qp.meta = h.contains("meta") ? h["meta"] : nlohmann::json::object();
    Friction& fr = qp.friction;
    if (a["mu"].present) {
        fr.mu = Eigen::Map<const Vec>(a["mu"].f64(), Eigen::Index(m));
        build_csr(fr.T, mt, n, a["T.indptr"], a["T.indices"], a["T.data"], pages);
    }
    if (a["cT"].present) fr.cT = Eigen::Map<const Vec>(a["cT"].f64(), Eigen::Index(mt));
    if (h.contains("h")) fr.h = h["h"].get<double>();
    if (a["v0"].present) fr.v0 = Eigen::Map<const Vec>(a["v0"].f64(), Eigen::Index(n));
    if (extras) {
        extras->x_ref = a["x_ref"].present ? Vec(Eigen::Map<const Vec>(a["x_ref"].f64(), Eigen::Index(n))) : Vec();
        extras->lambda_ref =
            a["lambda_ref"].present ? Vec(Eigen::Map<const Vec>(a["lambda_ref"].f64(), Eigen::Index(m))) : Vec();
    }
    return qp;
}

}  // namespace

namespace {

using ByteSink = std::function<void(const unsigned char*, size_t)>;

/// One array of the file, streamed from its source rather than copied: `emit` hands its bytes to a
/// sink in chunks, once for the checksum and once for the write. A 1M-DOF snapshot is 760 MB;
/// a copy of it doubled the writer's memory.
struct OutArray {
    std::string name, dtype;
    std::vector<std::uint64_t> shape;
    std::uint64_t nbytes = 0;
    std::function<void(const ByteSink&)> emit;
};

template <typename T, typename S>
OutArray out_array(const std::string& name, const char* dtype, std::vector<std::uint64_t> shape, const S* src,
                   size_t count)
{
    static_assert(sizeof(T) == 8, "qpsnap arrays hold 8-byte elements");
    OutArray o{name, dtype, std::move(shape), count * 8, {}};
    o.emit = [src, count](const ByteSink& sink) {
        // little-endian hosts only (x86-64, arm64): the file's bytes are the values' bytes
        if constexpr (std::is_same_v<T, S>) {
            if (count > 0) sink(reinterpret_cast<const unsigned char*>(src), count * 8);
        } else {
            constexpr size_t CHUNK_VALUES = size_t(1) << 16;  // values converted per chunk (512 KiB)
            std::vector<unsigned char> buf(std::min(count, CHUNK_VALUES) * 8);
            for (size_t first = 0; first < count; first += CHUNK_VALUES) {
                const size_t k = std::min(CHUNK_VALUES, count - first);
                for (size_t i = 0; i < k; ++i) {
                    const T v = T(src[first + i]);
                    std::memcpy(buf.data() + 8 * i, &v, 8);
                }
                sink(buf.data(), 8 * k);
            }
        }
    };
    return o;
}

/// `keep` holds a compressed copy of an uncompressed matrix for as long as its arrays are emitted.
void csr_arrays(std::vector<OutArray>& out, const std::string& prefix, const SpMat& M0,
                std::vector<std::unique_ptr<SpMat>>& keep)
{
    const SpMat* M = &M0;
    if (!M0.isCompressed()) {
        keep.push_back(std::make_unique<SpMat>(M0));
        keep.back()->makeCompressed();
        M = keep.back().get();
    }
    const size_t rows = size_t(M->rows()), nnz = size_t(M->nonZeros());
    out.push_back(out_array<std::int64_t>(prefix + ".indptr", "int64", {rows + 1}, M->outerIndexPtr(), rows + 1));
    out.push_back(out_array<std::int64_t>(prefix + ".indices", "int64", {nnz}, M->innerIndexPtr(), nnz));
    out.push_back(out_array<double>(prefix + ".data", "float64", {nnz}, M->valuePtr(), nnz));
}

}  // namespace

void write_qpsnap(const std::string& path, const Qp& qp, const SnapshotExtras* extras)
{
    const std::uint64_t n = std::uint64_t(qp.A.rows()), m = std::uint64_t(qp.J.rows());
    auto bad = [&](const std::string& field, const std::string& what) {
        throw_input_error(path + " (writing)", field, what);
    };
    if (qp.A.cols() != qp.A.rows()) bad("A", "not square");
    if (std::uint64_t(qp.b.size()) != n) bad("b", "size " + str(std::uint64_t(qp.b.size())) + " != n = " + str(n));
    if (std::uint64_t(qp.x0.size()) != n) bad("x0", "size " + str(std::uint64_t(qp.x0.size())) + " != n = " + str(n));
    if (std::uint64_t(qp.J.cols()) != n && !(m == 0 && qp.J.cols() == 0))
        bad("J", "has " + str(std::uint64_t(qp.J.cols())) + " columns, expected n = " + str(n));
    if (std::uint64_t(qp.c.size()) != m) bad("c", "size " + str(std::uint64_t(qp.c.size())) + " != m = " + str(m));
    const ContactRows& ct = qp.contacts;
    if (!ct.kind.empty() && ct.kind.size() != m) bad("contact.kind", "size != m");
    if (!ct.depth.empty() && ct.depth.size() != m) bad("contact.depth", "size != m");
    if (!ct.vertex.empty() && ct.vertex.size() != 4 * m) bad("contact.vertex", "size != 4 m");
    if (!qp.meta.is_object()) bad("meta", "must be a JSON object");
    check_friction(path + " (writing)", qp);
    const Friction& fr = qp.friction;

    std::vector<OutArray> arrays;
    std::vector<std::unique_ptr<SpMat>> compressed;
    const std::int64_t zero[1] = {0};
    csr_arrays(arrays, "A", qp.A, compressed);
    arrays.push_back(out_array<double>("b", "float64", {n}, qp.b.data(), n));
    arrays.push_back(out_array<double>("x0", "float64", {n}, qp.x0.data(), n));
    if (m == 0 && qp.J.cols() == 0) {
        arrays.push_back(out_array<std::int64_t>("J.indptr", "int64", {1}, zero, 1));
        arrays.push_back(out_array<std::int64_t>("J.indices", "int64", {0}, zero, 0));
        arrays.push_back(out_array<double>("J.data", "float64", {0}, qp.c.data(), 0));
    } else {
        csr_arrays(arrays, "J", qp.J, compressed);
    }
    arrays.push_back(out_array<double>("c", "float64", {m}, qp.c.data(), m));
    if (!ct.kind.empty()) arrays.push_back(out_array<std::int64_t>("contact.kind", "int64", {m}, ct.kind.data(), m));
    if (!ct.depth.empty()) arrays.push_back(out_array<double>("contact.depth", "float64", {m}, ct.depth.data(), m));
    if (!ct.vertex.empty())
        arrays.push_back(out_array<std::int64_t>("contact.vertex", "int64", {m, 4}, ct.vertex.data(), 4 * m));
    if (extras && extras->x_ref.size()) {
        if (std::uint64_t(extras->x_ref.size()) != n) bad("x_ref", "size != n");
        arrays.push_back(out_array<double>("x_ref", "float64", {n}, extras->x_ref.data(), n));
    }
    if (extras && extras->lambda_ref.size()) {
        if (std::uint64_t(extras->lambda_ref.size()) != m) bad("lambda_ref", "size != m");
        arrays.push_back(out_array<double>("lambda_ref", "float64", {m}, extras->lambda_ref.data(), m));
    }

    if (fr.mu.size()) {
        arrays.push_back(out_array<double>("mu", "float64", {m}, fr.mu.data(), m));
        csr_arrays(arrays, "T", fr.T, compressed);
    }
    if (fr.cT.size()) arrays.push_back(out_array<double>("cT", "float64", {2 * m}, fr.cT.data(), 2 * m));
    if (fr.v0.size()) arrays.push_back(out_array<double>("v0", "float64", {n}, fr.v0.data(), n));

    // Version 1 unless a friction field is present: a frictionless QP's file is byte for byte
    // what it was before version 2 (content hashes, reference caches and baselines keep).
    nlohmann::json header = {{"format", "qpsnap"}, {"version", fr.empty() ? 1 : 2}, {"n", n}, {"m", m}};
    if (fr.h > 0) header["h"] = fr.h;
    nlohmann::json entries = nlohmann::json::object();
    std::uint64_t offset = 0;
    for (const auto& a : arrays) {
        std::uint64_t crc = crc32_z(0L, Z_NULL, 0);
        a.emit([&](const unsigned char* p, size_t n) { crc = crc32_z(crc, p, n); });
        entries[a.name] = {
            {"dtype", a.dtype}, {"shape", a.shape}, {"offset", offset}, {"nbytes", a.nbytes}, {"crc32", crc}};
        offset += a.nbytes;  // multiples of 8: every array stays aligned
    }
    header["arrays"] = entries;
    header["meta"] = qp.meta;
    std::string text = header.dump();
    text.append((8 - text.size() % 8) % 8, ' ');  // so that the data buffer starts 8-byte aligned in the file
    unsigned char len[8];
    for (int i = 0; i < 8; ++i) len[i] = static_cast<unsigned char>((std::uint64_t(text.size()) >> (8 * i)) & 0xff);

    AtomicFile out(path);  // checked writes, fsync, rename: no partial snapshot on a full disk
    out.write(len, 8);
    out.write(text);
    for (const auto& a : arrays) a.emit([&](const unsigned char* p, size_t n) { out.write(p, n); });
    out.commit();
}

std::string qpsnap_content_hash(const std::string& path)
{
    FILE* in = ::fdopen(open_regular_file(path), "rb");
    if (!in) throw_input_error(path, "", std::string("cannot open: ") + std::strerror(errno));
    std::uint64_t h = 14695981039346656037ULL;  // FNV-1a 64 offset basis
    std::vector<unsigned char> buf(1 << 20);
    size_t got;
    while ((got = std::fread(buf.data(), 1, buf.size(), in)) > 0)
        for (size_t i = 0; i < got; ++i) {
            h ^= buf[i];
            h *= 1099511628211ULL;  // FNV prime
        }
    std::fclose(in);
    char hex[17];
    std::snprintf(hex, sizeof hex, "%016" PRIx64, h);
    return hex;
}

}  // namespace cb
