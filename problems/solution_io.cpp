// Solution readers: .npy, Matrix Market and plain-text vectors, and the solution folder.
#include "problems/solution_io.hpp"

#include "problems/io_util.hpp"
#include "problems/matrix_market.hpp"

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>

namespace cb {

namespace {

namespace fs = std::filesystem;

std::string extension(const std::string& path)
{
    std::string ext = fs::path(path).extension().string();
    for (auto& ch : ext) ch = char(std::tolower(static_cast<unsigned char>(ch)));
    return ext;
}

/// The value of `key` in a numpy header dict ("{'descr': '<f8', 'fortran_order': False, 'shape': (3,), }"):
/// the text after "'key':" up to the next top-level comma or closing brace, trimmed.
std::string npy_header_value(const std::string& header, const std::string& key, const std::string& path)
{
    const std::string quoted = "'" + key + "'";
    size_t at = header.find(quoted);
    if (at == std::string::npos) throw_input_error(path, "header", "no '" + key + "' in the .npy header");
    at = header.find(':', at + quoted.size());
    if (at == std::string::npos) throw_input_error(path, "header", "no value for '" + key + "'");
    size_t end = at + 1;
    int depth = 0;
    for (; end < header.size(); ++end) {
        const char ch = header[end];
        if (ch == '(') ++depth;
        if (ch == ')') --depth;
        if (depth == 0 && (ch == ',' || ch == '}')) break;
    }
    std::string value = header.substr(at + 1, end - at - 1);
    const auto first = value.find_first_not_of(" \t");
    const auto last = value.find_last_not_of(" \t");
    return first == std::string::npos ? "" : value.substr(first, last - first + 1);
}

/// A numpy .npy file holding a float64 or float32 vector (shape (k,), (k, 1) or (1, k)).
Vec read_npy(const std::string& path, const std::string& field)
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
    const std::string header = bytes.substr(offset, header_len);
    const std::string descr = npy_header_value(header, "descr", path);
    const std::string fortran = npy_header_value(header, "fortran_order", path);
    const std::string shape = npy_header_value(header, "shape", path);
    size_t item = 0;
    if (descr == "'<f8'" || descr == "'float64'")
        item = 8;
    else if (descr == "'<f4'")
        item = 4;
    else
        throw_input_error(path, field, "dtype " + descr + " not supported; write float64 (numpy: x.astype(float))");
    (void)fortran;  // a vector reads the same in either order
    // Shape: "(k,)", "(k, 1)" or "(1, k)"; at most one dimension other than 1.
    std::vector<long> dims;
    const char* p = shape.c_str();
    if (*p != '(') throw_input_error(path, "shape", "expected a tuple, got " + shape);
    ++p;
    while (*p && *p != ')') {
        while (*p == ' ' || *p == ',') ++p;
        if (*p == ')') break;
        char* end = nullptr;
        const long d = std::strtol(p, &end, 10);
        if (end == p || d < 0) throw_input_error(path, "shape", "expected a tuple of sizes, got " + shape);
        dims.push_back(d);
        p = end;
    }
    long count = 1;
    int non_unit = 0;
    for (long d : dims) {
        count *= d;
        if (d != 1) ++non_unit;
    }
    if (non_unit > 1 || dims.empty())
        throw_input_error(path, field, "expected a vector, got an array of shape " + shape);
    const size_t data = offset + header_len;
    if (bytes.size() - data != size_t(count) * item)
        throw_input_error(path, field,
                          "shape " + shape + " needs " + std::to_string(size_t(count) * item) + " bytes of data, got " +
                              std::to_string(bytes.size() - data));
    Vec v(count);
    for (long i = 0; i < count; ++i) {
        if (item == 8) {
            double d;
            std::memcpy(&d, bytes.data() + data + size_t(i) * 8, 8);
            v[i] = d;
        } else {
            float f;
            std::memcpy(&f, bytes.data() + data + size_t(i) * 4, 4);
            v[i] = f;
        }
    }
    return v;
}

/// Numbers separated by white space or commas; `#` comments to the end of a line.
Vec read_text_vector(const std::string& path, const std::string& field)
{
    const std::string text = read_regular_file(path);
    std::vector<double> values;
    long line = 1;
    size_t i = 0;
    while (i < text.size()) {
        const char ch = text[i];
        if (ch == '\n') {
            ++line;
            ++i;
        } else if (ch == ' ' || ch == '\t' || ch == '\r' || ch == ',') {
            ++i;
        } else if (ch == '#') {
            while (i < text.size() && text[i] != '\n') ++i;
        } else {
            size_t j = i;
            while (j < text.size() && !std::strchr(" \t\r\n,#", text[j])) ++j;
            const std::string token = text.substr(i, j - i);
            char* end = nullptr;
            const double v = std::strtod(token.c_str(), &end);
            if (end != token.c_str() + token.size())
                throw_input_error(path, "line " + std::to_string(line),
                                  "expected a number of " + field + ", got '" + token.substr(0, 40) + "'");
            values.push_back(v);
            i = j;
        }
    }
    return Eigen::Map<const Vec>(values.data(), Eigen::Index(values.size()));
}

void require_size(const Vec& v, long expected, const std::string& path, const std::string& field, const char* what)
{
    if (v.size() != expected)
        throw_input_error(path, field,
                          "expected " + std::to_string(expected) + " entries (" + what + " of the snapshot), got " +
                              std::to_string(v.size()));
}

}  // namespace

Vec read_vector_file(const std::string& path, const std::string& field)
{
    if (!fs::exists(path)) throw_input_error(path, field, "no such file");
    const std::string ext = extension(path);
    Vec v = ext == ".npy"   ? read_npy(path, field)
            : ext == ".mtx" ? read_mtx_vector(path)
                            : read_text_vector(path, field);
    for (Eigen::Index i = 0; i < v.size(); ++i)
        if (!std::isfinite(v[i]))
            throw_input_error(path, field + "[" + std::to_string(i) + "]",
                              std::string("not finite (") + (std::isnan(v[i]) ? "nan" : "inf") + ")");
    return v;
}

std::string find_vector_file(const std::string& dir, const std::string& stem)
{
    std::string found;
    for (const char* ext : {".mtx", ".npy", ".txt"}) {
        const std::string candidate = (fs::path(dir) / (stem + ext)).string();
        if (!fs::exists(candidate)) continue;
        if (!found.empty())
            throw_input_error(
                dir, stem, "both " + fs::path(found).filename().string() + " and " + stem + ext + " present; keep one");
        found = candidate;
    }
    return found;
}

SolutionPoint read_solution(const std::string& path, long n, long m, const std::string& lambda_file)
{
    SolutionPoint point;
    if (!fs::exists(path)) throw_input_error(path, "x", "no such file or folder");
    if (fs::is_directory(path)) {
        point.x_path = find_vector_file(path, "x");
        if (point.x_path.empty()) throw_input_error(path, "x", "missing: the folder has no x.mtx, x.npy or x.txt");
        point.lambda_path = find_vector_file(path, "lambda");
    } else {
        point.x_path = path;
    }
    if (!lambda_file.empty()) point.lambda_path = lambda_file;
    point.x = read_vector_file(point.x_path, "x");
    require_size(point.x, n, point.x_path, "x", "n");
    if (!point.lambda_path.empty()) {
        point.lambda = read_vector_file(point.lambda_path, "lambda");
        require_size(point.lambda, m, point.lambda_path, "lambda", "m");
    }
    return point;
}

}  // namespace cb
