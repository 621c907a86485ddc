// FCLIB export/import of the contact QP (mapping and its justification in fclib_io.hpp).
#include "problems/fclib_io.hpp"

#include <filesystem>

#ifdef CB_HAVE_FCLIB
extern "C" {
#include <fclib.h>
}
#include <cstdlib>
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

[[noreturn]] void fail(const std::string& path, const std::string& field, const std::string& problem)
{
    throw InputError(path + ": " + field + ": " + problem);
}

/// Any fclib matrix (triplets, CSC or CSR) as a row-major Eigen matrix; values kept bit for bit.
SpMat to_eigen(const std::string& path, const std::string& field, const fclib_matrix* f)
{
    if (!f) fail(path, field, "missing");
    if (f->m < 0 || f->n < 0) fail(path, field, "negative size");
    std::vector<Triplet> t;
    auto add = [&](long r, long c, double v) {
        if (r < 0 || r >= f->m || c < 0 || c >= f->n)
            fail(path, field, "index (" + std::to_string(r) + ", " + std::to_string(c) + ") out of range");
        t.emplace_back(static_cast<int>(r), static_cast<int>(c), v);
    };
    if (f->nz >= 0) {
        for (int k = 0; k < f->nz; ++k) add(f->p[k], f->i[k], f->x[k]);
    } else {
        const int outer = f->nz == -2 ? f->m : f->n;
        for (int o = 0; o < outer; ++o)
            for (int k = f->p[o]; k < f->p[o + 1]; ++k) {
                if (f->nz == -2)
                    add(o, f->i[k], f->x[k]);
                else
                    add(f->i[k], o, f->x[k]);
            }
    }
    SpMat out(f->m, f->n);
    out.setFromTriplets(t.begin(), t.end());
    out.makeCompressed();
    return out;
}

/// libfclib exits the process when a group it reads is missing, so look before reading.
bool has_group(const std::string& path, const char* group)
{
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);  // absent groups are expected: no HDF5 error stack on stderr
    const hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
    if (file < 0) return false;
    const bool exists = H5Lexists(file, group, H5P_DEFAULT) > 0;
    H5Fclose(file);
    return exists;
}

}  // namespace

void write_fclib_global(const std::string& path, const Qp& qp, const SnapshotExtras* extras)
{
    const Eigen::Index n = qp.n(), m = qp.m();
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

    const std::string tmp = path + ".tmp." + std::to_string(::getpid());
    std::filesystem::remove(tmp);
    auto cleanup_fail = [&](const std::string& what) {
        std::filesystem::remove(tmp);
        throw InputError(path + ": " + what);
    };
    if (!fclib_write_global(&problem, tmp.c_str())) cleanup_fail("libfclib could not write the problem");

    // x0 as the first guess: v = x0, r = 0, u = H'x0 + w.
    Vec x0 = qp.x0, r0 = Vec::Zero(3 * m), u0 = Vec::Zero(3 * m);
    const Vec jx0 = qp.J * qp.x0;
    for (Eigen::Index i = 0; i < m; ++i) u0[3 * i] = jx0[i] - qp.c[i];
    fclib_solution guess{x0.data(), u0.data(), r0.data(), nullptr};
    if (!fclib_write_guesses(1, &guess, tmp.c_str())) cleanup_fail("libfclib could not write the start point");

    if (extras && extras->x_ref.size() == n && extras->lambda_ref.size() == m) {
        Vec v = extras->x_ref, r = Vec::Zero(3 * m), u = Vec::Zero(3 * m);
        const Vec jx = qp.J * extras->x_ref;
        for (Eigen::Index i = 0; i < m; ++i) {
            r[3 * i] = extras->lambda_ref[i];
            u[3 * i] = jx[i] - qp.c[i];
        }
        fclib_solution solution{v.data(), u.data(), r.data(), nullptr};
        if (!fclib_write_solution(&solution, tmp.c_str())) cleanup_fail("libfclib could not write the solution");
    }
    std::error_code ec;
    std::filesystem::rename(tmp, path, ec);
    if (ec) cleanup_fail("cannot rename the temporary file into place: " + ec.message());
}

Qp read_fclib_global(const std::string& path, SnapshotExtras* extras)
{
    if (!std::filesystem::is_regular_file(path)) fail(path, "file", "does not exist or is not a file");
    if (!has_group(path, "/fclib_global")) fail(path, "/fclib_global", "not an HDF5 file with an FCLIB global problem");
    fclib_global* p = fclib_read_global(path.c_str());
    if (!p) fail(path, "/fclib_global", "libfclib could not read a global problem");
    struct Release {
        fclib_global* p;
        ~Release() { fclib_delete_global(p); }
    } release{p};

    if (p->spacedim != 3) fail(path, "/fclib_global/spacedim", "must be 3, got " + std::to_string(p->spacedim));
    if (p->G && p->G->n > 0) fail(path, "/fclib_global/G", "equality constraints are not supported");
    Qp qp;
    qp.A = to_eigen(path, "/fclib_global/M", p->M);
    const SpMat H = to_eigen(path, "/fclib_global/H", p->H);
    const Eigen::Index n = qp.A.rows();
    if (qp.A.cols() != n) fail(path, "/fclib_global/M", "not square");
    if (H.rows() != n)
        fail(path, "/fclib_global/H", "has " + std::to_string(H.rows()) + " rows, M has " + std::to_string(n));
    if (H.cols() % 3 != 0) fail(path, "/fclib_global/H", "column count is not a multiple of 3");
    const Eigen::Index m = H.cols() / 3;
    if (!p->f || (n > 0 && !p->w && m > 0)) fail(path, "/fclib_global", "f or w missing");
    qp.b = Eigen::Map<const Vec>(p->f, n);
    qp.c.resize(m);
    const SpMat Ht = H.transpose();
    std::vector<Triplet> jt;
    for (Eigen::Index i = 0; i < m; ++i) {
        const std::string contact = "contact " + std::to_string(i);
        if (p->mu && p->mu[i] != 0.0)
            fail(path, "/fclib_global/mu",
                 contact + " has mu = " + std::to_string(p->mu[i]) +
                     " (friction is not supported: only mu = 0 maps onto the QP)");
        if (p->w[3 * i + 1] != 0.0 || p->w[3 * i + 2] != 0.0)
            fail(path, "/fclib_global/w", contact + " has a tangential entry (only (w_N, 0, 0) maps onto the QP)");
        if (Ht.outerIndexPtr()[3 * i + 1] != Ht.outerIndexPtr()[3 * i + 3])
            fail(path, "/fclib_global/H",
                 contact + " has tangential columns (only the normal column maps onto the QP)");
        qp.c[i] = -p->w[3 * i];
        for (SpMat::InnerIterator it(Ht, 3 * i); it; ++it) jt.emplace_back(static_cast<int>(i), it.col(), it.value());
    }
    qp.J.resize(m, n);
    qp.J.setFromTriplets(jt.begin(), jt.end());
    qp.J.makeCompressed();
    qp.x0 = Vec::Zero(n);
    int guesses = 0;
    fclib_solution* g = has_group(path, "/guesses") ? fclib_read_guesses(path.c_str(), &guesses) : nullptr;
    if (g && guesses > 0 && g[0].v) qp.x0 = Eigen::Map<const Vec>(g[0].v, n);
    if (g) fclib_delete_solutions(g, guesses);
    if (p->info && p->info->description) {
        const auto meta = nlohmann::json::parse(p->info->description, nullptr, false);
        if (meta.is_object()) qp.meta = meta;
    }

    if (extras) {
        *extras = SnapshotExtras{};
        fclib_solution* s = has_group(path, "/solution") ? fclib_read_solution(path.c_str()) : nullptr;
        if (s && s->v && s->r) {
            extras->x_ref = Eigen::Map<const Vec>(s->v, n);
            extras->lambda_ref.resize(m);
            for (Eigen::Index i = 0; i < m; ++i) extras->lambda_ref[i] = s->r[3 * i];
        }
        if (s) fclib_delete_solutions(s, 1);
    }
    validate_qp(path, qp);
    return qp;
}

#endif

}  // namespace cb
