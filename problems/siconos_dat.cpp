// Siconos numerics .dat import (siconos_dat.hpp): a bounded tokenizer, the NumericsMatrix
// storages, and the local, global and LCP problem layouts.
#include "problems/siconos_dat.hpp"

#include "problems/io_util.hpp"

#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <string_view>
#include <vector>

namespace cb {
namespace {

std::string exact(double value)
{
    char text[32];
    std::snprintf(text, sizeof(text), "%.17g", value);
    return text;
}

bool is_space(char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\f' || c == '\v'; }

/// The file's text read token by token. Errors name the file, the field and the line.
class DatText {
public:
    explicit DatText(const std::string& path) : m_path(path), m_text(read_regular_file(path))
    {
        m_at = m_text.data();
        m_end = m_text.data() + m_text.size();
    }

    const std::string& path() const { return m_path; }

    [[noreturn]] void fail(const std::string& field, const std::string& problem) const
    {
        throw_input_error(m_path, field, problem + " (line " + std::to_string(line()) + ")");
    }

    /// The most values the rest of the file can hold: each takes a character and a separator.
    std::uint64_t values_left() const
    {
        skip_space();
        return std::uint64_t(m_end - m_at + 1) / 2;
    }

    /// Refuses a count the rest of the file cannot hold, before anything of that size is made.
    void expect_room(const std::string& field, std::uint64_t count, const std::string& what) const
    {
        if (count > values_left())
            fail(field, "declares " + std::to_string(count) + " " + what +
                            ", more than the rest of the file can hold (" + std::to_string(m_end - m_at) +
                            " bytes: a wrong count or a truncated file)");
    }

    /// Counts the tokens left without consuming them.
    std::uint64_t tokens_left() const
    {
        std::uint64_t n = 0;
        for (const char* p = m_at; p < m_end;) {
            while (p < m_end && is_space(*p)) ++p;
            if (p == m_end) break;
            ++n;
            while (p < m_end && !is_space(*p)) ++p;
        }
        return n;
    }

    /// The next `count` tokens as integers, without consuming them (fewer: not all are integers).
    std::vector<long long> peek_integers(int count) const
    {
        std::vector<long long> out;
        const char* p = m_at;
        while (int(out.size()) < count) {
            while (p < m_end && is_space(*p)) ++p;
            const char* stop = p;
            while (stop < m_end && !is_space(*stop)) ++stop;
            long long value = 0;
            const auto [ptr, ec] = std::from_chars(p, stop, value);
            if (p == stop || ec != std::errc() || ptr != stop) break;
            out.push_back(value);
            p = stop;
        }
        return out;
    }

    long long integer(const std::string& field, long long lo, long long hi)
    {
        const std::string_view t = token(field);
        long long value = 0;
        const auto [ptr, ec] = std::from_chars(t.data(), t.data() + t.size(), value);
        if (ec != std::errc() || ptr != t.data() + t.size()) fail(field, "'" + printable(t) + "' is not an integer");
        if (value < lo || value > hi)
            fail(field, "is " + std::to_string(value) +
                            (hi == std::numeric_limits<long long>::max()
                                 ? ", must be >= " + std::to_string(lo)
                                 : ", must be in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]"));
        return value;
    }

    double real(const std::string& field)
    {
        const std::string_view t = token(field);
        double value = 0.0;
        const auto [ptr, ec] = std::from_chars(t.data(), t.data() + t.size(), value);
        if ((ec != std::errc() && ec != std::errc::result_out_of_range) || ptr != t.data() + t.size())
            fail(field, "'" + printable(t) + "' is not a number");
        // from_chars leaves value unset out of range: strtod says inf (1e999, refused) or a
        // subnormal or zero (1e-400), as fscanf would read it.
        if (ec == std::errc::result_out_of_range) value = std::strtod(std::string(t).c_str(), nullptr);
        if (!std::isfinite(value)) fail(field, "is " + printable(t) + " (values must be finite)");
        return value;
    }

    /// A count or size: >= lo, and no more than the rest of the file can hold (every count
    /// stands for values that follow), so nothing of a declared size outgrows the file.
    long long count(const std::string& field, long long lo)
    {
        const std::uint64_t room = values_left();
        const long long value = integer(field, lo, std::numeric_limits<long long>::max());
        if (std::uint64_t(value) > room)
            fail(field, "is " + std::to_string(value) + ", more than the rest of the file can hold (" +
                            std::to_string(m_end - m_at) + " bytes: a wrong count or a truncated file)");
        return value;
    }

    std::vector<double> reals(const std::string& field, std::uint64_t count)
    {
        expect_room(field, count, "values");
        std::vector<double> out(count);
        for (std::uint64_t k = 0; k < count; ++k) out[k] = real(field + "[" + std::to_string(k) + "]");
        return out;
    }

private:
    void skip_space() const
    {
        while (m_at < m_end && is_space(*m_at)) ++m_at;
    }

    std::string_view token(const std::string& field)
    {
        skip_space();
        if (m_at == m_end) fail(field, "missing: the file ends here (truncated)");
        const char* start = m_at;
        while (m_at < m_end && !is_space(*m_at)) ++m_at;
        return std::string_view(start, size_t(m_at - start));
    }

    static std::string printable(std::string_view t)
    {
        std::string out;
        for (const char c : t.substr(0, 40)) out += (c >= 32 && c < 127) ? c : '?';
        if (t.size() > 40) out += "...";
        return out;
    }

    long line() const
    {
        long n = 1;
        for (const char* p = m_text.data(); p < m_at; ++p) n += *p == '\n';
        return n;
    }

    std::string m_path;
    std::string m_text;
    mutable const char* m_at = nullptr;
    const char* m_end = nullptr;
};

/// A NumericsMatrix as read: its entries (zeros left out) and how it was stored.
struct DatMatrix {
    long long rows = 0, cols = 0;
    std::string storage;
    std::vector<Triplet> entries;
    SpMat sparse() const
    {
        SpMat M(rows, cols);
        M.setFromTriplets(entries.begin(), entries.end());
        M.makeCompressed();
        return M;
    }
};

/// Cumulative block sizes: strictly increasing, the last one the matrix's size.
std::vector<long long> block_bounds(DatText& t, const std::string& field, long long count, long long size)
{
    std::vector<long long> bounds(static_cast<size_t>(count));
    for (long long k = 0; k < count; ++k) {
        const std::string at = field + "[" + std::to_string(k) + "]";
        bounds[size_t(k)] = t.integer(at, 1, size);
        if (k > 0 && bounds[size_t(k)] <= bounds[size_t(k - 1)])
            t.fail(at, "is " + std::to_string(bounds[size_t(k)]) + ", not above the previous bound " +
                           std::to_string(bounds[size_t(k - 1)]) + " (cumulative block sizes increase)");
    }
    if (count > 0 && bounds.back() != size)
        t.fail(field + "[" + std::to_string(count - 1) + "]", "is " + std::to_string(bounds.back()) +
                                                                  ", but the matrix has " + std::to_string(size) +
                                                                  " (" + field + " ends at the matrix's size)");
    return bounds;
}

void read_dense(DatText& t, const std::string& name, DatMatrix& M)
{
    const long long rows = t.count(name + ".size0 (dense)", 0);
    const long long cols = t.count(name + ".size1 (dense)", 0);
    if (rows != M.rows || cols != M.cols)
        t.fail(name + ".size0 (dense)", "the dense block is " + std::to_string(rows) + " x " + std::to_string(cols) +
                                            ", the header says " + std::to_string(M.rows) + " x " +
                                            std::to_string(M.cols));
    const std::uint64_t count = std::uint64_t(rows) * std::uint64_t(cols);
    t.expect_room(name + ".matrix0", count, "values");
    for (std::uint64_t k = 0; k < count; ++k) {
        const double v = t.real(name + ".matrix0[" + std::to_string(k) + "]");
        if (v != 0.0) M.entries.emplace_back(int(k % std::uint64_t(rows)), int(k / std::uint64_t(rows)), v);
    }
}

void read_sparse_block(DatText& t, const std::string& name, DatMatrix& M)
{
    const long long nbblocks = t.count(name + ".nbblocks", 0);
    if (nbblocks == 0) return;  // Siconos writes nothing more for a matrix without blocks
    const long long rows_b = t.integer(name + ".blocknumber0", 1, std::max(M.rows, 1LL));
    const long long cols_b = t.integer(name + ".blocknumber1", 1, std::max(M.cols, 1LL));
    const std::vector<long long> row_end = block_bounds(t, name + ".blocksize0", rows_b, M.rows);
    const std::vector<long long> col_end = block_bounds(t, name + ".blocksize1", cols_b, M.cols);
    const long long filled1 = t.integer(name + ".filled1", 2, rows_b + 1);
    const long long filled2 = t.integer(name + ".filled2", nbblocks, nbblocks);
    t.expect_room(name + ".index1_data", std::uint64_t(filled1 + filled2), "indices");
    std::vector<long long> row_ptr(static_cast<size_t>(filled1)), col_of(static_cast<size_t>(filled2));
    for (long long k = 0; k < filled1; ++k) {
        const std::string at = name + ".index1_data[" + std::to_string(k) + "]";
        const long long lo = k == 0 ? 0 : row_ptr[size_t(k - 1)];
        row_ptr[size_t(k)] = t.integer(at, lo, k == 0 ? 0 : filled2);
    }
    if (row_ptr.back() != filled2)
        t.fail(name + ".index1_data[" + std::to_string(filled1 - 1) + "]",
               "is " + std::to_string(row_ptr.back()) + ", must be filled2 = " + std::to_string(filled2) +
                   " (the block-row pointers end at the block count)");
    for (long long k = 0; k < filled2; ++k)
        col_of[size_t(k)] = t.integer(name + ".index2_data[" + std::to_string(k) + "]", 0, cols_b - 1);
    std::vector<long long> seen_in_row(static_cast<size_t>(cols_b), -1);
    for (long long r = 0; r + 1 < filled1; ++r) {
        const long long r0 = r == 0 ? 0 : row_end[size_t(r - 1)], nr = row_end[size_t(r)] - r0;
        for (long long b = row_ptr[size_t(r)]; b < row_ptr[size_t(r + 1)]; ++b) {
            const std::string at = name + ".block[" + std::to_string(b) + "]";
            const long long c = col_of[size_t(b)];
            if (seen_in_row[size_t(c)] == r)
                t.fail(name + ".index2_data[" + std::to_string(b) + "]",
                       "block column " + std::to_string(c) + " appears twice in block row " + std::to_string(r));
            seen_in_row[size_t(c)] = r;
            const long long c0 = c == 0 ? 0 : col_end[size_t(c - 1)], nc = col_end[size_t(c)] - c0;
            const long long number = t.integer(at + " number", 0, std::numeric_limits<long long>::max());
            if (number != b)
                t.fail(at + " number", "is " + std::to_string(number) +
                                           ", the blocks are numbered in order (expected " + std::to_string(b) + ")");
            t.expect_room(at, std::uint64_t(nr) * std::uint64_t(nc), "values");
            for (long long k = 0; k < nr * nc; ++k) {
                const double v = t.real(at + "[" + std::to_string(k) + "]");
                if (v != 0.0) M.entries.emplace_back(int(r0 + k % nr), int(c0 + k / nr), v);
            }
        }
    }
}

DatMatrix read_matrix(DatText& t, const std::string& name)
{
    DatMatrix M;
    const long long storage = t.integer(name + ".storageType", 0, 2);
    if (storage == 2)
        t.fail(name + ".storageType", "is 2 (NM_SPARSE: CSparse's text print, values with 6 significant digits), "
                                      "which does not hold the problem to double precision; write it dense or "
                                      "sparse-block (NM_SPARSE_BLOCK), or as FCLIB (HDF5)");
    // Each size is the length of a vector that follows (q, b), so the file must have room for it.
    M.rows = t.count(name + ".size0", 1);
    M.cols = t.count(name + ".size1", 1);
    if (storage == 0) {
        M.storage = "dense";
        read_dense(t, name, M);
    } else {
        M.storage = "sparse block";
        read_sparse_block(t, name, M);
    }
    return M;
}

/// mu of every contact: finite (checked when read) and >= 0.
void check_mu(DatText& t, const std::vector<double>& mu)
{
    for (size_t i = 0; i < mu.size(); ++i)
        if (!(mu[i] >= 0.0))
            throw_input_error(t.path(), "mu[" + std::to_string(i) + "]",
                              "contact " + std::to_string(i) + " has mu = " + exact(mu[i]) +
                                  " (a friction coefficient is finite and >= 0)");
}

/// What a .dat file holds: a local problem (W, q, mu), a global one (M, H, q, b, mu) or an LCP
/// (n, M, q: Siconos' linearComplementarity_printInFile).
struct DatProblem {
    enum class Kind { LOCAL, GLOBAL, LCP } kind = Kind::LOCAL;
    long long dimension = 0, contacts = 0;  ///< LCP: contacts = n
    DatMatrix W;                            ///< local: W; global and LCP: M
    DatMatrix H;                            ///< global only
    std::vector<double> q, b, mu;
    std::uint64_t ignored_tokens = 0;  ///< after the last field (mu, or the LCP's q)
};

DatProblem read_dat(const std::string& path)
{
    DatText t(path);
    DatProblem p;
    // An LCP starts n, storageType, n, n; a friction-contact problem d, m, storageType, d m (the
    // two agree only for d = 2, m = 1, storage 2, which is refused as a friction problem anyway).
    const std::vector<long long> head = t.peek_integers(4);
    if (head.size() == 4 && head[0] >= 1 && head[1] >= 0 && head[1] <= 2 && head[2] == head[0] && head[3] == head[0]) {
        p.kind = DatProblem::Kind::LCP;
        p.contacts = t.count("size", 1);
        p.W = read_matrix(t, "M");
        p.q = t.reals("q", std::uint64_t(p.contacts));
        p.ignored_tokens = t.tokens_left();
        return p;
    }
    p.dimension = t.integer("dimension", 2, 3);
    p.contacts = t.count("numberOfContacts", 0);
    if (p.contacts == 0) t.fail("numberOfContacts", "is 0: the problem has no contacts");
    const long long rows = p.dimension * p.contacts;
    p.W = read_matrix(t, "M");
    // A global problem's second matrix H (storageType, size0 = M's rows, size1 = d m) follows M;
    // a local one has q and mu, written with %e (a hand-written q of integers is told apart by
    // the three values).
    const std::vector<long long> next = t.peek_integers(3);
    if (next.size() == 3 && next[0] >= 0 && next[0] <= 2 && next[1] == p.W.rows && next[2] == rows)
        p.kind = DatProblem::Kind::GLOBAL;
    if (p.kind == DatProblem::Kind::GLOBAL) {
        if (p.W.rows != p.W.cols)
            t.fail("M", "is " + std::to_string(p.W.rows) + " x " + std::to_string(p.W.cols) + ": not square");
        p.H = read_matrix(t, "H");
        if (p.H.rows != p.W.rows || p.H.cols != rows)
            t.fail("H", "is " + std::to_string(p.H.rows) + " x " + std::to_string(p.H.cols) + ", must be " +
                            std::to_string(p.W.rows) + " x " + std::to_string(rows) + " (M's rows x dimension " +
                            std::to_string(p.dimension) + " times " + std::to_string(p.contacts) + " contacts)");
        p.q = t.reals("q", std::uint64_t(p.W.rows));
        p.b = t.reals("b", std::uint64_t(rows));
    } else {
        if (p.W.rows != rows || p.W.cols != rows)
            t.fail("M", "is " + std::to_string(p.W.rows) + " x " + std::to_string(p.W.cols) + ", must be " +
                            std::to_string(rows) + " x " + std::to_string(rows) + " (dimension " +
                            std::to_string(p.dimension) + " times " + std::to_string(p.contacts) + " contacts)");
        p.q = t.reals("q", std::uint64_t(rows));
    }
    p.mu = t.reals("mu", std::uint64_t(p.contacts));
    // Siconos' test files append their solver settings; its reader stops after mu, and so do we.
    p.ignored_tokens = t.tokens_left();
    check_mu(t, p.mu);
    return p;
}

/// A global problem is not imported by any command; an LCP is by convert only.
void refuse_kind(const std::string& path, const DatProblem& p, bool lcp_taken)
{
    if (p.kind == DatProblem::Kind::GLOBAL)
        throw_input_error(path, "H",
                          "a global friction-contact problem (Siconos GlobalFrictionContactProblem: M, H, q, b, mu), "
                          "not a local one (W, q, mu); contactbench imports local .dat problems only (write it as "
                          "FCLIB fclib_global with Siconos, then `contactbench convert` it)");
    if (p.kind == DatProblem::Kind::LCP && !lcp_taken)
        throw_input_error(path, "size",
                          "a linear complementarity problem (Siconos LinearComplementarityProblem: n, M, q), not a "
                          "friction-contact one; `contactbench convert` takes it as a QP (A = M, b = -q, J = I, "
                          "c = 0)");
}

}  // namespace

FrictionLocal read_siconos_dat_friction(const std::string& path)
{
    DatProblem p = read_dat(path);
    refuse_kind(path, p, false);
    if (p.dimension != 3)
        throw_input_error(path, "dimension",
                          "is " + std::to_string(p.dimension) +
                              ": only 3-D frictional problems (dimension 3) are solved");
    FrictionLocal problem;
    problem.W = p.W.sparse();
    problem.q = Eigen::Map<const Vec>(p.q.data(), Eigen::Index(p.q.size()));
    problem.mu = Eigen::Map<const Vec>(p.mu.data(), Eigen::Index(p.mu.size()));
    problem.name = path;
    return problem;
}

Qp read_siconos_dat_qp(const std::string& path, const FclibReadOptions& options)
{
    DatProblem p = read_dat(path);
    refuse_kind(path, p, true);
    const bool lcp = p.kind == DatProblem::Kind::LCP;
    // An LCP is its own normal block: one "contact" per unknown, no friction.
    if (lcp) {
        p.dimension = 1;
        p.mu.assign(size_t(p.contacts), 0.0);
    }
    const long long d = p.dimension, m = p.contacts;
    const std::string block = lcp ? "the LCP matrix M" : "the normal block W_NN (indexed by contact)";
    double mu_min = p.mu[0], mu_max = p.mu[0];
    for (size_t i = 0; i < p.mu.size(); ++i) {
        if (p.mu[i] != 0.0 && !options.drop_friction)
            throw_input_error(path, "mu[" + std::to_string(i) + "]",
                              "contact " + std::to_string(i) + " has mu = " + exact(p.mu[i]) +
                                  ": this Siconos local problem has friction, which a snapshot cannot hold (it has no "
                                  "A); `convert --drop-friction` keeps its normal part (recorded in the snapshot), "
                                  "`friction-solve` solves a 3-D one with its friction");
        mu_min = std::min(mu_min, p.mu[i]);
        mu_max = std::max(mu_max, p.mu[i]);
    }
    // The normal block: rows and columns d i of W.
    std::vector<Triplet> normal;
    for (const Triplet& e : p.W.entries)
        if (e.row() % d == 0 && e.col() % d == 0) normal.emplace_back(int(e.row() / d), int(e.col() / d), e.value());
    SpMat A(m, m);
    A.setFromTriplets(normal.begin(), normal.end());
    A.makeCompressed();
    nlohmann::json provenance = {
        {"format", "siconos_dat"}, {"file", std::filesystem::path(path).filename().string()}, {"storage", p.W.storage}};
    if (lcp) {
        provenance["problem"] = "lcp";
        provenance["size"] = m;
        provenance["mapping"] = "A = M, b = -q, J = I, c = 0 (x = z, lambda = w = M z + q)";
    } else {
        provenance["problem"] = "local friction-contact";
        provenance["dimension"] = d;
        provenance["contacts"] = m;
        provenance["mapping"] = "A = W_NN, b = -q_N, J = I, c = 0 (x = r_N, lambda = u_N)";
    }
    // Symmetric to rounding, else refused (or averaged when asked), as FCLIB's W_NN is.
    const SpMat At = A.transpose();
    const SpMat diff = A - At;
    double worst = 0.0, max_abs = 0.0;
    Eigen::Index wi = 0, wj = 0;
    for (Eigen::Index r = 0; r < A.outerSize(); ++r)
        for (SpMat::InnerIterator it(A, r); it; ++it) max_abs = std::max(max_abs, std::abs(it.value()));
    for (Eigen::Index r = 0; r < diff.outerSize(); ++r)
        for (SpMat::InnerIterator it(diff, r); it; ++it)
            if (std::abs(it.value()) > worst) {
                worst = std::abs(it.value());
                wi = r;
                wj = it.col();
            }
    Qp qp;
    if (worst > 1e-12 * max_abs) {
        if (!options.symmetrise)
            throw_input_error(path, "M",
                              block + " is not symmetric: (" + std::to_string(wi) + ", " + std::to_string(wj) +
                                  ") = " + exact(A.coeff(wi, wj)) + " but (" + std::to_string(wj) + ", " +
                                  std::to_string(wi) + ") = " + exact(A.coeff(wj, wi)) +
                                  " (beyond 1e-12 of its largest entry); `convert --symmetrise` averages it with its "
                                  "transpose");
        qp.A = SpMat(0.5 * (A + At));
        provenance["matrices"] = {{"M", block + " not symmetric (largest difference " + exact(worst) +
                                            "): replaced by its average with its transpose"}};
    } else {
        qp.A = A;
    }
    qp.A.makeCompressed();
    qp.b.resize(Eigen::Index(m));
    for (Eigen::Index i = 0; i < m; ++i) qp.b[i] = -p.q[size_t(d * i)];
    qp.J.resize(Eigen::Index(m), Eigen::Index(m));
    qp.J.setIdentity();
    qp.J.makeCompressed();
    qp.c = Vec::Zero(Eigen::Index(m));
    qp.x0 = Vec::Zero(Eigen::Index(m));
    if (mu_max != 0.0)
        provenance["dropped_friction"] = {
            {"mu_min", mu_min},
            {"mu_max", mu_max},
            {"kept", "the normal block W_NN: a frictionless problem, not the file's frictional one"}};
    qp.meta = nlohmann::json::object();
    qp.meta["provenance"] = provenance;
    validate_qp(path + (lcp ? ": the LCP as the QP" : ": the normal block as the QP"), qp);
    return qp;
}

nlohmann::json describe_siconos_dat(const std::string& path)
{
    const DatProblem p = read_dat(path);
    if (p.kind == DatProblem::Kind::LCP)
        return {{"format", "siconos_dat"},
                {"problem", "linear complementarity (w = M z + q, 0 <= z ⊥ w >= 0)"},
                {"size", p.contacts},
                {"storage", p.W.storage},
                {"nnz_M", p.W.entries.size()},
                {"ignored_after_q", p.ignored_tokens},
                {"imported", true},
                {"convert", "contactbench convert " + path + " OUT.qpsnap"}};
    double mu_min = p.mu[0], mu_max = p.mu[0];
    for (const double mu : p.mu) {
        mu_min = std::min(mu_min, mu);
        mu_max = std::max(mu_max, mu);
    }
    nlohmann::json out = {{"format", "siconos_dat"},
                          {"problem", p.kind == DatProblem::Kind::GLOBAL
                                          ? "global friction-contact (M v = q + H r, u = H'v + b)"
                                          : "local friction-contact (u = W r + q)"},
                          {"dimension", p.dimension},
                          {"contacts", p.contacts},
                          {"storage", p.W.storage},
                          {"mu_min", mu_min},
                          {"mu_max", mu_max},
                          {"ignored_after_mu", p.ignored_tokens}};
    if (p.kind == DatProblem::Kind::GLOBAL) {
        out["unknowns"] = p.W.rows;
        out["nnz_M"] = p.W.entries.size();
        out["nnz_H"] = p.H.entries.size();
        out["imported"] = false;
        out["convert"] = "not imported: write it as FCLIB fclib_global with Siconos, then convert that";
        return out;
    }
    out["rows"] = p.W.rows;
    out["nnz_W"] = p.W.entries.size();
    out["imported"] = true;
    out["convert"] = "contactbench convert " + path + " OUT.qpsnap" + (mu_max > 0.0 ? " --drop-friction" : "");
    if (p.dimension == 3) out["friction_solve"] = "contactbench friction-solve " + path;
    return out;
}

}  // namespace cb
