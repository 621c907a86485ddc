// Matrix Market reader and writer, and the snapshot folder built from them.
#include "problems/matrix_market.hpp"

#include "problems/io_util.hpp"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <unistd.h>

namespace cb {
namespace {

namespace fs = std::filesystem;

std::string lower(std::string s)
{
    for (auto& ch : s) ch = char(std::tolower(static_cast<unsigned char>(ch)));
    return s;
}

std::string line_field(long line) { return "line " + std::to_string(line); }

/// A parsed .mtx file: the banner, the size line and raw (0-based) entries.
struct MtxFile {
    std::string format, field, symmetry;
    long rows = 0, cols = 0;
    struct Entry {
        long r, c;
        double v;
        long line;
    };
    std::vector<Entry> entries;
};

/// Splits the file into lines lazily; keeps line numbers for messages.
class LineReader {
public:
    explicit LineReader(const std::string& path) : m_path(path)
    {
        m_text = read_regular_file(path, std::uint64_t(16) << 30);  // FIFO or folder: refused
    }
    /// Bytes not yet returned by next().
    size_t remaining() const { return m_pos >= m_text.size() ? 0 : m_text.size() - m_pos; }
    /// Next line (without the newline), false at the end.
    bool next(const char*& begin, const char*& end)
    {
        if (m_pos >= m_text.size()) return false;
        begin = m_text.data() + m_pos;
        const size_t nl = m_text.find('\n', m_pos);
        const size_t stop = nl == std::string::npos ? m_text.size() : nl;
        end = m_text.data() + stop;
        if (end > begin && end[-1] == '\r') --end;
        m_pos = stop + 1;
        ++m_line;
        return true;
    }
    long line() const { return m_line; }

private:
    std::string m_path, m_text;
    size_t m_pos = 0;
    long m_line = 0;
};

bool blank(const char* b, const char* e)
{
    for (; b < e; ++b)
        if (!std::isspace(static_cast<unsigned char>(*b))) return false;
    return true;
}

/// Parses whitespace-separated numbers from [b, e): up to `want` of them; returns the count.
int parse_numbers(const char* b, const char* e, double* out, int want, bool* extra)
{
    std::string s(b, e);  // strtod needs a terminator
    const char* p = s.c_str();
    int k = 0;
    while (true) {
        while (*p && std::isspace(static_cast<unsigned char>(*p))) ++p;
        if (!*p) break;
        if (k == want) {
            *extra = true;
            return k;
        }
        char* stop = nullptr;
        const double v = std::strtod(p, &stop);
        if (stop == p) return -1;
        if (*stop && !std::isspace(static_cast<unsigned char>(*stop))) return -1;
        out[k++] = v;
        p = stop;
    }
    *extra = false;
    return k;
}

/// Upper bounds on the declared size known from elsewhere (the other files of a folder).
struct MtxLimits {
    long max_rows = 2147483647L, max_cols = 2147483647L;
    std::string why_rows, why_cols;
    bool plus_entries = false;     ///< max_rows grows by the entries the file declares (rows of J)
    bool vector_size = false;      ///< a vector of exactly max_rows entries: the folder's "size" message
    bool diagonal_needed = false;  ///< every row needs a stored entry (A: SPD, diagonal present)
};

MtxFile parse_mtx(const std::string& path, const MtxLimits& limits = {})
{
    LineReader lines(path);
    const char *b = nullptr, *e = nullptr;
    if (!lines.next(b, e)) throw_input_error(path, "line 1", "empty file, expected a %%MatrixMarket banner");
    std::vector<std::string> words;
    {
        std::string banner(b, e), w;
        for (size_t i = 0; i <= banner.size(); ++i) {
            if (i == banner.size() || std::isspace(static_cast<unsigned char>(banner[i]))) {
                if (!w.empty()) words.push_back(lower(w));
                w.clear();
            } else {
                w += banner[i];
            }
        }
    }
    if (words.size() != 5 || words[0] != "%%matrixmarket" || words[1] != "matrix")
        throw_input_error(path, "line 1",
                          "expected '%%MatrixMarket matrix FORMAT FIELD SYMMETRY', got '" + std::string(b, e) + "'");
    MtxFile f;
    f.format = words[2], f.field = words[3], f.symmetry = words[4];
    if (f.format != "coordinate" && f.format != "array")
        throw_input_error(path, "line 1", "format '" + f.format + "' not supported (coordinate or array)");
    if (f.field != "real" && f.field != "integer" && f.field != "double")
        throw_input_error(path, "line 1", "field '" + f.field + "' not supported (real or integer)");
    if (f.symmetry != "general" && f.symmetry != "symmetric")
        throw_input_error(path, "line 1", "symmetry '" + f.symmetry + "' not supported (general or symmetric)");
    // Size line (after comments and blank lines).
    double size[3];
    bool extra = false;
    const int want = f.format == "coordinate" ? 3 : 2;
    while (true) {
        if (!lines.next(b, e)) throw_input_error(path, line_field(lines.line() + 1), "file ends before the size line");
        if (b < e && *b == '%') continue;
        if (blank(b, e)) continue;
        const int got = parse_numbers(b, e, size, want, &extra);
        const char* expect = want == 3 ? "'rows cols entries'" : "'rows cols'";
        if (got != want || extra)
            throw_input_error(path, line_field(lines.line()),
                              std::string("expected the size line ") + expect + ", got '" + std::string(b, e) + "'");
        for (int k = 0; k < want; ++k)
            if (size[k] < 0 || size[k] != std::floor(size[k]) || size[k] > 2147483647.0)
                throw_input_error(path, line_field(lines.line()),
                                  "sizes must be integers in [0, 2^31), got '" + std::string(b, e) + "'");
        break;
    }
    f.rows = long(size[0]);
    f.cols = long(size[1]);
    const bool symmetric = f.symmetry == "symmetric";
    if (symmetric && f.rows != f.cols)
        throw_input_error(path, "line 1",
                          "symmetric but not square (" + std::to_string(f.rows) + " x " + std::to_string(f.cols) + ")");
    long expected = 0;
    if (f.format == "coordinate")
        expected = long(size[2]);
    else
        expected = symmetric ? f.rows * (f.rows + 1) / 2 : f.rows * f.cols;
    // A vector bounded by the size wanted: its entries are distinct positions, so more than it
    // holds is an error known now, before the entries are read and stored.
    const long positions = symmetric ? f.rows * (f.rows + 1) / 2 : f.rows * f.cols;
    if (limits.vector_size && f.format == "coordinate" && expected > positions)
        throw_input_error(path, line_field(lines.line()),
                          "declares " + std::to_string(expected) + " entries, more than the " + std::to_string(f.rows) +
                              " x " + std::to_string(f.cols) + " matrix holds");
    if (limits.vector_size) {
        const long got = (f.cols == 1 || f.rows == 0) ? f.rows : f.cols;
        if (got > limits.max_rows) throw_input_error(path, "size", limits.why_rows + ", got " + std::to_string(got));
    }
    const long max_rows = limits.plus_entries ? std::min(2147483647L, limits.max_rows + expected) : limits.max_rows;
    if (f.rows > max_rows)
        throw_input_error(
            path, line_field(lines.line()),
            "declares " + std::to_string(f.rows) + " rows, at most " + std::to_string(max_rows) + " possible (" +
                limits.why_rows +
                (limits.plus_entries ? ", this file declares " + std::to_string(expected) + " entries" : "") + ")");
    if (f.cols > limits.max_cols)
        throw_input_error(path, line_field(lines.line()),
                          "declares " + std::to_string(f.cols) + " columns, at most " +
                              std::to_string(limits.max_cols) + " possible (" + limits.why_cols + ")");
    if (limits.diagonal_needed && f.format == "coordinate" && expected < f.rows)
        throw_input_error(path, line_field(lines.line()),
                          "declares " + std::to_string(f.rows) + " rows but only " + std::to_string(expected) +
                              " entries (every row needs its diagonal entry)");
    // Reserve for what the bytes present can hold, not for what the size line declares (an entry
    // takes at least 2 bytes, "v\n"; 6 in coordinate format): a 70-byte file declaring 2e8 entries
    // ends in "the file ends after ..." having allocated next to nothing.
    const size_t min_bytes = f.format == "coordinate" ? 6 : 2;
    f.entries.reserve(std::min(size_t(expected), lines.remaining() / min_bytes + 1));
    long count = 0, ai = 0, aj = 0;  // array format: column-major position
    while (count < expected) {
        if (!lines.next(b, e))
            throw_input_error(path, "entries",
                              "expected " + std::to_string(expected) + " entries, the file ends after " +
                                  std::to_string(count));
        if ((b < e && *b == '%') || blank(b, e)) continue;
        double v[3];
        if (f.format == "coordinate") {
            const int got = parse_numbers(b, e, v, 3, &extra);
            if (got != 3 || extra)
                throw_input_error(path, line_field(lines.line()),
                                  "expected 'row col value', got '" + std::string(b, e) + "'");
            if (v[0] != std::floor(v[0]) || v[1] != std::floor(v[1]) || v[0] < 1 || v[0] > double(f.rows) || v[1] < 1 ||
                v[1] > double(f.cols))
                throw_input_error(path, line_field(lines.line()),
                                  "entry (" + std::string(b, e) + ") outside [1, " + std::to_string(f.rows) +
                                      "] x [1, " + std::to_string(f.cols) + "]");
            f.entries.push_back({long(v[0]) - 1, long(v[1]) - 1, v[2], lines.line()});
        } else {
            const int got = parse_numbers(b, e, v, 1, &extra);
            if (got != 1 || extra)
                throw_input_error(path, line_field(lines.line()),
                                  "expected one value, got '" + std::string(b, e) + "'");
            f.entries.push_back({ai, aj, v[0], lines.line()});
            if (++ai == f.rows) ++aj, ai = symmetric ? aj : 0;
        }
        ++count;
    }
    while (lines.next(b, e))
        if (!blank(b, e) && *b != '%')
            throw_input_error(path, line_field(lines.line()),
                              "unexpected data after the " + std::to_string(expected) + " declared entries");
    if (symmetric) {
        const size_t stored = f.entries.size();
        for (size_t k = 0; k < stored; ++k) {
            const auto en = f.entries[k];
            if (en.r != en.c) f.entries.push_back({en.c, en.r, en.v, en.line});
        }
    }
    return f;
}

SpMat read_mtx_matrix_bounded(const std::string& path, const MtxLimits& limits);
Vec read_mtx_vector_bounded(const std::string& path, const MtxLimits& limits);

}  // namespace

SpMat read_mtx_matrix(const std::string& path) { return read_mtx_matrix_bounded(path, {}); }

namespace {

SpMat read_mtx_matrix_bounded(const std::string& path, const MtxLimits& limits)
{
    MtxFile f = parse_mtx(path, limits);
    if (f.format == "array") {  // dense: keep nonzeros and the diagonal
        std::vector<MtxFile::Entry> kept;
        for (const auto& e : f.entries)
            if (e.v != 0.0 || e.r == e.c) kept.push_back(e);
        f.entries.swap(kept);
    }
    std::sort(f.entries.begin(), f.entries.end(),
              [](const MtxFile::Entry& a, const MtxFile::Entry& b) { return a.r != b.r ? a.r < b.r : a.c < b.c; });
    for (size_t k = 1; k < f.entries.size(); ++k)
        if (f.entries[k].r == f.entries[k - 1].r && f.entries[k].c == f.entries[k - 1].c)
            throw_input_error(path, line_field(std::max(f.entries[k].line, f.entries[k - 1].line)),
                              "duplicate entry (" + std::to_string(f.entries[k].r + 1) + ", " +
                                  std::to_string(f.entries[k].c + 1) + ")");
    if (f.entries.size() > 2147483647ULL) throw_input_error(path, "entries", "more than 2^31 - 1 entries");
    SpMat M(f.rows, f.cols);
    M.resizeNonZeros(Eigen::Index(f.entries.size()));
    int* outer = M.outerIndexPtr();
    std::fill(outer, outer + f.rows + 1, 0);
    for (size_t k = 0; k < f.entries.size(); ++k) {
        ++outer[f.entries[k].r + 1];
        M.innerIndexPtr()[k] = int(f.entries[k].c);
        M.valuePtr()[k] = f.entries[k].v;
    }
    for (long r = 0; r < f.rows; ++r) outer[r + 1] += outer[r];
    return M;
}

}  // namespace

Vec read_mtx_vector(const std::string& path, long expected_size, const std::string& what)
{
    MtxLimits limits;
    if (expected_size >= 0) {
        // A coordinate vector may declare any size with no entries: bound it by the size wanted.
        limits.max_rows = limits.max_cols = std::max(expected_size, 1L);
        limits.why_rows = limits.why_cols = "expected " + std::to_string(expected_size) + " entries (" +
                                            (what.empty() ? std::string("size") : what) + " of the snapshot)";
        limits.vector_size = true;
    }
    return read_mtx_vector_bounded(path, limits);
}

namespace {

Vec read_mtx_vector_bounded(const std::string& path, const MtxLimits& limits)
{
    const MtxFile f = parse_mtx(path, limits);
    if (f.cols != 1 && f.rows != 1 && !(f.rows == 0 || f.cols == 0))
        throw_input_error(path, "line 1",
                          "expected a vector (k x 1 or 1 x k), got " + std::to_string(f.rows) + " x " +
                              std::to_string(f.cols));
    const bool column = f.cols == 1 || f.rows == 0;
    Vec v = Vec::Zero(column ? f.rows : f.cols);
    std::vector<char> seen(size_t(v.size()), 0);
    for (const auto& e : f.entries) {
        const long i = column ? e.r : e.c;
        if (seen[size_t(i)]) throw_input_error(path, line_field(e.line), "duplicate entry " + std::to_string(i + 1));
        seen[size_t(i)] = 1;
        v[i] = e.v;
    }
    return v;
}

}  // namespace

namespace {

/// printf into a growing string (the files are built in memory, then written atomically).
void append(std::string& out, const char* format, ...) __attribute__((format(printf, 2, 3)));
void append(std::string& out, const char* format, ...)
{
    char buffer[128];
    va_list args;
    va_start(args, format);
    const int len = std::vsnprintf(buffer, sizeof buffer, format, args);
    va_end(args);
    if (len > 0) out.append(buffer, size_t(std::min<int>(len, int(sizeof buffer) - 1)));
}

}  // namespace

void write_mtx_matrix(const std::string& path, const SpMat& M0, const std::string& comment)
{
    SpMat M = M0;
    M.makeCompressed();
    std::string text = "%%MatrixMarket matrix coordinate real general\n";
    if (!comment.empty()) text += "% " + comment + "\n";
    append(text, "%ld %ld %ld\n", long(M.rows()), long(M.cols()), long(M.nonZeros()));
    for (Eigen::Index r = 0; r < M.rows(); ++r)
        for (int e = M.outerIndexPtr()[r]; e < M.outerIndexPtr()[r + 1]; ++e)
            append(text, "%ld %d %.17g\n", long(r) + 1, M.innerIndexPtr()[e] + 1, M.valuePtr()[e]);
    write_file_atomic(path, text);
}

void write_mtx_vector(const std::string& path, const Vec& v, const std::string& comment)
{
    std::string text = "%%MatrixMarket matrix array real general\n";
    if (!comment.empty()) text += "% " + comment + "\n";
    append(text, "%ld 1\n", long(v.size()));
    for (Eigen::Index i = 0; i < v.size(); ++i) append(text, "%.17g\n", v[i]);
    write_file_atomic(path, text);
}

namespace {

nlohmann::json read_json_file(const std::string& path) { return read_json_checked(path); }

void read_contacts(const std::string& path, long m, ContactRows& ct)
{
    const nlohmann::json j = read_json_file(path);
    if (!j.is_object()) throw_input_error(path, "", "expected an object {kind, depth, vertex}");
    for (auto it = j.begin(); it != j.end(); ++it)
        if (it.key() != "kind" && it.key() != "depth" && it.key() != "vertex")
            throw_input_error(path, it.key(), "unknown key (known: kind, depth, vertex)");
    auto array_of_m = [&](const char* key) -> const nlohmann::json& {
        const auto& a = j[key];
        if (!a.is_array() || long(a.size()) != m)
            throw_input_error(path, key, "expected an array of m = " + std::to_string(m) + " entries");
        return a;
    };
    try {
        if (j.contains("kind"))
            for (const auto& k : array_of_m("kind")) {
                const std::int64_t v = k.get<std::int64_t>();
                if (!k.is_number_integer() || v < 0 || v > std::int64_t(ContactKind::OTHER))
                    throw_input_error(path, "kind", "expected integers 0..4, got " + k.dump());
                ct.kind.push_back(v);
            }
        if (j.contains("depth"))
            for (const auto& d : array_of_m("depth")) {
                if (!d.is_number() || !std::isfinite(d.get<double>()) || d.get<double>() < 0)
                    throw_input_error(path, "depth", "expected finite numbers >= 0, got " + d.dump());
                ct.depth.push_back(d.get<double>());
            }
        if (j.contains("vertex"))
            for (const auto& row : array_of_m("vertex")) {
                if (!row.is_array() || row.size() != 4)
                    throw_input_error(path, "vertex", "expected rows of 4 integers, got " + row.dump());
                for (const auto& v : row) {
                    if (!v.is_number_integer() || v.get<std::int64_t>() < -1)
                        throw_input_error(path, "vertex", "expected vertex ids >= -1, got " + v.dump());
                    ct.vertex.push_back(v.get<std::int64_t>());
                }
            }
    } catch (const nlohmann::json::type_error&) {
        throw_input_error(path, "", "expected numbers in kind, depth and vertex");
    }
}

}  // namespace

Qp read_matrix_market_folder(const std::string& dir, SnapshotExtras* extras)
{
    const fs::path d(dir);
    if (!fs::is_directory(d)) throw_input_error(dir, "", "not a folder (expected A.mtx b.mtx J.mtx c.mtx x0.mtx)");
    for (const char* name : {"A.mtx", "b.mtx", "J.mtx", "c.mtx", "x0.mtx"})
        if (!fs::exists(d / name)) throw_input_error(dir, name, "missing");
    Qp qp;
    MtxLimits a_limits;
    a_limits.diagonal_needed = true;
    qp.A = read_mtx_matrix_bounded((d / "A.mtx").string(), a_limits);
    const long n = long(qp.A.rows());
    if (qp.A.cols() != n)
        throw_input_error((d / "A.mtx").string(), "size",
                          "A must be square, got " + std::to_string(n) + " x " + std::to_string(long(qp.A.cols())));
    auto vector_of = [&](const char* name, long size, const char* what) {
        const std::string path = (d / name).string();
        MtxLimits limits;  // a vector longer than expected is refused before it is allocated
        limits.vector_size = true;
        limits.max_rows = limits.max_cols = std::max(size, 1L);
        limits.why_rows = limits.why_cols = std::string("expected ") + what + " = " + std::to_string(size) + " entries";
        Vec v = read_mtx_vector_bounded(path, limits);
        if (v.size() != size)
            throw_input_error(path, "size",
                              "expected " + std::string(what) + " = " + std::to_string(size) + " entries, got " +
                                  std::to_string(long(v.size())));
        return v;
    };
    qp.b = vector_of("b.mtx", n, "n (from A.mtx)");
    qp.x0 = vector_of("x0.mtx", n, "n (from A.mtx)");
    // A row of J holds an entry of J.mtx or a value of c.mtx (2 bytes at least; a row with neither is
    // the vacuous 0 >= 0): rows beyond that are refused before J's row index is allocated.
    MtxLimits j_limits;
    std::error_code size_ec;
    const auto c_bytes = fs::file_size(d / "c.mtx", size_ec);
    if (!size_ec) {
        j_limits.max_rows = long(std::min<std::uintmax_t>(c_bytes / 2, 2147483647u));
        j_limits.why_rows = "c.mtx holds " + std::to_string(c_bytes) + " bytes";
        j_limits.plus_entries = true;
    }
    qp.J = read_mtx_matrix_bounded((d / "J.mtx").string(), j_limits);
    if (qp.J.cols() != n)
        throw_input_error((d / "J.mtx").string(), "size",
                          "expected n = " + std::to_string(n) + " columns (from A.mtx), got " +
                              std::to_string(long(qp.J.cols())));
    const long m = long(qp.J.rows());
    qp.c = vector_of("c.mtx", m, "m (rows of J.mtx)");
    if (fs::exists(d / "meta.json")) {
        qp.meta = read_json_file((d / "meta.json").string());
        if (!qp.meta.is_object()) throw_input_error((d / "meta.json").string(), "", "expected a JSON object");
    }
    if (fs::exists(d / "contact.json")) read_contacts((d / "contact.json").string(), m, qp.contacts);
    // Coulomb friction (snapshot version 2's fields), each in a file of its own; validate_qp's
    // check_friction applies the snapshot's rules to them (mu with T, cT with T, v0 with h).
    if (fs::exists(d / "mu.mtx")) qp.friction.mu = vector_of("mu.mtx", m, "m (rows of J.mtx)");
    if (fs::exists(d / "T.mtx")) {
        MtxLimits t_limits;  // 2m x n: a larger declared size is refused before it is allocated
        t_limits.max_rows = std::max(2 * m, 1L);
        t_limits.max_cols = std::max(n, 1L);
        t_limits.why_rows = "2m = " + std::to_string(2 * m) + ", two tangent rows per row of J.mtx";
        t_limits.why_cols = "n = " + std::to_string(n) + ", from A.mtx";
        qp.friction.T = read_mtx_matrix_bounded((d / "T.mtx").string(), t_limits);
    }
    if (fs::exists(d / "cT.mtx")) qp.friction.cT = vector_of("cT.mtx", 2 * m, "2m (two tangents per row of J.mtx)");
    if (fs::exists(d / "h.mtx")) qp.friction.h = vector_of("h.mtx", 1, "1 (the time step h)")[0];
    if (fs::exists(d / "v0.mtx")) qp.friction.v0 = vector_of("v0.mtx", n, "n (from A.mtx)");
    SnapshotExtras ex;
    if (fs::exists(d / "x_ref.mtx")) ex.x_ref = vector_of("x_ref.mtx", n, "n (from A.mtx)");
    if (fs::exists(d / "lambda_ref.mtx")) ex.lambda_ref = vector_of("lambda_ref.mtx", m, "m (rows of J.mtx)");
    validate_qp(dir, qp);
    if (extras) *extras = ex;
    return qp;
}

void write_matrix_market_folder(const std::string& dir, const Qp& qp, const SnapshotExtras* extras)
{
    fs::path target(dir);
    while (!target.empty() && !target.has_filename()) target = target.parent_path();  // "out/" -> "out"
    if (fs::exists(target) && !(fs::is_directory(target) && fs::exists(target / "A.mtx")))
        throw_input_error(dir, "", "exists and is not a snapshot folder (no A.mtx); not replacing it");
    remove_stale_temporaries(target.string());  // DIR.tmp.<pid> of an interrupted earlier convert
    const fs::path tmp = target.string() + ".tmp." + std::to_string(::getpid());
    std::error_code ec;
    fs::remove_all(tmp, ec);
    if (!fs::create_directories(tmp, ec) || ec)
        throw_input_error(tmp.string(), "", "cannot create folder: " + ec.message());
    try {
        write_mtx_matrix((tmp / "A.mtx").string(), qp.A, "A: n x n SPD, both triangles (contactbench snapshot)");
        write_mtx_vector((tmp / "b.mtx").string(), qp.b, "b: minimize 1/2 x'Ax - b'x");
        write_mtx_vector((tmp / "x0.mtx").string(), qp.x0, "x0: start point");
        SpMat J = qp.J;
        if (J.cols() != qp.A.rows() && J.rows() == 0) J.resize(0, qp.A.rows());
        write_mtx_matrix((tmp / "J.mtx").string(), J, "J: subject to J x >= c");
        write_mtx_vector((tmp / "c.mtx").string(), qp.c, "c");
        write_file_atomic((tmp / "meta.json").string(), qp.meta.dump(2) + "\n");
        if (!qp.contacts.empty()) {
            nlohmann::json ct = nlohmann::json::object();
            if (!qp.contacts.kind.empty()) ct["kind"] = qp.contacts.kind;
            if (!qp.contacts.depth.empty())
                ct["depth"] = qp.contacts.depth;  // nlohmann prints doubles round-trip exact
            if (!qp.contacts.vertex.empty()) {
                nlohmann::json rows = nlohmann::json::array();
                for (size_t r = 0; 4 * r < qp.contacts.vertex.size(); ++r)
                    rows.push_back({qp.contacts.vertex[4 * r], qp.contacts.vertex[4 * r + 1],
                                    qp.contacts.vertex[4 * r + 2], qp.contacts.vertex[4 * r + 3]});
                ct["vertex"] = rows;
            }
            write_file_atomic((tmp / "contact.json").string(), ct.dump() + "\n");
        }
        const Friction& fr = qp.friction;
        if (fr.mu.size()) {
            write_mtx_vector((tmp / "mu.mtx").string(), fr.mu, "mu: Coulomb friction coefficient per row of J");
            write_mtx_matrix((tmp / "T.mtx").string(), fr.T,
                             "T: 2m x n, rows 2i and 2i+1 are the tangents of J's row i");
        }
        if (fr.cT.size()) write_mtx_vector((tmp / "cT.mtx").string(), fr.cT, "cT: slip T x - cT");
        if (fr.h > 0) write_mtx_vector((tmp / "h.mtx").string(), Vec::Constant(1, fr.h), "h: time step");
        if (fr.v0.size()) write_mtx_vector((tmp / "v0.mtx").string(), fr.v0, "v0: start velocities");
        if (extras && extras->x_ref.size()) write_mtx_vector((tmp / "x_ref.mtx").string(), extras->x_ref, "x_ref");
        if (extras && extras->lambda_ref.size())
            write_mtx_vector((tmp / "lambda_ref.mtx").string(), extras->lambda_ref, "lambda_ref");
    } catch (...) {
        fs::remove_all(tmp, ec);
        throw;
    }
    // Replace an older folder of ours in one step (no half-written DIR, no DIR.old.<pid> left).
    fsync_dir(tmp.string());
    replace_dir(tmp.string(), target.string());
}

}  // namespace cb
