// A masked sparse LDL' factor kept by row additions and deletions (masked_gram_factor.hpp).
// Ref: Davis and Hager, SIMAX 26(3) 2005 (CHOLMOD's Modify module: cholmod_rowadd, cholmod_rowdel).
#include "solvers/linalg/masked_gram_factor.hpp"

#include <algorithm>
#include <stdexcept>

namespace cb {

namespace {
/// A copy of L (one memcpy of ~lnz entries) costs about as much as this many row changes
/// (flank_press's 1152-row component: copy ~40 us, a row addition or deletion ~6 us).
constexpr long COPY_IN_ROW_CHANGES = 8;
}  // namespace

MaskedGramFactor::MaskedGramFactor(const SpMatCol& S, long max_updates)
    : m_k(static_cast<int>(S.rows())), m_max_updates(max_updates), m_S(S)
{
    m_S.makeCompressed();
    allocate();
    // The symbolic analysis of the whole S: every masked pattern is a subset of it.
    fill_lower(true);
    m_L = cholmod_analyze(m_masked, &m_cm);
    if (m_L == nullptr) throw std::runtime_error("MaskedGramFactor: CHOLMOD's analysis failed");
    m_factor_flops = m_cm.fl;
    m_lnz = m_cm.lnz;
}

MaskedGramFactor::MaskedGramFactor(const MaskedGramFactor& twin, long max_updates)
    : m_k(twin.m_k), m_max_updates(max_updates), m_S(twin.m_S)
{
    if (twin.m_factored) throw std::logic_error("MaskedGramFactor: the twin must not be factored yet");
    allocate();
    // A symbolic factor's copy is its pattern and ordering (no values): what the analysis gives.
    m_L = cholmod_copy_factor(twin.m_L, &m_cm);
    if (m_L == nullptr) throw std::runtime_error("MaskedGramFactor: CHOLMOD could not copy the analysis");
    m_factor_flops = twin.m_factor_flops;
    m_lnz = twin.m_lnz;
}

void MaskedGramFactor::allocate()
{
    m_mask.assign(static_cast<size_t>(m_k), 0);
    cholmod_start(&m_cm);
    // The caller's order (AMD once per block), no postorder: row k of the factor is row k of S,
    // which is what cholmod_rowadd / cholmod_rowdel index. LDL', simplicial: what Modify needs.
    m_cm.nmethods = 1;
    m_cm.method[0].ordering = CHOLMOD_NATURAL;
    m_cm.postorder = 0;
    m_cm.supernodal = CHOLMOD_SIMPLICIAL;
    m_cm.final_ll = 0;
    m_cm.quick_return_if_not_posdef = 1;

    long lower = 0;
    for (int j = 0; j < m_k; ++j)
        for (SpMatCol::InnerIterator it(m_S, j); it; ++it) lower += it.row() >= j;
    m_masked = cholmod_allocate_sparse(static_cast<size_t>(m_k), static_cast<size_t>(m_k),
                                       static_cast<size_t>(std::max(1L, lower)), 1, 1, -1, CHOLMOD_REAL, &m_cm);
    long widest = 1;
    for (int j = 0; j < m_k; ++j) widest = std::max(widest, static_cast<long>(m_S.col(j).nonZeros()));
    m_column =
        cholmod_allocate_sparse(static_cast<size_t>(m_k), 1, static_cast<size_t>(widest), 1, 1, 0, CHOLMOD_REAL, &m_cm);
    m_b = cholmod_zeros(static_cast<size_t>(m_k), 1, CHOLMOD_REAL, &m_cm);
    if (m_masked == nullptr || m_column == nullptr || m_b == nullptr)
        throw std::runtime_error("MaskedGramFactor: CHOLMOD could not allocate its workspace");
}

MaskedGramFactor::~MaskedGramFactor()
{
    cholmod_free_factor(&m_L, &m_cm);
    cholmod_free_sparse(&m_masked, &m_cm);
    cholmod_free_sparse(&m_column, &m_cm);
    cholmod_free_dense(&m_b, &m_cm);
    cholmod_free_dense(&m_x, &m_cm);
    cholmod_free_dense(&m_y, &m_cm);
    cholmod_free_dense(&m_e, &m_cm);
    cholmod_finish(&m_cm);
}

void MaskedGramFactor::fill_lower(bool whole)
{
    int* p = static_cast<int*>(m_masked->p);
    int* ri = static_cast<int*>(m_masked->i);
    double* v = static_cast<double*>(m_masked->x);
    auto kept = [&](Eigen::Index row) { return whole || m_mask[static_cast<size_t>(row)] != 0; };
    int nz = 0;
    for (int j = 0; j < m_k; ++j) {
        p[j] = nz;
        if (!kept(j)) {
            ri[nz] = j;  // an identity row: its solve returns the (zero) right-hand side
            v[nz++] = 1.0;
            continue;
        }
        for (SpMatCol::InnerIterator it(m_S, j); it; ++it)
            if (it.row() >= j && kept(it.row())) {
                ri[nz] = static_cast<int>(it.row());
                v[nz++] = it.value();
            }
    }
    p[m_k] = nz;
    m_masked->nzmax = std::max<size_t>(m_masked->nzmax, static_cast<size_t>(nz));
}

bool MaskedGramFactor::refactor(Counters& cnt)
{
    fill_lower(false);
    const int status = cholmod_factorize(m_masked, m_L, &m_cm);
    ++m_tally.refactorizations;
    ++cnt.cholmod_factorizations;
    cnt.work_flops += m_factor_flops;
    m_ok = status != 0 && m_cm.status == CHOLMOD_OK;
    return m_ok;
}

long MaskedGramFactor::distance(const std::vector<char>& mask) const
{
    if (!m_factored || !m_ok) return static_cast<long>(m_k) + 1;
    long changes = 0;
    for (int j = 0; j < m_k; ++j)
        changes += (mask[static_cast<size_t>(j)] != 0) != (m_mask[static_cast<size_t>(j)] != 0);
    return changes;
}

bool MaskedGramFactor::set_mask(const std::vector<char>& mask, Counters& cnt,
                                const std::vector<const MaskedGramFactor*>* donors)
{
    long changes = distance(mask);
    if (changes == 0) {
        ++m_tally.reuses;
        return true;
    }
    if (changes > COPY_IN_ROW_CHANGES && donors != nullptr) {
        // A warm factor elsewhere (the face's for the chopped set, another use's projection set)
        // saves the refactorisation or most row changes: copy it, then modify it row by row below.
        const MaskedGramFactor* nearest = nullptr;
        long nearest_changes = std::min(changes - COPY_IN_ROW_CHANGES, m_max_updates + 1);
        for (const MaskedGramFactor* d : *donors) {
            if (d == nullptr || d == this || d->m_k != m_k) continue;
            const long c = d->distance(mask);
            if (c < nearest_changes) {
                nearest = d;
                nearest_changes = c;
            }
        }
        if (nearest != nullptr) {
            cholmod_factor* copy = cholmod_copy_factor(nearest->m_L, &m_cm);
            if (copy != nullptr) {
                cholmod_free_factor(&m_L, &m_cm);
                m_L = copy;
                m_mask = nearest->m_mask;
                m_factored = m_ok = true;
                changes = nearest_changes;
                ++m_tally.copies;
                cnt.work_flops += m_lnz;  // the copy: one pass over L
                if (changes == 0) return true;
            }
        }
    }
    if (!m_factored || !m_ok || changes > m_max_updates) {
        for (int j = 0; j < m_k; ++j) m_mask[static_cast<size_t>(j)] = mask[static_cast<size_t>(j)] != 0;
        m_factored = true;
        return refactor(cnt);
    }
    // Deletions first (the factor shrinks), then additions, each against the current mask.
    const double modify_flops = 4.0 * m_lnz;  // bound: a rank-2 modification touches at most all of L
    for (int j = 0; j < m_k && m_ok; ++j) {
        if (m_mask[static_cast<size_t>(j)] && !mask[static_cast<size_t>(j)]) {
            m_ok = cholmod_rowdel(static_cast<size_t>(j), nullptr, m_L, &m_cm) != 0 && m_cm.status == CHOLMOD_OK;
            m_mask[static_cast<size_t>(j)] = 0;
            ++m_tally.row_deletions;
            cnt.work_flops += modify_flops;
        }
    }
    for (int j = 0; j < m_k && m_ok; ++j) {
        if (!m_mask[static_cast<size_t>(j)] && mask[static_cast<size_t>(j)]) {
            m_mask[static_cast<size_t>(j)] = 1;
            int* ri = static_cast<int*>(m_column->i);
            double* v = static_cast<double*>(m_column->x);
            int nz = 0;
            for (SpMatCol::InnerIterator it(m_S, j); it; ++it)
                if (m_mask[static_cast<size_t>(it.row())]) {
                    ri[nz] = static_cast<int>(it.row());
                    v[nz++] = it.value();
                }
            static_cast<int*>(m_column->p)[0] = 0;
            static_cast<int*>(m_column->p)[1] = nz;
            m_ok = cholmod_rowadd(static_cast<size_t>(j), m_column, m_L, &m_cm) != 0 && m_cm.status == CHOLMOD_OK;
            ++m_tally.row_additions;
            cnt.work_flops += modify_flops;
        }
    }
    if (m_ok) {
        // A rank-2 modification may meet a pivot <= 0 without failing (it keeps the factor); check D.
        const int* lp = static_cast<const int*>(m_L->p);
        const double* lx = static_cast<const double*>(m_L->x);
        for (int j = 0; j < m_k && m_ok; ++j) m_ok = lx[lp[j]] > 0.0;
    }
    if (!m_ok) {
        for (int j = 0; j < m_k; ++j) m_mask[static_cast<size_t>(j)] = mask[static_cast<size_t>(j)] != 0;
        return refactor(cnt);
    }
    return true;
}

void MaskedGramFactor::solve(double* b, Counters& cnt)
{
    double* bx = static_cast<double*>(m_b->x);
    for (int j = 0; j < m_k; ++j) bx[j] = b[j];
    if (cholmod_solve2(CHOLMOD_A, m_L, m_b, nullptr, &m_x, nullptr, &m_y, &m_e, &m_cm) == 0 || m_x == nullptr) {
        for (int j = 0; j < m_k; ++j) b[j] = 0.0;
        m_ok = false;
        return;
    }
    const double* x = static_cast<const double*>(m_x->x);
    for (int j = 0; j < m_k; ++j) b[j] = m_mask[static_cast<size_t>(j)] ? x[j] : 0.0;
    ++cnt.cholmod_solves;
    cnt.work_flops += 4.0 * m_lnz;
}

}  // namespace cb
