// Solution readers: .npy, Matrix Market and plain-text vectors, and the solution folder. Each
// reader knows how many entries the file holds before it allocates, and refuses a count other
// than the one expected: memory is set by the snapshot's n, never by what a file declares.
#include "problems/solution_io.hpp"

#include "problems/io_util.hpp"
#include "problems/matrix_market.hpp"

#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <map>
#include <sys/stat.h>
#include <unistd.h>

namespace cb {

namespace {

namespace fs = std::filesystem;

std::string extension(const std::string& path)
{
    std::string ext = fs::path(path).extension().string();
    for (auto& ch : ext) ch = char(std::tolower(static_cast<unsigned char>(ch)));
    return ext;
}

/// Bytes of a file's text shown in a message: control bytes (a NUL among them) as \xNN.
std::string printable(const std::string& s, size_t max_chars = 40)
{
    std::string out;
    for (size_t i = 0; i < s.size() && i < max_chars; ++i) {
        const unsigned char ch = static_cast<unsigned char>(s[i]);
        if (ch < 0x20 || ch >= 0x7f) {
            char hex[8];
            std::snprintf(hex, sizeof hex, "\\x%02x", ch);
            out += hex;
        } else {
            out += char(ch);
        }
    }
    return out;
}

/// The snapshot's dimension a solution vector has: n for x, 2m for lambda_t, m for lambda.
const char* dimension_name(const std::string& field) { return field == "x" ? "n" : field == "lambda_t" ? "2m" : "m"; }

void require_count(long got, long expected, const std::string& path, const std::string& field)
{
    if (expected >= 0 && got != expected)
        throw_input_error(path, field,
                          "expected " + std::to_string(expected) + " entries (" + dimension_name(field) +
                              " of the snapshot), got " + std::to_string(got));
}

/// The dict of a .npy header ("{'descr': '<f8', 'fortran_order': False, 'shape': (3,), }"),
/// parsed as the Python literal it is: keys and values at the top level only, so that a key's
/// text inside another value is never taken for the key. Values are kept as written.
std::map<std::string, std::string> npy_header_dict(const std::string& header, const std::string& path)
{
    size_t i = 0;
    auto skip = [&] {
        while (i < header.size() && (header[i] == ' ' || header[i] == '\t' || header[i] == '\n')) ++i;
    };
    auto fail = [&](const std::string& what) -> void {
        throw_input_error(path, "header", what + " at byte " + std::to_string(i) + " of the .npy header");
    };
    auto quoted = [&]() -> std::string {  // 'text' or "text", no escapes (numpy writes none)
        const char q = header[i];
        const size_t end = header.find(q, i + 1);
        if (end == std::string::npos) fail("unterminated string");
        std::string s = header.substr(i + 1, end - i - 1);
        i = end + 1;
        return s;
    };
    std::map<std::string, std::string> dict;
    skip();
    if (i >= header.size() || header[i] != '{') fail("expected '{'");
    ++i;
    while (true) {
        skip();
        if (i < header.size() && header[i] == '}') break;
        if (i >= header.size() || (header[i] != '\'' && header[i] != '"')) fail("expected a quoted key or '}'");
        const std::string key = quoted();
        skip();
        if (i >= header.size() || header[i] != ':') fail("expected ':' after '" + printable(key) + "'");
        ++i;
        skip();
        std::string value;
        if (i < header.size() && (header[i] == '\'' || header[i] == '"')) {
            value = "'" + quoted() + "'";
        } else if (i < header.size() && header[i] == '(') {
            const size_t end = header.find(')', i);
            if (end == std::string::npos) fail("unterminated tuple");
            value = header.substr(i, end - i + 1);
            i = end + 1;
        } else {
            const size_t start = i;
            while (i < header.size() && std::isalnum(static_cast<unsigned char>(header[i]))) ++i;
            value = header.substr(start, i - start);
            if (value.empty()) fail("expected a value for '" + printable(key) + "'");
        }
        if (!dict.emplace(key, value).second) throw_input_error(path, key, "given twice in the .npy header");
        skip();
        if (i < header.size() && header[i] == ',') {
            ++i;
            continue;
        }
        skip();
        if (i >= header.size() || header[i] != '}') fail("expected ',' or '}'");
        break;
    }
    for (const auto& [key, value] : dict)
        if (key != "descr" && key != "fortran_order" && key != "shape")
            throw_input_error(path, printable(key), "unknown key in the .npy header (descr, fortran_order, shape)");
    for (const char* key : {"descr", "fortran_order", "shape"})
        if (!dict.count(key)) throw_input_error(path, "header", std::string("no '") + key + "' in the .npy header");
    return dict;
}

/// A numpy .npy file holding a float64 or float32 vector (shape (k,), (k, 1) or (1, k)).
Vec read_npy(const std::string& path, const std::string& field, long expected)
{
    const std::string bytes = read_regular_file(path);
    static const char magic[] = "\x93NUMPY";
    if (bytes.size() < 10 || std::memcmp(bytes.data(), magic, 6) != 0)
        throw_input_error(path, "header", "not a .npy file (no \\x93NUMPY magic)");
    const int major = static_cast<unsigned char>(bytes[6]);
    size_t header_len = 0, offset = 0;
    if (major == 1) {
        header_len = static_cast<unsigned char>(bytes[8]) | (size_t(static_cast<unsigned char>(bytes[9])) << 8);
        offset = 10;
    } else if (major == 2 || major == 3) {
        if (bytes.size() < 12) throw_input_error(path, "header", "file too short for a .npy header");
        for (int k = 0; k < 4; ++k) header_len |= size_t(static_cast<unsigned char>(bytes[8 + k])) << (8 * k);
        offset = 12;
    } else {
        throw_input_error(path, "header", "unknown .npy version " + std::to_string(major));
    }
    if (header_len > bytes.size() - offset)
        throw_input_error(path, "header", "header length " + std::to_string(header_len) + " exceeds the file");
    const auto dict = npy_header_dict(bytes.substr(offset, header_len), path);
    const std::string& descr = dict.at("descr");
    const std::string& fortran = dict.at("fortran_order");
    const std::string& shape = dict.at("shape");
    size_t item = 0;
    if (descr == "'<f8'" || descr == "'float64'")
        item = 8;
    else if (descr == "'<f4'")
        item = 4;
    else
        throw_input_error(path, field,
                          "dtype " + printable(descr) + " not supported; write float64 (numpy: x.astype(float))");
    if (fortran != "True" && fortran != "False")
        throw_input_error(path, "fortran_order", "expected True or False, got " + printable(fortran));
    // Shape: "(k,)", "(k, 1)" or "(1, k)"; at most one dimension other than 1.
    std::vector<std::uint64_t> dims;
    const char* p = shape.c_str();
    if (*p != '(') throw_input_error(path, "shape", "expected a tuple, got " + printable(shape));
    ++p;
    while (*p && *p != ')') {
        while (*p == ' ' || *p == ',') ++p;
        if (*p == ')') break;
        if (!std::isdigit(static_cast<unsigned char>(*p)))
            throw_input_error(path, "shape", "expected a tuple of sizes, got " + printable(shape));
        char* end = nullptr;
        errno = 0;
        const unsigned long long d = std::strtoull(p, &end, 10);
        if (errno == ERANGE) throw_input_error(path, "shape", "size out of range in " + printable(shape));
        dims.push_back(d);
        p = end;
    }
    int non_unit = 0;
    std::uint64_t count = 1;
    for (std::uint64_t d : dims) {
        if (d != 1) ++non_unit, count = d;
        if (d == 0) count = 0;
    }
    if (non_unit > 1 || dims.empty())
        throw_input_error(path, field, "expected a vector, got an array of shape " + printable(shape));
    // Compare in entries, not bytes: count * item could wrap.
    const size_t data_bytes = bytes.size() - offset - header_len;
    if (data_bytes % item != 0 || count != data_bytes / item)
        throw_input_error(path, field,
                          "shape " + printable(shape) + " declares " + std::to_string(count) +
                              " entries, the file holds " + std::to_string(data_bytes) + " bytes of data (" +
                              std::to_string(data_bytes / item) + " entries of " + std::to_string(item) + " bytes)");
    require_count(long(count), expected, path, field);
    const char* data = bytes.data() + offset + header_len;
    Vec v(static_cast<Eigen::Index>(count));
    for (std::uint64_t i = 0; i < count; ++i) {
        if (item == 8) {
            double d;
            std::memcpy(&d, data + i * 8, 8);
            v[Eigen::Index(i)] = d;
        } else {
            float f;
            std::memcpy(&f, data + i * 4, 4);
            v[Eigen::Index(i)] = f;
        }
    }
    return v;
}

/// Calls on_token(token, line) for every token of a plain-text vector, reading the file in
/// pieces: numbers separated by white space or commas, `#` comments to the end of a line.
template <class OnToken> void for_each_text_token(const std::string& path, const std::string& field, OnToken&& on_token)
{
    // A token longer than any number is refused rather than grown without bound.
    constexpr size_t MAX_TOKEN = 256;
    const int fd = open_regular_file(path);
    std::string token;
    long line = 1;
    bool comment = false;
    std::vector<char> buffer(size_t(1) << 20);
    auto flush = [&] {
        if (token.empty()) return;
        on_token(token, line);
        token.clear();
    };
    try {
        while (true) {
            const ssize_t got = ::read(fd, buffer.data(), buffer.size());
            if (got < 0 && errno == EINTR) continue;
            if (got < 0) throw_input_error(path, "", std::string("read failed: ") + std::strerror(errno));
            if (got == 0) break;
            for (ssize_t k = 0; k < got; ++k) {
                const char ch = buffer[size_t(k)];
                if (ch == '\n') {
                    flush();
                    comment = false;
                    ++line;
                } else if (comment) {
                } else if (ch == ' ' || ch == '\t' || ch == '\r' || ch == ',') {
                    flush();
                } else if (ch == '#') {
                    flush();
                    comment = true;
                } else {
                    if (token.size() == MAX_TOKEN)
                        throw_input_error(path, "line " + std::to_string(line),
                                          "expected a number of " + field + ", got '" + printable(token) +
                                              "...' (longer than " + std::to_string(MAX_TOKEN) + " characters)");
                    token += ch;
                }
            }
        }
        flush();
    } catch (...) {
        ::close(fd);
        throw;
    }
    ::close(fd);
}

/// Numbers separated by white space or commas; `#` comments to the end of a line. A first pass
/// counts the entries (nothing allocated), the second stores them.
Vec read_text_vector(const std::string& path, const std::string& field, long expected)
{
    long count = 0;
    for_each_text_token(path, field, [&](const std::string& token, long line) {
        char* end = nullptr;
        const double v = std::strtod(token.c_str(), &end);
        // A NUL inside the token stops strtod short of its end: refused like any other garbage.
        if (end != token.c_str() + token.size())
            throw_input_error(path, "line " + std::to_string(line),
                              "expected a number of " + field + ", got '" + printable(token) + "'");
        if (!std::isfinite(v))
            throw_input_error(path, field + "[" + std::to_string(count) + "]",
                              std::string("not finite (") + (std::isnan(v) ? "nan" : "inf") + ")");
        ++count;
    });
    require_count(count, expected, path, field);
    Vec v(count);
    long i = 0;
    for_each_text_token(path, field, [&](const std::string& token, long line) {
        if (i == count) throw_input_error(path, "line " + std::to_string(line), "the file grew while it was read");
        v[i++] = std::strtod(token.c_str(), nullptr);
    });
    if (i != count) throw_input_error(path, field, "the file shrank while it was read");
    return v;
}

/// What is at `path`: 'd' a folder, 'f' anything else that exists (the readers refuse FIFOs and
/// devices by name), or an InputError ("no such file", "cannot open: Too many levels of
/// symbolic links").
char path_kind(const std::string& path, const std::string& field, const char* missing)
{
    struct stat st {};
    if (::stat(path.c_str(), &st) != 0) {
        const int err = errno;
        if (err == ENOENT || err == ENOTDIR) throw_input_error(path, field, missing);
        throw_input_error(path, field, std::string("cannot open: ") + std::strerror(err));
    }
    return S_ISDIR(st.st_mode) ? 'd' : 'f';
}

Vec read_vector_file_sized(const std::string& path, const std::string& field, long expected)
{
    path_kind(path, field, "no such file");
    const std::string ext = extension(path);
    Vec v = ext == ".npy"   ? read_npy(path, field, expected)
            : ext == ".mtx" ? read_mtx_vector(path, expected, dimension_name(field))
                            : read_text_vector(path, field, expected);
    require_count(long(v.size()), expected, path, field);
    for (Eigen::Index i = 0; i < v.size(); ++i)
        if (!std::isfinite(v[i]))
            throw_input_error(path, field + "[" + std::to_string(i) + "]",
                              std::string("not finite (") + (std::isnan(v[i]) ? "nan" : "inf") + ")");
    return v;
}

}  // namespace

Vec read_vector_file(const std::string& path, const std::string& field, long expected)
{
    return read_vector_file_sized(path, field, expected);
}

std::string find_vector_file(const std::string& dir, const std::string& stem)
{
    std::string found;
    for (const char* ext : {".mtx", ".npy", ".txt"}) {
        const std::string candidate = (fs::path(dir) / (stem + ext)).string();
        // lstat: a dangling or looping link is present (and refused when read), not absent.
        struct stat st {};
        if (::lstat(candidate.c_str(), &st) != 0) continue;
        if (!found.empty())
            throw_input_error(
                dir, stem, "both " + fs::path(found).filename().string() + " and " + stem + ext + " present; keep one");
        found = candidate;
    }
    return found;
}

SolutionPoint read_solution(const std::string& path, long n, long m, const std::string& lambda_file,
                            const std::string& lambda_t_file, long tangent_rows)
{
    SolutionPoint point;
    if (path_kind(path, "x", "no such file or folder") == 'd') {
        point.x_path = find_vector_file(path, "x");
        if (point.x_path.empty()) throw_input_error(path, "x", "missing: the folder has no x.mtx, x.npy or x.txt");
        point.lambda_path = find_vector_file(path, "lambda");
        point.lambda_t_path = find_vector_file(path, "lambda_t");
    } else {
        point.x_path = path;
    }
    if (!lambda_file.empty()) point.lambda_path = lambda_file;
    if (!lambda_t_file.empty()) point.lambda_t_path = lambda_t_file;
    // Tangential multipliers answer tangent rows; without them they would be measured against nothing.
    if (!point.lambda_t_path.empty() && tangent_rows <= 0)
        throw_input_error(point.lambda_t_path, "lambda_t",
                          "given, but the snapshot has no friction (no tangent rows T): remove it, or judge the "
                          "frictional snapshot it answers");
    point.x = read_vector_file_sized(point.x_path, "x", n);
    if (!point.lambda_path.empty()) point.lambda = read_vector_file_sized(point.lambda_path, "lambda", m);
    if (!point.lambda_t_path.empty())
        point.lambda_t = read_vector_file_sized(point.lambda_t_path, "lambda_t", tangent_rows);
    return point;
}

}  // namespace cb
