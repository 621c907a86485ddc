// Collision decoupling (ALGORITHMS.md §1): keep at most one row per vertex so that JJ' is diagonal.
// Ref: Li et al., "Deformable Objects Collision Handling with Fast Convergence", CGF 2015, Sec. 5.
#include "solvers/mprgp/decouple.hpp"

#include <algorithm>
#include <numeric>
#include <random>

namespace cb {

DecoupleOrder decouple_order_from_string(const std::string& name)
{
    if (name == "authors") return DecoupleOrder::AUTHORS;
    if (name == "random") return DecoupleOrder::RANDOM;
    if (name == "depth") return DecoupleOrder::DEPTH;
    throw_input_error("decouple", "order", "expected one of authors, random, depth, got '" + name + "'");
}

const char* to_string(DecoupleOrder order)
{
    switch (order) {
    case DecoupleOrder::AUTHORS:
        return "authors";
    case DecoupleOrder::RANDOM:
        return "random";
    case DecoupleOrder::DEPTH:
        return "depth";
    }
    return "unknown";
}

namespace {

/// Vertices (column / 3) touched by row i, sorted and unique (a row has at most a few).
void row_vertices(const SpMat& J, Eigen::Index i, std::vector<Eigen::Index>& out)
{
    out.clear();
    for (SpMat::InnerIterator it(J, i); it; ++it)
        if (it.value() != 0.0) out.push_back(it.col() / 3);
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
}

}  // namespace

bool is_decoupled(const SpMat& J)
{
    std::vector<int> owner(static_cast<size_t>(J.cols() / 3 + 1), -1);
    std::vector<Eigen::Index> vertices;
    for (Eigen::Index i = 0; i < J.rows(); ++i) {
        row_vertices(J, i, vertices);
        for (Eigen::Index v : vertices) {
            int& o = owner[static_cast<size_t>(v)];
            if (o >= 0 && o != static_cast<int>(i)) return false;
            o = static_cast<int>(i);
        }
    }
    return true;
}

DecoupleReport decouple_rows(const QpView& qp, const ContactRows& contacts, DecoupleOrder order, std::uint64_t seed)
{
    const Eigen::Index m = qp.m();
    DecoupleReport report;
    report.order = order;
    report.seed = seed;
    report.rows_before = static_cast<long>(m);
    if (is_decoupled(qp.J)) {
        // Already decoupled: pass through untouched (never re-run the greedy choice).
        report.already_decoupled = true;
        report.kept_rows.resize(static_cast<size_t>(m));
        std::iota(report.kept_rows.begin(), report.kept_rows.end(), 0);
        report.rows_after = report.rows_before;
        return report;
    }
    std::vector<int> visit(static_cast<size_t>(m));
    std::iota(visit.begin(), visit.end(), 0);
    const bool has_kind = contacts.kind.size() == static_cast<size_t>(m);
    const bool has_depth = contacts.depth.size() == static_cast<size_t>(m);
    switch (order) {
    case DecoupleOrder::AUTHORS: {
        // Planes, then obstacles, then inter-body (then self / other), each in detection order.
        auto rank = [&](int i) -> std::int64_t {
            return has_kind ? contacts.kind[static_cast<size_t>(i)] : static_cast<std::int64_t>(ContactKind::OTHER);
        };
        std::stable_sort(visit.begin(), visit.end(), [&](int a, int b) { return rank(a) < rank(b); });
        break;
    }
    case DecoupleOrder::RANDOM: {
        // Our own Fisher-Yates on mt19937_64: std::shuffle's result differs between libraries.
        std::mt19937_64 rng(seed);
        for (size_t k = visit.size(); k > 1; --k) {
            const size_t j = static_cast<size_t>(rng() % k);
            std::swap(visit[k - 1], visit[j]);
        }
        break;
    }
    case DecoupleOrder::DEPTH: {
        std::vector<double> depth(static_cast<size_t>(m));
        if (has_depth) {
            depth = contacts.depth;
        } else {
            const Vec residual = qp.c - qp.J * qp.x0;  // c_i - J_i x0: penetration in row units
            for (Eigen::Index i = 0; i < m; ++i) depth[static_cast<size_t>(i)] = residual[i];
        }
        std::stable_sort(visit.begin(), visit.end(),
                         [&](int a, int b) { return depth[static_cast<size_t>(a)] > depth[static_cast<size_t>(b)]; });
        break;
    }
    }
    std::vector<char> taken(static_cast<size_t>(qp.J.cols() / 3 + 1), 0);
    std::vector<Eigen::Index> vertices;
    for (int i : visit) {
        row_vertices(qp.J, i, vertices);
        bool free = true;
        for (Eigen::Index v : vertices) free = free && !taken[static_cast<size_t>(v)];
        if (!free) continue;
        for (Eigen::Index v : vertices) taken[static_cast<size_t>(v)] = 1;
        report.kept_rows.push_back(i);
    }
    std::sort(report.kept_rows.begin(), report.kept_rows.end());
    report.rows_after = static_cast<long>(report.kept_rows.size());
    return report;
}

void select_constraint_rows(const Qp& qp, const std::vector<int>& rows, SpMat& J_out, Vec& c_out)
{
    std::vector<Triplet> triplets;
    c_out.resize(static_cast<Eigen::Index>(rows.size()));
    for (size_t r = 0; r < rows.size(); ++r) {
        const int i = rows[r];
        if (i < 0 || i >= qp.m())
            throw_input_error("select_rows", "rows",
                              "row " + std::to_string(i) + " out of range [0, " + std::to_string(qp.m()) + ")");
        for (SpMat::InnerIterator it(qp.J, i); it; ++it)
            triplets.emplace_back(static_cast<int>(r), static_cast<int>(it.col()), it.value());
        c_out[static_cast<Eigen::Index>(r)] = qp.c[i];
    }
    J_out.resize(static_cast<Eigen::Index>(rows.size()), qp.J.cols());
    J_out.setFromTriplets(triplets.begin(), triplets.end());
}

Qp select_rows(const Qp& qp, const std::vector<int>& rows)
{
    Qp out;
    out.A = qp.A;
    out.a_symmetric = qp.a_symmetric;  // the same A
    out.b = qp.b;
    out.x0 = qp.x0;
    out.meta = qp.meta;
    out.length = qp.length;  // A, b and x0 are kept: so is the scene size
    select_constraint_rows(qp, rows, out.J, out.c);
    const ContactRows& in = qp.contacts;
    const size_t m = static_cast<size_t>(qp.m());
    for (int i : rows) {
        const size_t k = static_cast<size_t>(i);
        if (in.kind.size() == m) out.contacts.kind.push_back(in.kind[k]);
        if (in.depth.size() == m) out.contacts.depth.push_back(in.depth[k]);
        if (in.vertex.size() == 4 * m)
            for (size_t j = 0; j < 4; ++j) out.contacts.vertex.push_back(in.vertex[4 * k + j]);
    }
    return out;
}

}  // namespace cb
