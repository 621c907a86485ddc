// The face operators of the coupled MPRGP, per component of J's row graph (ALGORITHMS.md §4): the
// blocks (solvers/mprgp/coupled_row_block.hpp) and the scatter / gather between them and the rows.
// Ref: Li et al., "Deformable Objects Collision Handling with Fast Convergence", CGF 2015,
//      eq. (15)-(16) free gradient, (17)-(18) chopped gradient, (19)-(20) projection.
#include "solvers/mprgp/coupled_face_operators.hpp"

#include "solvers/mprgp/coupled_row_block.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace cb {

CoupledFaceOperators::CoupledFaceOperators(const SpMat& J, const Vec& dinv, const CoupledOperatorOptions& options)
    : CoupledFaceOperators(J, dinv, options, find_row_components(J))
{
}

CoupledFaceOperators::CoupledFaceOperators(const SpMat& J, const Vec& dinv, const CoupledOperatorOptions& options,
                                           RowComponents components)
    : m_opt(options), m_comp(std::move(components))
{
    const Eigen::Index m = J.rows();
    m_s.resize(m);
    for (Eigen::Index i = 0; i < m; ++i) {
        double s = 0.0;
        for (SpMat::InnerIterator it(J, i); it; ++it) s += it.value() * it.value();
        m_s[i] = s;
    }
    m_block_of_component.assign(static_cast<size_t>(m_comp.count()), 0);
    if (m_opt.global) {
        std::vector<int> all(static_cast<size_t>(m));
        std::iota(all.begin(), all.end(), 0);
        if (m > 0) {
            m_blocks.push_back(make_global_block(J, std::move(all), dinv, m_opt));
            ++m_sparse_blocks;
        }
    } else {
        std::vector<double> scatter(static_cast<size_t>(J.cols()), 0.0);
        for (int k = 0; k < m_comp.count(); ++k) {
            std::vector<int> rows(m_comp.rows.begin() + m_comp.start[static_cast<size_t>(k)],
                                  m_comp.rows.begin() + m_comp.start[static_cast<size_t>(k) + 1]);
            m_block_of_component[static_cast<size_t>(k)] = static_cast<int>(m_blocks.size());
            if (static_cast<long>(rows.size()) <= m_opt.dense_max_rows) {
                m_blocks.push_back(make_dense_block(J, std::move(rows), dinv, m_opt, scatter));
                ++m_dense_blocks;
            } else {
                m_blocks.push_back(make_large_block(J, std::move(rows), dinv, m_opt));
                ++m_sparse_blocks;
            }
        }
    }
    m_block_violated.assign(m_blocks.size(), 0);
}

CoupledFaceOperators::~CoupledFaceOperators() = default;

void CoupledFaceOperators::set_face(const std::vector<char>& active, Counters& cnt)
{
    for (auto& b : m_blocks)
        if (b->set_face(active, m_s, cnt) && !b->face().empty()) ++m_face_refactorizations;
}

namespace {

/// Gathers v on the block's face rows into buf (face order).
void gather_face(const RowBlock& b, const Vec& v, std::vector<double>& buf)
{
    const std::vector<int>& face = b.face();
    for (size_t r = 0; r < face.size(); ++r) buf[r] = v[b.rows()[static_cast<size_t>(face[r])]];
}

void scatter_face(const RowBlock& b, const std::vector<double>& buf, Vec& v)
{
    const std::vector<int>& face = b.face();
    for (size_t r = 0; r < face.size(); ++r) v[b.rows()[static_cast<size_t>(face[r])]] = buf[r];
}

// Per-thread workspace sized on first use (the largest block), so the loop does not allocate.
std::vector<double>& workspace(size_t size, int which)
{
    thread_local std::vector<double> buf[3];
    if (buf[which].size() < size) buf[which].resize(size);
    return buf[which];
}

}  // namespace

void CoupledFaceOperators::face_multipliers(const Vec& jg, Vec& nu, Counters& cnt)
{
    nu.setZero();
    for (auto& b : m_blocks) {
        const size_t q = b->face().size();
        if (q == 0) continue;
        std::vector<double>& in = workspace(q, 0);
        std::vector<double>& out = workspace(q, 1);
        gather_face(*b, jg, in);
        b->face_solve(in.data(), out.data(), false, cnt);
        scatter_face(*b, out, nu);
    }
}

void CoupledFaceOperators::jacobi_multipliers(const Vec& jdg, Vec& eta, Counters& cnt)
{
    eta.setZero();
    for (auto& b : m_blocks) {
        const size_t q = b->face().size();
        if (q == 0) continue;
        std::vector<double>& in = workspace(q, 0);
        std::vector<double>& out = workspace(q, 1);
        gather_face(*b, jdg, in);
        b->face_solve(in.data(), out.data(), true, cnt);
        scatter_face(*b, out, eta);
    }
}

void CoupledFaceOperators::chopped_multipliers(const Vec& q, const Vec& nu, Vec& mu, Counters& cnt)
{
    mu.setZero();
    LcpTally tally{m_pgs_fallbacks, m_lcp_solves};
    for (auto& b : m_blocks) {
        const size_t k = b->face().size();
        if (k == 0) continue;
        if (!m_opt.global) {
            // nu >= 0 on the face solves the LCP (q = G_AA nu up to rounding): beta = 0 here.
            bool nonnegative = true;
            for (int r : b->face()) nonnegative = nonnegative && nu[b->rows()[static_cast<size_t>(r)]] >= 0.0;
            if (nonnegative) {
                for (int r : b->face()) mu[b->rows()[static_cast<size_t>(r)]] = nu[b->rows()[static_cast<size_t>(r)]];
                ++m_fast_paths;
                continue;
            }
        }
        std::vector<double>& in = workspace(k, 0);
        std::vector<double>& out = workspace(k, 1);
        gather_face(*b, q, in);
        if (!b->face_lcp(in.data(), out.data(), cnt, tally)) ++m_lcp_failures;
        scatter_face(*b, out, mu);
    }
}

long CoupledFaceOperators::projection_multipliers(Vec& q, const std::vector<char>& violated, Vec& lam, Counters& cnt,
                                                  const std::vector<char>* keep, ProjectionUse use)
{
    lam.setZero();
    const Eigen::Index m = q.size();
    // A component with no violated row keeps lam = 0: clip its q to <= 0 so that the global LCP
    // gives the same answer as the per-component ones.
    std::vector<char>& comp_violated = m_block_violated;  // reused, sized to blocks; components below
    thread_local std::vector<char> by_component;
    by_component.assign(static_cast<size_t>(m_comp.count()), 0);
    for (Eigen::Index i = 0; i < m; ++i)
        if (violated[static_cast<size_t>(i)])
            by_component[static_cast<size_t>(m_comp.of_row[static_cast<size_t>(i)])] = 1;
    std::fill(comp_violated.begin(), comp_violated.end(), 0);
    long solved = 0;
    for (int k = 0; k < m_comp.count(); ++k) {
        if (by_component[static_cast<size_t>(k)]) {
            comp_violated[static_cast<size_t>(m_block_of_component[static_cast<size_t>(k)])] = 1;
            ++solved;
        } else {
            for (int r = m_comp.start[static_cast<size_t>(k)]; r < m_comp.start[static_cast<size_t>(k) + 1]; ++r)
                q[m_comp.rows[static_cast<size_t>(r)]] = std::min(0.0, q[m_comp.rows[static_cast<size_t>(r)]]);
        }
    }
    if (solved == 0) return 0;
    LcpTally tally{m_pgs_fallbacks, m_lcp_solves};
    for (size_t bi = 0; bi < m_blocks.size(); ++bi) {
        if (!comp_violated[bi]) continue;
        RowBlock& b = *m_blocks[bi];
        const size_t k = b.rows().size();
        std::vector<double>& in = workspace(k, 0);
        std::vector<double>& out = workspace(k, 1);
        for (size_t r = 0; r < k; ++r) in[r] = q[b.rows()[r]];
        const char* fixed = nullptr;
        if (keep != nullptr) {
            m_fixed.resize(k);
            for (size_t r = 0; r < k; ++r) m_fixed[r] = (*keep)[static_cast<size_t>(b.rows()[r])];
            fixed = m_fixed.data();
        }
        if (!b.block_lcp(in.data(), out.data(), fixed, static_cast<int>(use), cnt, tally)) ++m_lcp_failures;
        for (size_t r = 0; r < k; ++r) lam[b.rows()[r]] = out[r];
    }
    return solved;
}

nlohmann::json CoupledFaceOperators::stats() const
{
    MaskedFactorTally t;
    for (const auto& b : m_blocks) b->add_tally(t);
    return {{"operators", m_opt.global ? "global" : "components"},
            {"components", m_comp.count()},
            {"largest_component", m_comp.largest()},
            {"singleton_components", m_comp.singletons()},
            {"dense_blocks", m_dense_blocks},
            {"sparse_blocks", m_sparse_blocks},
            {"dense_max_rows", m_opt.dense_max_rows},
            {"face_refactorizations", m_face_refactorizations},
            {"chopped_fast_paths", m_fast_paths},
            {"lcp_solves", m_lcp_solves},
            {"pgs_fallbacks", m_pgs_fallbacks},
            {"lcp_failures", m_lcp_failures},
            {"sparse_refactorizations", t.refactorizations},
            {"sparse_row_additions", t.row_additions},
            {"sparse_row_deletions", t.row_deletions},
            {"sparse_factor_reuses", t.reuses},
            {"sparse_factor_copies", t.copies},
            {"dense_set_solves", t.dense_set_solves},
            {"dense_set_appends", t.dense_set_appends},
            {"dense_set_removals", t.dense_set_removals},
            {"dense_set_rebuilds", t.dense_set_rebuilds}};
}

}  // namespace cb