// FCLIB export/import of the contact QP (mappings and their justification in fclib_io.hpp).
#include "problems/fclib_io.hpp"

#include "problems/io_util.hpp"
#include "problems/safe_output.hpp"

#include <filesystem>

#ifdef CB_HAVE_FCLIB
extern "C" {
#include <fclib.h>
}
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <hdf5.h>
#include <unistd.h>
#include <vector>
#endif

namespace cb {

bool is_fclib_path(const std::string& path)
{
    const std::string ext = std::filesystem::path(path).extension().string();
    return ext == ".hdf5" || ext == ".h5";
}

#ifndef CB_HAVE_FCLIB

std::string fclib_version() { return ""; }

void write_fclib_global(const std::string& path, const Qp&, const SnapshotExtras*)
{
    throw InputError(path + ": FCLIB export is not built (install libfclib-dev and reconfigure with CB_PEERS=ON)");
}

Qp read_fclib(const std::string& path, SnapshotExtras*, const FclibReadOptions&)
{
    throw InputError(path + ": FCLIB import is not built (install libfclib-dev and reconfigure with CB_PEERS=ON)");
}

Qp read_fclib_global(const std::string& path, SnapshotExtras* extras, const FclibReadOptions& options)
{
    return read_fclib(path, extras, options);
}

FrictionLocal read_fclib_local_friction(const std::string& path)
{
    read_fclib(path);
    return {};
}

FrictionGlobal read_fclib_global_friction(const std::string& path)
{
    read_fclib(path);
    return {};
}

std::string read_fclib_friction(const std::string& path, FrictionLocal&, FrictionGlobal&)
{
    read_fclib(path);
    return "";
}

std::string fclib_kind(const std::string&) { return ""; }

nlohmann::json describe_fclib(const std::string& path)
{
    read_fclib(path);
    return {};
}

#else

std::string fclib_version() { return CB_FCLIB_VERSION; }

namespace {

/// An fclib_matrix viewing arrays owned elsewhere (fclib only reads them when writing).
struct MatrixView {
    fclib_matrix m{};
    std::vector<int> p, i;
    std::vector<double> x;
    void point()
    {
        m.p = p.data();
        m.i = i.data();
        m.x = x.data();
        m.nzmax = static_cast<int>(x.size());
        m.info = nullptr;
    }
};

/// A as compressed rows (nz = -2), its CSR arrays unchanged.
MatrixView csr_view(const SpMat& A)
{
    MatrixView v;
    v.p.assign(A.outerIndexPtr(), A.outerIndexPtr() + A.outerSize() + 1);
    v.i.assign(A.innerIndexPtr(), A.innerIndexPtr() + A.nonZeros());
    v.x.assign(A.valuePtr(), A.valuePtr() + A.nonZeros());
    v.m.m = static_cast<int>(A.rows());
    v.m.n = static_cast<int>(A.cols());
    v.m.nz = -2;
    v.point();
    return v;
}

/// H (n x 3m) as compressed columns (nz = -1): column 3i is row i of J, columns 3i+1 and 3i+2 are
/// T's rows 2i and 2i+1 (a row-major matrix's rows are its transpose's columns).
MatrixView h_view(const SpMat& J, const SpMat& T)
{
    const Eigen::Index m = J.rows();
    MatrixView v;
    v.p.push_back(0);
    auto append_row = [&](const SpMat& S, Eigen::Index row) {
        for (SpMat::InnerIterator it(S, row); it; ++it) {
            v.i.push_back(static_cast<int>(it.col()));
            v.x.push_back(it.value());
        }
        v.p.push_back(static_cast<int>(v.x.size()));
    };
    for (Eigen::Index r = 0; r < m; ++r) {
        append_row(J, r);
        append_row(T, 2 * r);
        append_row(T, 2 * r + 1);
    }
    v.m.m = static_cast<int>(J.cols());
    v.m.n = static_cast<int>(3 * m);
    v.m.nz = -1;
    v.point();
    return v;
}

/// H (n x 3m) as compressed columns (nz = -1): column 3i is row i of J (J's CSR arrays are J''s
/// CSC arrays), columns 3i+1 and 3i+2 are empty.
MatrixView h_view(const SpMat& J)
{
    MatrixView v;
    const Eigen::Index m = J.rows();
    v.p.resize(static_cast<size_t>(3 * m + 1));
    for (Eigen::Index r = 0; r < m; ++r) {
        v.p[static_cast<size_t>(3 * r)] = J.outerIndexPtr()[r];
        v.p[static_cast<size_t>(3 * r + 1)] = J.outerIndexPtr()[r + 1];
        v.p[static_cast<size_t>(3 * r + 2)] = J.outerIndexPtr()[r + 1];
    }
    v.p[static_cast<size_t>(3 * m)] = static_cast<int>(J.nonZeros());
    v.i.assign(J.innerIndexPtr(), J.innerIndexPtr() + J.nonZeros());
    v.x.assign(J.valuePtr(), J.valuePtr() + J.nonZeros());
    v.m.m = static_cast<int>(J.cols());
    v.m.n = static_cast<int>(3 * m);
    v.m.nz = -1;
    v.point();
    return v;
}

/// An HDF5 identifier closed by its own close function when it goes out of scope.
class H5Handle {
public:
    H5Handle(hid_t id, herr_t (*close)(hid_t)) : m_id(id), m_close(close) {}
    ~H5Handle()
    {
        if (m_id >= 0) m_close(m_id);
    }
    H5Handle(const H5Handle&) = delete;
    H5Handle& operator=(const H5Handle&) = delete;
    hid_t id() const { return m_id; }

private:
    hid_t m_id;
    herr_t (*m_close)(hid_t);
};

std::string exact(double value)
{
    char text[32];
    std::snprintf(text, sizeof(text), "%.17g", value);
    return text;
}

/// Reads the FCLIB layout (fclib.h; the groups and datasets libfclib writes) with plain HDF5
/// calls, so that no malformed file reaches libfclib's readers, which allocate from declared
/// sizes, read whatever length the dataset has, and exit(1) on any HDF5 error. Every dataset's
/// class, rank, length and stored bytes are checked before its buffer is allocated: a length
/// must be one the layout declares, and the bytes must be in the file (so memory is bounded by
/// the file's size: no fill values, no compressed data, no external storage). Only hard links
/// are followed: an external link would open another file (a FIFO blocks), a soft link can loop.
class FclibReader {
public:
    explicit FclibReader(std::string path) : m_path(std::move(path))
    {
        ::close(open_regular_file(m_path));           // a FIFO, a folder or a device: refused without blocking
        H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);  // errors are reported here, naming the field
        if (H5Fis_hdf5(m_path.c_str()) <= 0) fail("file", "not an HDF5 file");
        m_file = H5Fopen(m_path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
        if (m_file < 0) fail("file", "HDF5 cannot open it");
    }
    ~FclibReader() { H5Fclose(m_file); }
    FclibReader(const FclibReader&) = delete;
    FclibReader& operator=(const FclibReader&) = delete;

    const std::string& path() const { return m_path; }

    [[noreturn]] void fail(const std::string& field, const std::string& problem) const
    {
        throw InputError(m_path + ": " + field + ": " + problem);
    }

    /// True when every link of `name` ("/a/b/c") exists; each must be a hard link (H5Lexists
    /// needs the parents to exist, and resolving a child would traverse an external parent).
    bool exists(const std::string& name) const
    {
        for (size_t slash = name.find('/', 1);; slash = name.find('/', slash + 1)) {
            const std::string prefix = name.substr(0, slash);
            if (H5Lexists(m_file, prefix.c_str(), H5P_DEFAULT) <= 0) return false;
            H5L_info_t info{};
            if (H5Lget_info(m_file, prefix.c_str(), &info, H5P_DEFAULT) < 0) return false;
            if (info.type == H5L_TYPE_EXTERNAL)
                fail(prefix, "is an external link to another file (not followed: the file must hold its own data)");
            if (info.type != H5L_TYPE_HARD)
                fail(prefix, "is a soft or user-defined link (only hard links are followed)");
            if (slash == std::string::npos) return true;
        }
    }

    /// One integer (a dataset of one element).
    long long integer(const std::string& name)
    {
        const std::vector<long long> v = integers(name, {1}, "one value");
        return v[0];
    }

    /// An integer array whose length is one of `allowed` (the first is named in errors when the
    /// others are equal to it); `declared` says who declares the length.
    std::vector<long long> integers(const std::string& name, const std::vector<long long>& allowed,
                                    const std::string& declared)
    {
        std::vector<long long> values;
        read(name, H5T_INTEGER, allowed, declared, H5T_NATIVE_LLONG, values);
        return values;
    }

    /// A real array as above; non-finite values are refused naming the entry when `finite`.
    std::vector<double> reals(const std::string& name, const std::vector<long long>& allowed,
                              const std::string& declared, bool finite = true)
    {
        std::vector<double> values;
        read(name, H5T_FLOAT, allowed, declared, H5T_NATIVE_DOUBLE, values);
        if (finite)
            for (size_t k = 0; k < values.size(); ++k)
                if (!std::isfinite(values[k]))
                    fail(name, "entry " + std::to_string(k) + " is " + exact(values[k]) + " (values must be finite)");
        return values;
    }

    /// A fixed-length string (as H5LTmake_dataset_string writes), at most 16 MiB.
    std::string text(const std::string& name)
    {
        const H5Handle data(open_dataset(name), H5Dclose);
        const H5Handle type(H5Dget_type(data.id()), H5Tclose);
        if (H5Tget_class(type.id()) != H5T_STRING || H5Tis_variable_str(type.id()) != 0)
            fail(name, "expected a fixed-length string");
        const size_t size = H5Tget_size(type.id());
        if (size == 0 || size > (size_t(16) << 20)) fail(name, "string of " + std::to_string(size) + " bytes");
        if (points(name, data.id()) != 1) fail(name, "expected one string");
        check_stored(name, data.id(), size);
        std::string buffer(size, '\0');
        if (H5Dread(data.id(), type.id(), H5S_ALL, H5S_ALL, H5P_DEFAULT, &buffer[0]) < 0)
            fail(name, "HDF5 cannot read it");
        return buffer.substr(0, buffer.find('\0'));
    }

private:
    hid_t open_dataset(const std::string& name) const
    {
        if (!exists(name)) fail(name, "missing");
        const hid_t data = H5Dopen2(m_file, name.c_str(), H5P_DEFAULT);
        if (data < 0) fail(name, "not a dataset");
        // External storage reads another file (any local file, /dev/zero, a FIFO) when the data
        // are read; a virtual dataset maps other files too. Checked before anything is read.
        const H5Handle create(H5Dget_create_plist(data), H5Pclose);
        if (create.id() < 0 || H5Pget_external_count(create.id()) != 0) {
            H5Dclose(data);
            fail(name, "stored in an external file (external storage is not read: the file must hold its own data)");
        }
        if (H5Pget_layout(create.id()) == H5D_VIRTUAL) {
            H5Dclose(data);
            fail(name, "a virtual dataset mapping other files (not read: the file must hold its own data)");
        }
        return data;
    }

    /// Elements of a scalar or 1-D dataset (a null dataspace has none).
    long long points(const std::string& name, hid_t data) const
    {
        const H5Handle space(H5Dget_space(data), H5Sclose);
        const H5S_class_t kind = H5Sget_simple_extent_type(space.id());
        if (kind == H5S_NULL) return 0;
        if (kind == H5S_SCALAR) return 1;
        const int rank = H5Sget_simple_extent_ndims(space.id());
        if (kind != H5S_SIMPLE || rank != 1)
            fail(name, "expected a 1-D array, found " + std::to_string(rank) + " dimensions");
        hsize_t extent = 0;
        H5Sget_simple_extent_dims(space.id(), &extent, nullptr);
        return static_cast<long long>(std::min<hsize_t>(extent, hsize_t(1) << 62));
    }

    /// The dataset's bytes must be in the file: a declared extent with nothing stored (fill
    /// values) or a compressed one could make a small file allocate gigabytes.
    void check_stored(const std::string& name, hid_t data, size_t bytes) const
    {
        const hsize_t stored = H5Dget_storage_size(data);
        if (stored < bytes)
            fail(name, "declares " + std::to_string(bytes) + " bytes but stores " + std::to_string(stored) +
                           " (compressed or unwritten data are not read)");
    }

    template <typename T>
    void read(const std::string& name, H5T_class_t kind, const std::vector<long long>& allowed,
              const std::string& declared, hid_t memory_type, std::vector<T>& out)
    {
        const H5Handle data(open_dataset(name), H5Dclose);
        const H5Handle type(H5Dget_type(data.id()), H5Tclose);
        if (H5Tget_class(type.id()) != kind)
            fail(name, kind == H5T_INTEGER ? "expected integers" : "expected floating-point numbers");
        const long long count = points(name, data.id());
        if (std::find(allowed.begin(), allowed.end(), count) == allowed.end())
            fail(name,
                 "holds " + std::to_string(count) + " values, " + declared + " declares " + std::to_string(allowed[0]));
        check_stored(name, data.id(), size_t(count) * H5Tget_size(type.id()));
        out.resize(size_t(count));
        // HDF5 converts integers that do not fit (a uint64 beyond LLONG_MAX) by clamping: the
        // range checks below then name them.
        if (count > 0 && H5Dread(data.id(), memory_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, out.data()) < 0)
            fail(name, "HDF5 cannot read it");
    }

    std::string m_path;
    hid_t m_file = -1;
};

/// Largest size or count accepted (our sparse matrices index with int).
constexpr long long MAX_INDEX = 2147483646;

/// A sparse matrix of the FCLIB layout (group with nzmax, m, n, nz, p, i, x).
struct SparseSizes {
    long long nzmax = 0, m = 0, n = 0, nz = 0;
};

/// The declared sizes of the matrix in `group`, each in range.
SparseSizes read_sizes(FclibReader& file, const std::string& group)
{
    SparseSizes s;
    s.nzmax = file.integer(group + "/nzmax");
    s.m = file.integer(group + "/m");
    s.n = file.integer(group + "/n");
    s.nz = file.integer(group + "/nz");
    for (const auto& [name, value] : {std::pair<const char*, long long>{"nzmax", s.nzmax}, {"m", s.m}, {"n", s.n}})
        if (value < 0 || value > MAX_INDEX)
            file.fail(group + "/" + name,
                      "must be in 0.." + std::to_string(MAX_INDEX) + ", got " + std::to_string(value));
    if (s.nz < -2)
        file.fail(group + "/nz", "must be >= 0 (triplets), -1 (CSC) or -2 (CSR), got " + std::to_string(s.nz));
    if (s.nz > s.nzmax)
        file.fail(group + "/nz", std::to_string(s.nz) + " triplets, but nzmax is " + std::to_string(s.nzmax));
    return s;
}

/// The matrix of `group` (sizes checked by read_sizes) as a row-major Eigen matrix; values bit
/// for bit, duplicates summed (as CSparse's cs_compress does).
SpMat read_matrix(FclibReader& file, const std::string& group, const SparseSizes& s)
{
    const std::string nzmax = group + "/nzmax";
    std::vector<Triplet> t;
    auto index = [&](const char* field, long long k, long long value, long long bound, const char* what) {
        if (value < 0 || value >= bound)
            file.fail(group + "/" + field, "entry " + std::to_string(k) + " is " + std::to_string(value) +
                                               ", outside 0.." + std::to_string(bound - 1) + " (" + what + ")");
        return static_cast<int>(value);
    };
    if (s.nz >= 0) {
        // Triplets in CSparse's convention, which real writers follow (fclib.h's comment says the
        // opposite): p holds column indices, i row indices; libfclib writes x with nzmax values.
        const std::string declared = group + "/nz";
        const std::vector<long long> p = file.integers(group + "/p", {s.nz, s.nzmax}, declared);
        const std::vector<long long> i = file.integers(group + "/i", {s.nz, s.nzmax}, declared);
        const std::vector<double> x = file.reals(group + "/x", {s.nz, s.nzmax}, declared);
        t.reserve(size_t(s.nz));
        for (long long k = 0; k < s.nz; ++k)
            t.emplace_back(index("i", k, i[size_t(k)], s.m, "row indices"),
                           index("p", k, p[size_t(k)], s.n, "column indices"), x[size_t(k)]);
    } else {  // -1: compressed columns (p over the n columns), -2: compressed rows
        const bool columns = s.nz == -1;
        const long long outer = columns ? s.n : s.m, inner = columns ? s.m : s.n;
        const std::vector<long long> p =
            file.integers(group + "/p", {outer + 1}, (columns ? group + "/n" : group + "/m") + " + 1 (CSC/CSR)");
        for (long long o = 0; o <= outer; ++o)
            if (p[size_t(o)] < (o == 0 ? 0 : p[size_t(o - 1)]) || p[size_t(o)] > s.nzmax)
                file.fail(group + "/p", "entry " + std::to_string(o) + " is " + std::to_string(p[size_t(o)]) +
                                            ": pointers must be non-decreasing within 0..nzmax (" +
                                            std::to_string(s.nzmax) + ")");
        // i and x hold nzmax values (libfclib) or just the p[outer] used ones (other writers).
        const long long used = p[size_t(outer)];
        const std::vector<long long> i = file.integers(group + "/i", {s.nzmax, used}, nzmax);
        const std::vector<double> x = file.reals(group + "/x", {s.nzmax, used}, nzmax);
        t.reserve(size_t(used - p[0]));
        for (long long o = 0; o < outer; ++o)
            for (long long k = p[size_t(o)]; k < p[size_t(o + 1)]; ++k) {
                const int in = index("i", k, i[size_t(k)], inner, columns ? "row indices" : "column indices");
                if (columns)
                    t.emplace_back(in, static_cast<int>(o), x[size_t(k)]);
                else
                    t.emplace_back(static_cast<int>(o), in, x[size_t(k)]);
            }
    }
    SpMat out(static_cast<Eigen::Index>(s.m), static_cast<Eigen::Index>(s.n));
    out.setFromTriplets(t.begin(), t.end());
    out.makeCompressed();
    return out;
}

/// A symmetric matrix as the file means it: stored as one triangle (every off-diagonal entry
/// above the diagonal, or every one below) it is mirrored; otherwise it must be symmetric to
/// rounding (1e-12 max|a_ij|, validate_qp's test), or, with `symmetrise`, it is averaged with its
/// transpose. `note` records what was done (the snapshot's provenance).
SpMat symmetric_matrix(FclibReader& file, const std::string& field, const std::string& what, SpMat M, bool symmetrise,
                       nlohmann::json& note)
{
    long long upper = 0, lower = 0;
    double max_abs = 0.0;
    for (Eigen::Index r = 0; r < M.outerSize(); ++r)
        for (SpMat::InnerIterator it(M, r); it; ++it) {
            if (it.value() == 0.0) continue;
            max_abs = std::max(max_abs, std::abs(it.value()));
            if (it.col() > r) ++upper;
            if (it.col() < r) ++lower;
        }
    if ((upper == 0) != (lower == 0)) {
        std::vector<Triplet> both;
        for (Eigen::Index r = 0; r < M.outerSize(); ++r)
            for (SpMat::InnerIterator it(M, r); it; ++it) {
                both.emplace_back(static_cast<int>(r), static_cast<int>(it.col()), it.value());
                if (it.col() != r) both.emplace_back(static_cast<int>(it.col()), static_cast<int>(r), it.value());
            }
        SpMat mirrored(M.rows(), M.cols());
        mirrored.setFromTriplets(both.begin(), both.end());
        mirrored.makeCompressed();
        note[field] = std::string("stored as its ") + (upper ? "upper" : "lower") + " triangle: mirrored";
        return mirrored;
    }
    const SpMat At = M.transpose();
    const SpMat diff = M - At;
    double worst = 0.0;
    Eigen::Index wi = 0, wj = 0;
    for (Eigen::Index r = 0; r < diff.outerSize(); ++r)
        for (SpMat::InnerIterator it(diff, r); it; ++it)
            if (std::abs(it.value()) > worst) {
                worst = std::abs(it.value());
                wi = r;
                wj = it.col();
            }
    const double tol = 1e-12 * max_abs;
    if (worst <= tol) return M;
    const std::string pair = "(" + std::to_string(wi) + ", " + std::to_string(wj) + ") = " + exact(M.coeff(wi, wj)) +
                             " but (" + std::to_string(wj) + ", " + std::to_string(wi) +
                             ") = " + exact(M.coeff(wj, wi));
    if (!symmetrise)
        file.fail(field, what + " is not symmetric: " + pair + " (difference " + exact(worst) +
                             " > 1e-12 max|entry| = " + exact(tol) +
                             "; one triangle alone is mirrored; `convert --symmetrise` takes (A + A')/2)");
    SpMat averaged = 0.5 * M + 0.5 * At;
    averaged.makeCompressed();
    note[field] = {{"symmetrised", "(A + A')/2"},
                   {"max_asymmetry", worst},
                   {"relative_asymmetry", worst / max_abs},
                   {"worst_entry", pair}};
    return averaged;
}

/// mu of every contact: finite and >= 0; nonzero ones refused unless friction is dropped.
/// Returns {min, max} of mu.
std::pair<double, double> check_mu(FclibReader& file, const std::string& field, const std::vector<double>& mu,
                                   bool drop_friction, const std::string& kind)
{
    double lo = 0.0, hi = 0.0;
    for (size_t i = 0; i < mu.size(); ++i) {
        const std::string contact = "contact " + std::to_string(i);
        if (!(mu[i] >= 0.0) || !std::isfinite(mu[i]))  // NaN too
            file.fail(field, contact + " has mu = " + exact(mu[i]) + " (a friction coefficient is finite and >= 0)");
        if (mu[i] != 0.0 && !drop_friction) {
            std::string message = contact;
            message += " has mu = " + exact(mu[i]);
            message += ": this " + kind;
            message += kind == "fclib_local"
                           ? " problem has friction, which a snapshot cannot hold (it has no A); `convert "
                             "--drop-friction` keeps its normal part (recorded in the snapshot), `friction-solve` "
                             "solves a 3-D one with its friction"
                           : " problem has friction: read it with keep_friction (as `convert` does: a snapshot of "
                             "version 2) or drop_friction (its normal part)";
            file.fail(field, message);
        }
        lo = i == 0 ? mu[i] : std::min(lo, mu[i]);
        hi = std::max(hi, mu[i]);
    }
    return {lo, hi};
}

long long spacedim_of(FclibReader& file, const std::string& field)
{
    const long long d = file.integer(field);
    if (d != 2 && d != 3) file.fail(field, "must be 2 or 3, got " + std::to_string(d));
    return d;
}

/// The title and description of a foreign file, kept in the provenance (bounded, printable).
void describe_source(FclibReader& file, const std::string& root, nlohmann::json& provenance)
{
    for (const char* key : {"title", "description"}) {
        const std::string name = root + "/info/" + key;
        if (!file.exists(name)) continue;
        try {
            std::string value = file.text(name);
            if (value.size() > 1000) value = value.substr(0, 1000) + "...";
            for (char& ch : value)
                if (static_cast<unsigned char>(ch) < 32 || static_cast<unsigned char>(ch) > 126) ch = ' ';
            provenance[key] = value;
        } catch (const InputError&) {
        }
    }
}

/// The first initial guess's `vector` (v for global, r for local) of `length`, or empty.
std::vector<double> first_guess(FclibReader& file, const char* vector, long long length, const std::string& declared)
{
    if (!file.exists("/guesses")) return {};
    const long long guesses = file.integer("/guesses/number_of_guesses");
    if (guesses < 0) file.fail("/guesses/number_of_guesses", "must be >= 0, got " + std::to_string(guesses));
    if (guesses == 0 || length == 0) return {};
    return file.reals(std::string("/guesses/1/") + vector, {length}, declared);
}

Qp read_global(FclibReader& file, SnapshotExtras* extras, const FclibReadOptions& options)
{
    const std::string G = "/fclib_global";
    const long long d = spacedim_of(file, G + "/spacedim");
    if (file.exists(G + "/G")) {
        const long long g = file.integer(G + "/G/n");
        if (g != 0) file.fail(G + "/G", "equality constraints are not supported (" + std::to_string(g) + " columns)");
    }

    // Every declared size first, checked against each other and against the vectors' lengths
    // (whose bytes are in the file), before any matrix array is allocated.
    const SparseSizes ms = read_sizes(file, G + "/M"), hs = read_sizes(file, G + "/H");
    const long long n = ms.m;
    if (ms.n != n) file.fail(G + "/M", "not square: m = " + std::to_string(ms.m) + ", n = " + std::to_string(ms.n));
    if (n == 0) file.fail(G + "/M/n", "the problem has no unknowns (n = 0)");
    if (hs.m != n) file.fail(G + "/H/m", std::to_string(hs.m) + " rows, but M has " + std::to_string(n));
    if (hs.n % d != 0)
        file.fail(G + "/H/n", std::to_string(hs.n) + " columns: not " + std::to_string(d) + " per contact (spacedim " +
                                  std::to_string(d) + ")");
    const long long m = hs.n / d;
    const std::vector<double> f = file.reals(G + "/vectors/f", {n}, G + "/M/m");
    const std::vector<double> w = file.reals(G + "/vectors/w", {d * m}, G + "/H/n");
    const std::vector<double> mu = file.reals(G + "/vectors/mu", {m}, G + "/H/n / spacedim", false);
    const bool keep = options.keep_friction && !options.drop_friction;
    const auto [mu_min, mu_max] = check_mu(file, G + "/vectors/mu", mu, options.drop_friction || keep, "fclib_global");
    const bool friction = keep && mu_max > 0.0;
    if (friction && d != 3)
        file.fail(G + "/spacedim", "is 2: a frictional snapshot holds two tangents per contact (3-D); "
                                   "`convert --drop-friction` keeps the normal part");
    const bool exact_map = mu_max == 0.0;

    nlohmann::json notes = nlohmann::json::object();
    Qp qp;
    qp.A = symmetric_matrix(file, G + "/M", "M", read_matrix(file, G + "/M", ms), options.symmetrise, notes);
    const SpMat H = read_matrix(file, G + "/H", hs);
    qp.b = Eigen::Map<const Vec>(f.data(), Eigen::Index(n));
    // J's row i is H's normal column d i; the tangential columns carry r_T, which is 0 (mu = 0) or
    // dropped with the friction.
    const SpMat Ht = H.transpose();
    std::vector<Triplet> jt;
    qp.c.resize(Eigen::Index(m));
    for (Eigen::Index i = 0; i < m; ++i) {
        qp.c[i] = -w[size_t(d * i)];
        for (SpMat::InnerIterator it(Ht, d * i); it; ++it) jt.emplace_back(static_cast<int>(i), it.col(), it.value());
    }
    qp.J.resize(Eigen::Index(m), Eigen::Index(n));
    qp.J.setFromTriplets(jt.begin(), jt.end());
    qp.J.makeCompressed();
    if (friction) {
        // T's rows 2i, 2i+1 are H's tangent columns 3i+1, 3i+2; u_T = H_T' v + w_T = T x - cT.
        std::vector<Triplet> tt;
        qp.friction.cT.resize(2 * Eigen::Index(m));
        for (Eigen::Index i = 0; i < m; ++i)
            for (int k = 1; k <= 2; ++k) {
                const Eigen::Index row = 2 * i + k - 1;
                qp.friction.cT[row] = -w[size_t(3 * i + k)];
                for (SpMat::InnerIterator it(Ht, 3 * i + k); it; ++it)
                    tt.emplace_back(static_cast<int>(row), it.col(), it.value());
            }
        qp.friction.T.resize(2 * Eigen::Index(m), Eigen::Index(n));
        qp.friction.T.setFromTriplets(tt.begin(), tt.end());
        qp.friction.T.makeCompressed();
        qp.friction.mu = Eigen::Map<const Vec>(mu.data(), Eigen::Index(m));
    }

    const std::vector<double> v0 = first_guess(file, "v", n, G + "/M/n");
    qp.x0 = v0.empty() ? Vec(Vec::Zero(Eigen::Index(n))) : Vec(Eigen::Map<const Vec>(v0.data(), Eigen::Index(n)));

    // Our own export stores the QP's metadata as JSON in the description; other writers free text.
    bool ours = false;
    if (file.exists(G + "/info/description")) {
        try {
            const nlohmann::json meta = parse_json_text(file.text(G + "/info/description"), file.path());
            if (meta.is_object()) {
                qp.meta = meta;
                ours = true;
            }
        } catch (const InputError&) {
        }
    }
    if (!ours || !exact_map || !notes.empty()) {
        nlohmann::json provenance = {{"format", "fclib_global"},
                                     {"file", std::filesystem::path(file.path()).filename().string()},
                                     {"spacedim", d},
                                     {"contacts", m},
                                     {"mapping", "A = M, b = f, J = H_N' (the normal columns of H), c = -w_N"}};
        if (friction)
            provenance["friction"] = {
                {"mu_min", mu_min},
                {"mu_max", mu_max},
                {"mapping", "mu kept, T = H_T' (rows 2i, 2i+1 = H's columns 3i+1, 3i+2), cT = -w_T"},
                {"solution", "not kept (no tangential multipliers in a snapshot's reference)"}};
        else if (!exact_map)
            provenance["dropped_friction"] = {
                {"mu_min", mu_min},
                {"mu_max", mu_max},
                {"kept", "the normal rows of H: a frictionless problem, not the file's frictional one"}};
        if (!notes.empty()) provenance["matrices"] = notes;
        if (!ours) describe_source(file, G, provenance);
        qp.meta["provenance"] = provenance;
    }
    if (extras) {
        *extras = SnapshotExtras{};
        // A frictional file's solution solves another problem than the QP: not a reference.
        if (exact_map && file.exists("/solution")) {
            const std::vector<double> v = file.reals("/solution/v", {n}, G + "/M/n");
            const std::vector<double> r = file.reals("/solution/r", {d * m}, G + "/H/n");
            extras->x_ref = Eigen::Map<const Vec>(v.data(), Eigen::Index(n));
            extras->lambda_ref.resize(Eigen::Index(m));
            for (Eigen::Index i = 0; i < m; ++i) extras->lambda_ref[i] = r[size_t(d * i)];
        }
    }
    return qp;
}

Qp read_local(FclibReader& file, SnapshotExtras* extras, const FclibReadOptions& options)
{
    const std::string L = "/fclib_local";
    const long long d = spacedim_of(file, L + "/spacedim");
    for (const char* mixed : {"/V", "/R"})
        if (file.exists(L + mixed)) {
            const long long cols = file.integer(L + mixed + "/n");
            if (cols != 0)
                file.fail(L + mixed, "equality constraints (a mixed problem) are not supported (" +
                                         std::to_string(cols) + " columns)");
        }
    const SparseSizes ws = read_sizes(file, L + "/W");
    if (ws.m != ws.n) file.fail(L + "/W", "not square: m = " + std::to_string(ws.m) + ", n = " + std::to_string(ws.n));
    if (ws.m == 0) file.fail(L + "/W/n", "the problem has no contacts (n = 0)");
    if (ws.m % d != 0)
        file.fail(L + "/W/n", std::to_string(ws.m) + " rows: not " + std::to_string(d) + " per contact (spacedim " +
                                  std::to_string(d) + ")");
    const long long m = ws.m / d;
    const std::vector<double> q = file.reals(L + "/vectors/q", {ws.m}, L + "/W/m");
    const std::vector<double> mu = file.reals(L + "/vectors/mu", {m}, L + "/W/m / spacedim", false);
    const auto [mu_min, mu_max] = check_mu(file, L + "/vectors/mu", mu, options.drop_friction, "fclib_local");
    const bool exact_map = mu_max == 0.0;

    // The normal block: rows and columns d i of W.
    const SpMat W = read_matrix(file, L + "/W", ws);
    std::vector<Triplet> nt;
    for (Eigen::Index r = 0; r < W.outerSize(); r += d)
        for (SpMat::InnerIterator it(W, r); it; ++it)
            if (it.col() % d == 0) nt.emplace_back(static_cast<int>(r / d), static_cast<int>(it.col() / d), it.value());
    SpMat WNN(static_cast<Eigen::Index>(m), static_cast<Eigen::Index>(m));
    WNN.setFromTriplets(nt.begin(), nt.end());
    WNN.makeCompressed();

    nlohmann::json notes = nlohmann::json::object();
    Qp qp;
    qp.A =
        symmetric_matrix(file, L + "/W", "the normal block W_NN (indexed by contact)", WNN, options.symmetrise, notes);
    qp.b.resize(Eigen::Index(m));
    for (Eigen::Index i = 0; i < m; ++i) qp.b[i] = -q[size_t(d * i)];
    qp.J.resize(Eigen::Index(m), Eigen::Index(m));
    qp.J.setIdentity();
    qp.J.makeCompressed();
    qp.c = Vec::Zero(Eigen::Index(m));
    const std::vector<double> r0 = first_guess(file, "r", ws.m, L + "/W/m");
    qp.x0 = Vec::Zero(Eigen::Index(m));
    for (Eigen::Index i = 0; i < Eigen::Index(r0.size() / size_t(d)); ++i) qp.x0[i] = r0[size_t(d * i)];

    nlohmann::json provenance = {{"format", "fclib_local"},
                                 {"file", std::filesystem::path(file.path()).filename().string()},
                                 {"spacedim", d},
                                 {"contacts", m},
                                 {"mapping", "A = W_NN, b = -q_N, J = I, c = 0 (x = r_N, lambda = u_N)"}};
    if (!exact_map)
        provenance["dropped_friction"] = {
            {"mu_min", mu_min},
            {"mu_max", mu_max},
            {"kept", "the normal block W_NN: a frictionless problem, not the file's frictional one"}};
    if (!notes.empty()) provenance["matrices"] = notes;
    describe_source(file, L, provenance);
    qp.meta = nlohmann::json::object();
    qp.meta["provenance"] = provenance;
    if (extras) {
        *extras = SnapshotExtras{};
        if (exact_map && file.exists("/solution")) {
            const std::vector<double> r = file.reals("/solution/r", {ws.m}, L + "/W/m");
            const std::vector<double> u = file.reals("/solution/u", {ws.m}, L + "/W/m");
            extras->x_ref.resize(Eigen::Index(m));
            extras->lambda_ref.resize(Eigen::Index(m));
            for (Eigen::Index i = 0; i < m; ++i) {
                extras->x_ref[i] = r[size_t(d * i)];
                extras->lambda_ref[i] = u[size_t(d * i)];
            }
        }
    }
    return qp;
}

/// Which problem the file holds; both groups present is ambiguous and refused.
std::string kind_of(FclibReader& file)
{
    const bool global = file.exists("/fclib_global"), local = file.exists("/fclib_local");
    if (global && local)
        file.fail("/fclib_global", "the file holds both an fclib_global and an fclib_local problem (ambiguous)");
    return global ? "fclib_global" : local ? "fclib_local" : "";
}

}  // namespace

void write_fclib_global(const std::string& path, const Qp& qp, const SnapshotExtras* extras)
{
    const Eigen::Index n = qp.n(), m = qp.m();
    // libfclib exits the process (assert) when it writes a start point or solution without contacts.
    if (m == 0)
        throw InputError(path +
                         ": J: the QP has no constraints (m = 0); FCLIB stores no problem without contacts (write "
                         "a .qpsnap or a Matrix Market folder instead)");
    if (3 * m > MAX_INDEX || qp.A.nonZeros() > MAX_INDEX || qp.J.nonZeros() > MAX_INDEX)
        throw InputError(path + ": the QP is too large for FCLIB's int sizes");
    const Friction& fr = qp.friction;
    const bool friction = fr.mu.size() == m && m > 0 && fr.T.rows() == 2 * m;
    MatrixView M = csr_view(qp.A), H = friction ? h_view(qp.J, fr.T) : h_view(qp.J);
    Vec f = qp.b;
    Vec w = Vec::Zero(3 * m), mu = friction ? Vec(fr.mu) : Vec(Vec::Zero(m));
    for (Eigen::Index i = 0; i < m; ++i) {
        w[3 * i] = -qp.c[i];
        if (friction && fr.cT.size() == 2 * m) {
            w[3 * i + 1] = -fr.cT[2 * i];
            w[3 * i + 2] = -fr.cT[2 * i + 1];
        }
    }

    std::string title = "contactbench QP", description = qp.meta.dump(),
                math_info = friction ? "Coulomb friction: A x - b = J'lambda + T'lambda_T, contact i = (J_i; T_2i; "
                                       "T_2i+1) x - (c_i; cT_2i; cT_2i+1)"
                                     : "frictionless (mu = 0): minimize 1/2 x'Ax - b'x subject to Jx >= c";
    fclib_info info{title.data(), description.data(), math_info.data()};
    fclib_global problem{};
    problem.M = &M.m;
    problem.H = &H.m;
    problem.G = nullptr;
    problem.mu = mu.data();
    problem.f = f.data();
    problem.b = nullptr;
    problem.w = w.data();
    problem.spacedim = 3;
    problem.info = &info;

    // A FIFO or device target is refused (HDF5 seeks); PATH.tmp.<pid> is removed on every error.
    AtomicFile out(path, SpecialTarget::REFUSE);
    const std::string tmp = out.hand_over_temporary();
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
    {
        // libfclib adds its groups to an existing HDF5 file: start from an empty one.
        const H5Handle created(H5Fcreate(tmp.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT), H5Fclose);
        if (created.id() < 0) throw InputError(path + ": HDF5 cannot create " + tmp);
    }
    if (!fclib_write_global(&problem, tmp.c_str())) throw InputError(path + ": libfclib could not write the problem");

    // x0 as the first guess: v = x0, r = 0, u = H'x0 + w.
    Vec x0 = qp.x0, r0 = Vec::Zero(3 * m), u0 = Vec::Zero(3 * m);
    const Vec jx0 = qp.J * qp.x0;
    for (Eigen::Index i = 0; i < m; ++i) u0[3 * i] = jx0[i] - qp.c[i];
    if (friction) {
        const Vec tx0 = fr.T * qp.x0;
        for (Eigen::Index i = 0; i < m; ++i) {
            u0[3 * i + 1] = tx0[2 * i] + w[3 * i + 1];
            u0[3 * i + 2] = tx0[2 * i + 1] + w[3 * i + 2];
        }
    }
    fclib_solution guess{x0.data(), u0.data(), r0.data(), nullptr};
    if (!fclib_write_guesses(1, &guess, tmp.c_str()))
        throw InputError(path + ": libfclib could not write the start point");

    // A snapshot's reference has no tangential multipliers: a frictional problem's is not written.
    if (!friction && extras && extras->x_ref.size() == n && extras->lambda_ref.size() == m) {
        Vec v = extras->x_ref, r = Vec::Zero(3 * m), u = Vec::Zero(3 * m);
        const Vec jx = qp.J * extras->x_ref;
        for (Eigen::Index i = 0; i < m; ++i) {
            r[3 * i] = extras->lambda_ref[i];
            u[3 * i] = jx[i] - qp.c[i];
        }
        fclib_solution solution{v.data(), u.data(), r.data(), nullptr};
        if (!fclib_write_solution(&solution, tmp.c_str()))
            throw InputError(path + ": libfclib could not write the solution");
    }
    out.commit();
}

Qp read_fclib(const std::string& path, SnapshotExtras* extras, const FclibReadOptions& options)
{
    FclibReader file(path);
    const std::string kind = kind_of(file);
    if (kind.empty())
        file.fail("/fclib_global",
                  "missing: an HDF5 file without an FCLIB problem (neither /fclib_global nor /fclib_local)");
    Qp qp = kind == "fclib_global" ? read_global(file, extras, options) : read_local(file, extras, options);
    validate_qp(path + ": /" + kind + " as the QP", qp);
    return qp;
}

Qp read_fclib_global(const std::string& path, SnapshotExtras* extras, const FclibReadOptions& options)
{
    FclibReader file(path);
    if (!file.exists("/fclib_global")) {
        if (file.exists("/fclib_local"))
            file.fail("/fclib_global", "missing: this is an fclib_local problem, not an fclib_global one");
        file.fail("/fclib_global", "missing: not an HDF5 file with an FCLIB global problem");
    }
    Qp qp = read_global(file, extras, options);
    validate_qp(path + ": /fclib_global as the QP", qp);
    return qp;
}

FrictionLocal read_fclib_local_friction(const std::string& path)
{
    FclibReader file(path);
    const std::string L = "/fclib_local";
    if (!file.exists(L)) {
        if (file.exists("/fclib_global"))
            file.fail(L, "missing: this is an fclib_global problem, not an fclib_local one");
        file.fail(L, "missing: not an HDF5 file with an FCLIB local problem");
    }
    const long long d = spacedim_of(file, L + "/spacedim");
    if (d != 3) file.fail(L + "/spacedim", "is 2: only 3-D frictional problems (spacedim 3) are solved");
    for (const char* mixed : {"/V", "/R"})
        if (file.exists(L + mixed) && file.integer(L + mixed + "/n") != 0)
            file.fail(L + mixed, "equality constraints (a mixed problem) are not supported");
    const SparseSizes ws = read_sizes(file, L + "/W");
    if (ws.m != ws.n) file.fail(L + "/W", "not square: m = " + std::to_string(ws.m) + ", n = " + std::to_string(ws.n));
    if (ws.m == 0) file.fail(L + "/W/n", "the problem has no contacts (n = 0)");
    if (ws.m % 3 != 0) file.fail(L + "/W/n", std::to_string(ws.m) + " rows: not 3 per contact (spacedim 3)");
    const std::vector<double> q = file.reals(L + "/vectors/q", {ws.m}, L + "/W/m");
    const std::vector<double> mu = file.reals(L + "/vectors/mu", {ws.m / 3}, L + "/W/m / spacedim", false);
    check_mu(file, L + "/vectors/mu", mu, true, "fclib_local");
    FrictionLocal problem;
    problem.W = read_matrix(file, L + "/W", ws);
    problem.q = Eigen::Map<const Vec>(q.data(), Eigen::Index(q.size()));
    problem.mu = Eigen::Map<const Vec>(mu.data(), Eigen::Index(mu.size()));
    problem.name = path;
    return problem;
}

FrictionGlobal read_fclib_global_friction(const std::string& path)
{
    FclibReader file(path);
    const std::string G = "/fclib_global";
    if (!file.exists(G)) {
        if (file.exists("/fclib_local"))
            file.fail(G, "missing: this is an fclib_local problem, not an fclib_global one");
        file.fail(G, "missing: not an HDF5 file with an FCLIB global problem");
    }
    const long long d = spacedim_of(file, G + "/spacedim");
    if (d != 3)
        file.fail(G + "/spacedim", "is 2 (one tangent per contact): only 3-D frictional problems (spacedim 3, "
                                   "two tangents) are solved");
    if (file.exists(G + "/G") && file.integer(G + "/G/n") != 0)
        file.fail(G + "/G", "equality constraints are not supported");
    // Every declared size first, checked against each other and against the vectors' lengths,
    // before any matrix array is allocated.
    const SparseSizes ms = read_sizes(file, G + "/M"), hs = read_sizes(file, G + "/H");
    const long long n = ms.m;
    if (ms.n != n) file.fail(G + "/M", "not square: m = " + std::to_string(ms.m) + ", n = " + std::to_string(ms.n));
    if (n == 0) file.fail(G + "/M/n", "the problem has no unknowns (n = 0)");
    if (hs.m != n) file.fail(G + "/H/m", std::to_string(hs.m) + " rows, but M has " + std::to_string(n));
    if (hs.n == 0) file.fail(G + "/H/n", "the problem has no contacts (n = 0)");
    if (hs.n % 3 != 0)
        file.fail(G + "/H/n", std::to_string(hs.n) + " columns: not 3 per contact (a normal and two tangents)");
    const long long m = hs.n / 3;
    const std::vector<double> f = file.reals(G + "/vectors/f", {n}, G + "/M/m");
    const std::vector<double> w = file.reals(G + "/vectors/w", {hs.n}, G + "/H/n");
    const std::vector<double> mu = file.reals(G + "/vectors/mu", {m}, G + "/H/n / 3", false);
    check_mu(file, G + "/vectors/mu", mu, true, "fclib_global");
    FrictionGlobal problem;
    nlohmann::json notes = nlohmann::json::object();
    problem.M = symmetric_matrix(file, G + "/M", "M", read_matrix(file, G + "/M", ms), false, notes);
    problem.H = read_matrix(file, G + "/H", hs);
    problem.f = Eigen::Map<const Vec>(f.data(), Eigen::Index(n));
    problem.w = Eigen::Map<const Vec>(w.data(), Eigen::Index(w.size()));
    problem.mu = Eigen::Map<const Vec>(mu.data(), Eigen::Index(m));
    problem.name = path;
    return problem;
}

std::string read_fclib_friction(const std::string& path, FrictionLocal& local, FrictionGlobal& global)
{
    std::string kind;
    {
        FclibReader file(path);
        kind = kind_of(file);
        if (kind.empty())
            file.fail("/fclib_global",
                      "missing: an HDF5 file without an FCLIB problem (neither /fclib_global nor /fclib_local)");
    }
    if (kind == "fclib_global")
        global = read_fclib_global_friction(path);
    else
        local = read_fclib_local_friction(path);
    return kind;
}

std::string fclib_kind(const std::string& path)
{
    FclibReader file(path);
    try {
        return kind_of(file);
    } catch (const InputError&) {
        return "";  // both groups, or a link that is not followed: the reader says which
    }
}

nlohmann::json describe_fclib(const std::string& path)
{
    FclibReader file(path);
    const std::string kind = kind_of(file);
    if (kind.empty())
        file.fail("/fclib_global",
                  "missing: an HDF5 file without an FCLIB problem (neither /fclib_global nor /fclib_local)");
    const std::string root = "/" + kind;
    nlohmann::json out = {{"format", kind}};
    const long long d = spacedim_of(file, root + "/spacedim");
    const SparseSizes s = read_sizes(file, root + (kind == "fclib_global" ? "/H" : "/W"));
    const long long contacts = (kind == "fclib_global" ? s.n : s.m) / d;
    out["spacedim"] = d;
    out["contacts"] = contacts;
    if (kind == "fclib_global") out["unknowns"] = read_sizes(file, root + "/M").n;
    const std::vector<double> mu = file.reals(root + "/vectors/mu", {contacts}, root + " sizes", false);
    if (!mu.empty()) {
        out["mu_min"] = *std::min_element(mu.begin(), mu.end());
        out["mu_max"] = *std::max_element(mu.begin(), mu.end());
    }
    // What convert and friction-solve do with the file today: a 3-D global problem keeps its
    // friction in the snapshot (version 2); a local one (no A) or a 2-D one keeps only its normal part.
    const bool frictional = !mu.empty() && *std::max_element(mu.begin(), mu.end()) > 0.0;
    const bool keeps_friction = kind == "fclib_global" && d == 3;
    out["convert"] =
        "contactbench convert " + path + " OUT.qpsnap" + (frictional && !keeps_friction ? " --drop-friction" : "");
    if (frictional && d == 3) out["friction_solve"] = "contactbench friction-solve " + path;
    out["has_solution"] = file.exists("/solution");
    out["guesses"] = file.exists("/guesses/number_of_guesses") ? file.integer("/guesses/number_of_guesses") : 0;
    nlohmann::json source = nlohmann::json::object();
    describe_source(file, root, source);
    for (auto it = source.begin(); it != source.end(); ++it) out[it.key()] = it.value();
    return out;
}

#endif

}  // namespace cb
