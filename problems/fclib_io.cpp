// FCLIB export/import of the contact QP (mapping and its justification in fclib_io.hpp).
#include "problems/fclib_io.hpp"

#include "problems/io_util.hpp"
#include "problems/safe_output.hpp"

#include <filesystem>

#ifdef CB_HAVE_FCLIB
extern "C" {
#include <fclib.h>
}
#include <algorithm>
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

Qp read_fclib_global(const std::string& path, SnapshotExtras*)
{
    throw InputError(path + ": FCLIB import is not built (install libfclib-dev and reconfigure with CB_PEERS=ON)");
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

/// A sparse matrix of the FCLIB layout (group with nzmax, m, n, nz, p, i, x), checked.
struct SparseSizes {
    long long nzmax = 0, m = 0, n = 0, nz = 0;
};

/// Reads the FCLIB layout (fclib.h; the groups and datasets libfclib writes) with plain HDF5
/// calls, so that no malformed file reaches libfclib's readers, which allocate from declared
/// sizes, read whatever length the dataset has, and exit(1) on any HDF5 error. Every dataset's
/// class, rank, length and stored bytes are checked before its buffer is allocated: a length
/// must equal the size the layout declares, and the bytes must be in the file (so memory is
/// bounded by the file's size: no fill values, no compressed data).
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

    [[noreturn]] void fail(const std::string& field, const std::string& problem) const
    {
        throw InputError(m_path + ": " + field + ": " + problem);
    }

    /// True when every link of `name` ("/a/b/c") exists (H5Lexists needs the parents to exist).
    bool exists(const std::string& name) const
    {
        for (size_t slash = name.find('/', 1);; slash = name.find('/', slash + 1)) {
            const std::string prefix = name.substr(0, slash);
            if (H5Lexists(m_file, prefix.c_str(), H5P_DEFAULT) <= 0) return false;
            if (slash == std::string::npos) return true;
        }
    }

    /// One integer (a dataset of one element).
    long long integer(const std::string& name)
    {
        const std::vector<long long> v = integers(name, 1, "one value");
        return v[0];
    }

    /// An integer array of exactly `expected` values; `declared` says who declares the length.
    std::vector<long long> integers(const std::string& name, long long expected, const std::string& declared)
    {
        std::vector<long long> values;
        read(name, H5T_INTEGER, expected, declared, H5T_NATIVE_LLONG, values);
        return values;
    }

    std::vector<double> reals(const std::string& name, long long expected, const std::string& declared)
    {
        std::vector<double> values;
        read(name, H5T_FLOAT, expected, declared, H5T_NATIVE_DOUBLE, values);
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
    void read(const std::string& name, H5T_class_t kind, long long expected, const std::string& declared,
              hid_t memory_type, std::vector<T>& out)
    {
        const H5Handle data(open_dataset(name), H5Dclose);
        const H5Handle type(H5Dget_type(data.id()), H5Tclose);
        if (H5Tget_class(type.id()) != kind)
            fail(name, kind == H5T_INTEGER ? "expected integers" : "expected floating-point numbers");
        const long long count = points(name, data.id());
        if (count != expected)
            fail(name,
                 "holds " + std::to_string(count) + " values, " + declared + " declares " + std::to_string(expected));
        check_stored(name, data.id(), size_t(count) * H5Tget_size(type.id()));
        out.resize(size_t(count));
        if (count > 0 && H5Dread(data.id(), memory_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, out.data()) < 0)
            fail(name, "HDF5 cannot read it");
    }

    std::string m_path;
    hid_t m_file = -1;
};

std::string exact(double value)
{
    char text[32];
    std::snprintf(text, sizeof(text), "%.17g", value);
    return text;
}

/// Largest size or count accepted (our sparse matrices index with int).
constexpr long long MAX_INDEX = 2147483646;

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

/// The matrix of `group` (sizes checked by read_sizes) as a row-major Eigen matrix; values bit for bit.
SpMat read_matrix(FclibReader& file, const std::string& group, const SparseSizes& s)
{
    const std::string nzmax = group + "/nzmax";
    const std::vector<double> x = file.reals(group + "/x", s.nzmax, nzmax);
    std::vector<Triplet> t;
    auto index = [&](const char* field, long long k, long long value, long long bound) {
        if (value < 0 || value >= bound)
            file.fail(group + "/" + field, "entry " + std::to_string(k) + " is " + std::to_string(value) +
                                               ", outside 0.." + std::to_string(bound - 1));
        return static_cast<int>(value);
    };
    if (s.nz >= 0) {  // triplets: p holds rows, i columns
        const std::string declared = group + "/nz";
        const std::vector<long long> p = file.integers(group + "/p", s.nz, declared);
        const std::vector<long long> i = file.integers(group + "/i", s.nz, declared);
        t.reserve(size_t(s.nz));
        for (long long k = 0; k < s.nz; ++k) t.emplace_back(index("p", k, p[k], s.m), index("i", k, i[k], s.n), x[k]);
    } else {  // -1: compressed columns (p over the n columns), -2: compressed rows
        const bool columns = s.nz == -1;
        const long long outer = columns ? s.n : s.m, inner = columns ? s.m : s.n;
        const std::vector<long long> p =
            file.integers(group + "/p", outer + 1, (columns ? group + "/n" : group + "/m") + " + 1 (CSC/CSR)");
        const std::vector<long long> i = file.integers(group + "/i", s.nzmax, nzmax);
        for (long long o = 0; o <= outer; ++o)
            if (p[o] < (o == 0 ? 0 : p[o - 1]) || p[o] > s.nzmax)
                file.fail(group + "/p", "entry " + std::to_string(o) + " is " + std::to_string(p[o]) +
                                            ": column pointers must be non-decreasing within 0..nzmax (" +
                                            std::to_string(s.nzmax) + ")");
        t.reserve(size_t(p[outer] - p[0]));
        for (long long o = 0; o < outer; ++o)
            for (long long k = p[o]; k < p[o + 1]; ++k) {
                const int in = index("i", k, i[k], inner);
                if (columns)
                    t.emplace_back(in, static_cast<int>(o), x[k]);
                else
                    t.emplace_back(static_cast<int>(o), in, x[k]);
            }
    }
    SpMat out(static_cast<Eigen::Index>(s.m), static_cast<Eigen::Index>(s.n));
    out.setFromTriplets(t.begin(), t.end());
    out.makeCompressed();
    return out;
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
    MatrixView M = csr_view(qp.A), H = h_view(qp.J);
    Vec f = qp.b;
    Vec w = Vec::Zero(3 * m), mu = Vec::Zero(m);
    for (Eigen::Index i = 0; i < m; ++i) w[3 * i] = -qp.c[i];

    std::string title = "contactbench QP", description = qp.meta.dump(),
                math_info = "frictionless (mu = 0): minimize 1/2 x'Ax - b'x subject to Jx >= c";
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
    fclib_solution guess{x0.data(), u0.data(), r0.data(), nullptr};
    if (!fclib_write_guesses(1, &guess, tmp.c_str()))
        throw InputError(path + ": libfclib could not write the start point");

    if (extras && extras->x_ref.size() == n && extras->lambda_ref.size() == m) {
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

Qp read_fclib_global(const std::string& path, SnapshotExtras* extras)
{
    FclibReader file(path);
    if (!file.exists("/fclib_global"))
        file.fail("/fclib_global", "missing: not an HDF5 file with an FCLIB global problem");
    const long long spacedim = file.integer("/fclib_global/spacedim");
    if (spacedim != 3) file.fail("/fclib_global/spacedim", "must be 3, got " + std::to_string(spacedim));
    if (file.exists("/fclib_global/G")) {
        const long long g = file.integer("/fclib_global/G/n");
        if (g != 0)
            file.fail("/fclib_global/G", "equality constraints are not supported (" + std::to_string(g) + " columns)");
    }

    // Every declared size first, checked against each other and against the vectors' lengths
    // (whose bytes are in the file), before any matrix array is allocated.
    const SparseSizes ms = read_sizes(file, "/fclib_global/M"), hs = read_sizes(file, "/fclib_global/H");
    const long long n = ms.m;
    if (ms.n != n)
        file.fail("/fclib_global/M", "not square: m = " + std::to_string(ms.m) + ", n = " + std::to_string(ms.n));
    if (hs.m != n) file.fail("/fclib_global/H/m", std::to_string(hs.m) + " rows, but M has " + std::to_string(n));
    if (hs.n % 3 != 0)
        file.fail("/fclib_global/H/n", std::to_string(hs.n) + " columns: not 3 per contact (spacedim 3)");
    const long long m = hs.n / 3;
    const std::vector<double> f = file.reals("/fclib_global/vectors/f", n, "/fclib_global/M/m");
    const std::vector<double> w = file.reals("/fclib_global/vectors/w", 3 * m, "/fclib_global/H/n");
    const std::vector<double> mu = file.reals("/fclib_global/vectors/mu", m, "/fclib_global/H/n / 3");
    for (long long i = 0; i < m; ++i) {
        const std::string contact = "contact " + std::to_string(i);
        if (mu[size_t(i)] != 0.0)  // NaN too
            file.fail("/fclib_global/vectors/mu", contact + " has mu = " + exact(mu[size_t(i)]) +
                                                      " (friction is not supported: only mu = 0 maps onto the QP)");
        if (w[size_t(3 * i + 1)] != 0.0 || w[size_t(3 * i + 2)] != 0.0)
            file.fail("/fclib_global/vectors/w",
                      contact + " has a tangential entry (only (w_N, 0, 0) maps onto the QP)");
    }

    Qp qp;
    qp.A = read_matrix(file, "/fclib_global/M", ms);
    const SpMat H = read_matrix(file, "/fclib_global/H", hs);
    qp.b = Eigen::Map<const Vec>(f.data(), Eigen::Index(n));
    qp.c.resize(Eigen::Index(m));
    const SpMat Ht = H.transpose();
    std::vector<Triplet> jt;
    for (Eigen::Index i = 0; i < m; ++i) {
        if (Ht.outerIndexPtr()[3 * i + 1] != Ht.outerIndexPtr()[3 * i + 3])
            file.fail("/fclib_global/H", "contact " + std::to_string(i) +
                                             " has tangential columns (only the normal column maps onto the QP)");
        qp.c[i] = -w[size_t(3 * i)];
        for (SpMat::InnerIterator it(Ht, 3 * i); it; ++it) jt.emplace_back(static_cast<int>(i), it.col(), it.value());
    }
    qp.J.resize(Eigen::Index(m), Eigen::Index(n));
    qp.J.setFromTriplets(jt.begin(), jt.end());
    qp.J.makeCompressed();

    // The first initial guess (libfclib sizes v by M/n) is the start point.
    qp.x0 = Vec::Zero(Eigen::Index(n));
    if (file.exists("/guesses")) {
        const long long guesses = file.integer("/guesses/number_of_guesses");
        if (guesses < 0) file.fail("/guesses/number_of_guesses", "must be >= 0, got " + std::to_string(guesses));
        if (guesses > 0 && n > 0) {
            const std::vector<double> v = file.reals("/guesses/1/v", n, "/fclib_global/M/n");
            qp.x0 = Eigen::Map<const Vec>(v.data(), Eigen::Index(n));
        }
    }
    if (file.exists("/fclib_global/info/description")) {
        // Free text in files from elsewhere: only a JSON object of ours becomes the metadata.
        try {
            const nlohmann::json meta = parse_json_text(file.text("/fclib_global/info/description"), path);
            if (meta.is_object()) qp.meta = meta;
        } catch (const InputError&) {
        }
    }
    if (extras) {
        *extras = SnapshotExtras{};
        if (file.exists("/solution")) {
            if (n > 0) {
                const std::vector<double> v = file.reals("/solution/v", n, "/fclib_global/M/n");
                extras->x_ref = Eigen::Map<const Vec>(v.data(), Eigen::Index(n));
            }
            const std::vector<double> r = file.reals("/solution/r", 3 * m, "/fclib_global/H/n");
            extras->lambda_ref.resize(Eigen::Index(m));
            for (Eigen::Index i = 0; i < m; ++i) extras->lambda_ref[i] = r[size_t(3 * i)];
        }
    }
    validate_qp(path, qp);
    return qp;
}

#endif

}  // namespace cb
