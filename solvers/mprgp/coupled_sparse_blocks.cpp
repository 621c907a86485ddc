// Sparse blocks of the coupled face operators on CHOLMOD: all rows (the global oracle) or a
// component too large for dense work. LCPs: block principal pivoting (Judice and Pires 1994) with
// Murty's single pivot when the infeasible count stops dropping, warm-started from the last set;
// projected Gauss-Seidel fallback (solvers/mprgp/coupled_sparse_lcp.*).
#include "solvers/mprgp/coupled_row_block.hpp"
#include "solvers/mprgp/coupled_sparse_lcp.hpp"

#include "solvers/linalg/dense_set_factor.hpp"
#include "solvers/measure/work_units.hpp"

#include <Eigen/CholmodSupport>
#include <Eigen/OrderingMethods>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numeric>

namespace cb {

namespace {

// Large components' projection LCP sets of up to this many rows use a dense Cholesky factor kept by
// row appends and deletions (dense_set_factor.hpp): at 128 rows an append or deletion costs ~16k
// flops, about what one of CHOLMOD's row modifications costs on flank_press's 1152-row factor.
constexpr int DENSE_SET_MAX_ROWS = 128;

// The sweep start of an LCP (LargeBlock::sweep_start) is tried on drops of more rows than this and
// than a factor modification takes: its 20 sweeps cost about half a refactorisation, more than
// the few extra row changes that the overshoot of a smaller drop costs.
constexpr long SWEEP_START_MIN_ROWS = 32;
// A cold LCP (no warm set: the first projection of x0) sweeps until the sign pattern has held
// for this many sweeps, at most COLD_SWEEPS_MAX: on flank_press_wide's first projection 20 sweeps
// left 213 rows to drop and 27 LCP steps; sweeping to rest, 4. Warm LCPs gained nothing by it.
constexpr long COLD_SWEEPS_QUIET = 5;
constexpr long COLD_SWEEPS_MAX = 200;

// ---------------------------------------------------------------------------------------------
// Sparse blocks on CHOLMOD: all rows (the global oracle) or a component too large for dense work.

/// The rows `rows` of J, in that order. Rows whose columns increase (as a compressed J's do) are
/// copied straight into the result's arrays: a triplet build costs O(J's columns), 0.75G
/// instructions for a component's two calls on a million DOFs, against O(its nonzeros) here.
SpMat block_rows(const SpMat& J, const std::vector<int>& rows)
{
    SpMat direct(static_cast<Eigen::Index>(rows.size()), J.cols());
    std::vector<int> outer(rows.size() + 1, 0);
    bool sorted = true;
    for (size_t r = 0; r < rows.size() && sorted; ++r) {
        int count = 0;
        Eigen::Index previous = -1;
        for (SpMat::InnerIterator it(J, rows[r]); it; ++it, ++count) {
            sorted = sorted && it.col() > previous;
            previous = it.col();
        }
        outer[r + 1] = outer[r] + count;
    }
    if (sorted) {
        direct.resizeNonZeros(outer.back());
        std::copy(outer.begin(), outer.end(), direct.outerIndexPtr());
        int k = 0;
        for (int row : rows)
            for (SpMat::InnerIterator it(J, row); it; ++it, ++k) {
                direct.innerIndexPtr()[k] = static_cast<int>(it.col());
                direct.valuePtr()[k] = it.value();
            }
        return direct;
    }
    std::vector<Triplet> t;
    for (size_t r = 0; r < rows.size(); ++r)
        for (SpMat::InnerIterator it(J, rows[r]); it; ++it)
            t.emplace_back(static_cast<int>(r), static_cast<int>(it.col()), it.value());
    SpMat JB(static_cast<Eigen::Index>(rows.size()), J.cols());
    JB.setFromTriplets(t.begin(), t.end());
    return JB;
}

/// All rows on CHOLMOD (operators=global, the test oracle): every face and LCP set analysed and
/// factored afresh, as before issue 31.
class SparseBlock final : public RowBlock {
public:
    SparseBlock(const SpMat& J, std::vector<int> rows, const Vec& dinv, const CoupledOperatorOptions& opt)
        : RowBlock(std::move(rows)), m_jacobi(opt.jacobi), m_max_pivots(opt.lcp_max_pivots),
          m_max_sweeps(opt.pgs_max_sweeps)
    {
        const SpMat JB = block_rows(J, m_rows);
        m_gram = SpMatCol(JB * JB.transpose());
        if (m_jacobi) m_gram_d = SpMatCol(JB * dinv.asDiagonal() * JB.transpose());
    }

    void face_solve(const double* rhs, double* out, bool weighted, Counters& cnt) override
    {
        const Eigen::Index q = static_cast<Eigen::Index>(m_face.size());
        SparseFactor& f = weighted ? m_face_factor_d : m_face_factor;
        Eigen::Map<Vec> o(out, q);
        if (!f.ok) {
            o.setZero();
            return;
        }
        o = f.solve(Eigen::Map<const Vec>(rhs, q), cnt);
    }
    bool face_lcp(const double* q, double* mu, Counters& cnt, LcpTally& tally) override
    {
        ++tally.solves;
        const Eigen::Index k = static_cast<Eigen::Index>(m_face.size());
        Vec sol;
        const bool ok = sparse_lcp(m_face_gram, Eigen::Map<const Vec>(q, k), nullptr, m_face_set, sol, cnt,
                                   m_max_pivots, m_max_sweeps, tally.pgs_fallbacks);
        Eigen::Map<Vec>(mu, k) = sol;
        return ok;
    }
    bool block_lcp(const double* q, double* lam, const char* fixed, int /*use*/, Counters& cnt,
                   LcpTally& tally) override
    {
        ++tally.solves;
        const Eigen::Index k = static_cast<Eigen::Index>(m_rows.size());
        Vec sol;
        const bool ok = sparse_lcp(m_gram, Eigen::Map<const Vec>(q, k), fixed, m_proj_set, sol, cnt, m_max_pivots,
                                   m_max_sweeps, tally.pgs_fallbacks);
        Eigen::Map<Vec>(lam, k) = sol;
        return ok;
    }

private:
    void refactor(Counters& cnt) override
    {
        m_face_gram = submatrix(m_gram, m_face);
        m_face_factor.compute(m_face_gram, cnt);
        if (m_jacobi) m_face_factor_d.compute(submatrix(m_gram_d, m_face), cnt);
    }

    bool m_jacobi;
    long m_max_pivots, m_max_sweeps;
    SpMatCol m_gram, m_gram_d, m_face_gram;
    SparseFactor m_face_factor, m_face_factor_d;
};

/// A component too large for dense factors: its rows in AMD order of J_B J_B' (once per solve),
/// its Gram matrices scaled and shifted once, and one masked sparse factor per use (the face,
/// the face's Jacobi Gram, the chopped LCP's set, the projection LCP's set), each modified by
/// row additions and deletions as its set moves (solvers/linalg/masked_gram_factor.hpp). Measured on
/// flank_press frame 0 (1152 rows, one component, 101 iterations): 994 LCP steps, 6332 row
/// modifications, 73 refactorisations, 355 solves on an unchanged set; before (a fresh Eigen
/// simplicial factor per face and per pivot) 945 factorisations with their symbolic analyses.
class LargeBlock final : public RowBlock {
public:
    LargeBlock(const SpMat& J, std::vector<int> rows, const Vec& dinv, const CoupledOperatorOptions& opt)
        : RowBlock(std::move(rows)), m_jacobi(opt.jacobi), m_max_pivots(opt.lcp_max_pivots),
          m_max_sweeps(opt.pgs_max_sweeps), m_max_updates(std::max(1L, opt.sparse_max_updates)),
          m_sweep_start_sweeps(opt.sweep_start_sweeps)
    {
        {
            const SpMat JB = block_rows(J, m_rows);
            const SpMatCol pattern = SpMatCol(JB * JB.transpose());
            Eigen::AMDOrdering<int> amd;
            Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> order;  // order.indices()[new] = old
            amd(pattern, order);
            std::vector<int> reordered(m_rows.size());
            for (size_t k = 0; k < m_rows.size(); ++k)
                reordered[k] = m_rows[static_cast<size_t>(order.indices()[static_cast<Eigen::Index>(k)])];
            m_rows = std::move(reordered);
        }
        const SpMat JB = block_rows(J, m_rows);
        m_gram = SpMatCol(JB * JB.transpose());
        m_gram.makeCompressed();
        const long max_updates = std::max(1L, opt.sparse_max_updates);
        // Rows that join the face join the chopped LCP's start set (RowBlock::set_face): the first
        // face's start is then the whole face, whose solve is nu on the face factor's mask (copied,
        // MaskedGramFactor::set_mask), and the negative rows leave, where an empty start added the
        // rows in blocks of hundreds, each refactored. Rows that stay keep their last state (flank_press
        // frame 0: chopped LCP steps 60 -> 49, row modifications 510 -> 404).
        m_fresh_face_set = 1;
        m_scale = unit_diagonal_scale(m_gram);
        m_scaled = scaled_shifted(m_gram, m_scale);
        // One analysis of the scaled, shifted J_B J_B', copied to the other factors of it.
        m_face_factor = std::make_unique<MaskedGramFactor>(m_scaled, max_updates);
        m_chopped_factor = std::make_unique<MaskedGramFactor>(*m_face_factor, max_updates);
        for (auto& f : m_projection_factors) f = std::make_unique<MaskedGramFactor>(*m_face_factor, max_updates);
        for (auto& set : m_use_sets) set.assign(m_rows.size(), 0);
        if (m_jacobi) {
            const SpMatCol gram_d = SpMatCol(JB * dinv.asDiagonal() * JB.transpose());
            m_scale_d = unit_diagonal_scale(gram_d);
            m_face_factor_d = std::make_unique<MaskedGramFactor>(scaled_shifted(gram_d, m_scale_d), max_updates);
        }
        // The factors of the scaled, shifted J_B J_B' are donors to each other (MaskedGramFactor::set_mask):
        // an expansion's projection set nearly equals the next face, the face the chopped set.
        m_donors = {m_face_factor.get(), m_chopped_factor.get(), m_projection_factors[0].get(),
                    m_projection_factors[1].get(), m_projection_factors[2].get()};
        for (auto& d : m_dense_sets) d = std::make_unique<DenseSetFactor>(m_scaled, DENSE_SET_MAX_ROWS);
        const size_t k = m_rows.size();
        m_all.resize(k);
        std::iota(m_all.begin(), m_all.end(), 0);
        m_mask.assign(k, 0);
        m_b.setZero(static_cast<Eigen::Index>(k));
        m_z.setZero(static_cast<Eigen::Index>(k));
        m_cur.setZero(static_cast<Eigen::Index>(k));
        m_w.setZero(static_cast<Eigen::Index>(k));
        m_y.setZero(static_cast<Eigen::Index>(k));
        m_inv_diag = m_scaled.diagonal().cwiseInverse();
        m_bad.reserve(k);
        m_members.reserve(k);
    }

    void face_solve(const double* rhs, double* out, bool weighted, Counters& cnt) override
    {
        MaskedGramFactor& f = weighted ? *m_face_factor_d : *m_face_factor;
        const Vec& sc = weighted ? m_scale_d : m_scale;
        const size_t q = m_face.size();
        if (weighted && m_face_d_stale) {
            std::fill(m_mask.begin(), m_mask.end(), 0);
            for (int r : m_face) m_mask[static_cast<size_t>(r)] = 1;
            f.set_mask(m_mask, cnt);
            m_face_d_stale = false;
        }
        if (!f.ok()) {
            for (size_t r = 0; r < q; ++r) out[r] = 0.0;
            return;
        }
        m_b.setZero();
        for (size_t r = 0; r < q; ++r) m_b[m_face[r]] = sc[m_face[r]] * rhs[r];
        f.solve(m_b.data(), cnt);
        for (size_t r = 0; r < q; ++r) out[r] = sc[m_face[r]] * m_b[m_face[r]];
    }
    bool face_lcp(const double* q, double* mu, Counters& cnt, LcpTally& tally) override
    {
        return lcp(m_face, q, nullptr, m_face_set, *m_chopped_factor, nullptr, mu, cnt, tally);
    }
    bool block_lcp(const double* q, double* lam, const char* fixed, int use, Counters& cnt, LcpTally& tally) override
    {
        const size_t u = static_cast<size_t>(use);
        return lcp(m_all, q, fixed, m_use_sets[u], *m_projection_factors[u], m_dense_sets[u].get(), lam, cnt, tally);
    }
    void add_tally(MaskedFactorTally& t) const override
    {
        for (const MaskedGramFactor* f :
             {m_face_factor.get(), m_face_factor_d.get(), m_chopped_factor.get(), m_projection_factors[0].get(),
              m_projection_factors[1].get(), m_projection_factors[2].get()}) {
            if (f == nullptr) continue;
            t.refactorizations += f->tally().refactorizations;
            t.row_additions += f->tally().row_additions;
            t.row_deletions += f->tally().row_deletions;
            t.reuses += f->tally().reuses;
            t.copies += f->tally().copies;
        }
        t.dense_set_solves += m_dense_solves;
        for (const auto& d : m_dense_sets) {
            t.dense_set_appends += d->appends();
            t.dense_set_removals += d->removals();
            t.dense_set_rebuilds += d->rebuilds();
        }
    }

private:
    static Vec unit_diagonal_scale(const SpMatCol& G)
    {
        Vec sc(G.rows());
        for (Eigen::Index i = 0; i < G.rows(); ++i) {
            const double d = G.coeff(i, i);
            sc[i] = d > 0.0 ? 1.0 / std::sqrt(d) : 1.0;
        }
        return sc;
    }
    static SpMatCol scaled_shifted(const SpMatCol& G, const Vec& sc)
    {
        SpMatCol S = SpMatCol(sc.asDiagonal() * G * sc.asDiagonal());
        for (Eigen::Index i = 0; i < S.rows(); ++i) S.coeffRef(i, i) += GRAM_SHIFT;
        return S;
    }

    void refactor(Counters& cnt) override
    {
        std::fill(m_mask.begin(), m_mask.end(), 0);
        for (int r : m_face) m_mask[static_cast<size_t>(r)] = 1;
        m_face_factor->set_mask(m_mask, cnt, &m_donors);
        // The weighted factor follows on its first solve: a face that only passes through (the
        // expansion's intermediate face, which needs phi but no z) is never factored weighted.
        m_face_d_stale = m_jacobi;
    }

    /// m_sweep_start_sweeps projected Gauss-Seidel sweeps (`cold`: until no row changed sign in
    /// COLD_SWEEPS_QUIET sweeps, at most COLD_SWEEPS_MAX) over the block rows U = `universe` on the
    /// scaled problem (unit diagonal: lam = scale y), from m_cur (lam >= 0 off the fixed rows, zero
    /// off `set`); then `set` = the fixed rows and those with y > 0, m_cur = lam there (feasible, so
    /// the active-set loop's ratio tests may start from it).
    void sweep_start(const std::vector<int>& universe, const double* q, const char* fixed, std::vector<char>& set,
                     bool cold, Counters& cnt)
    {
        const size_t ku = universe.size();
        // y = 0 off U: a column's sum then needs no test of its rows (a product with y_i = 0 adds an
        // exact zero, and a sum that starts at +0 stays what the tested loop gives, to the bit).
        m_y.setZero();
        for (size_t r = 0; r < ku; ++r) {
            const int j = universe[r];
            m_y[j] = m_cur[j] / m_scale[j];
        }
        const int* outer = m_scaled.outerIndexPtr();
        const int* inner = m_scaled.innerIndexPtr();
        const double* value = m_scaled.valuePtr();
        double touched = 0.0;
        const long most = cold ? COLD_SWEEPS_MAX : m_sweep_start_sweeps;
        long sweeps = 0, quiet = 0;
        for (; sweeps < most && (!cold || quiet < COLD_SWEEPS_QUIET); ++sweeps) {
            long flips = 0;
            for (size_t r = 0; r < ku; ++r) {
                const int j = universe[r];
                // (G y)_j over U (G symmetric: column j is row j)
                const double gy = sparse_column_dot(outer[j], outer[j + 1], inner, value, m_y.data());
                const double next = m_y[j] - (gy - m_scale[j] * q[r]) * m_inv_diag[j];
                const bool was_in = m_y[j] > 0.0;
                m_y[j] = fixed != nullptr && fixed[r] ? next : std::max(0.0, next);
                flips += was_in != (m_y[j] > 0.0);
                touched += outer[j + 1] - outer[j];
            }
            quiet = flips == 0 ? quiet + 1 : 0;
        }
        cnt.work_flops += sparse_product_flops(touched);
        cnt.pgs_sweeps += sweeps;
        for (size_t r = 0; r < ku; ++r) {
            const int j = universe[r];
            set[r] = (fixed != nullptr && fixed[r]) || m_y[j] > 0.0;
            m_cur[j] = set[r] ? m_scale[j] * m_y[j] : 0.0;
        }
    }

    /// m_z = G(S, S)^-1 q_S on the set S (zero off it), with the set's factor modified to S.
    bool solve_on_set(const std::vector<int>& universe, const double* q, const std::vector<char>& set,
                      MaskedGramFactor& f, DenseSetFactor* dense, Counters& cnt)
    {
        std::fill(m_mask.begin(), m_mask.end(), 0);
        m_members.clear();
        for (size_t r = 0; r < universe.size(); ++r)
            if (set[r]) {
                m_mask[static_cast<size_t>(universe[r])] = 1;
                m_members.push_back(static_cast<int>(r));
            }
        const int in = static_cast<int>(m_members.size());
        if (in == 0) {
            // Nothing to factor: z = 0, and the factor stays warm for the next set (flank_press
            // frame 0: 5 refactorisations to the identity before).
            m_z.setZero();
            ++cnt.lcp_iterations;
            return true;
        }
        // A small set on its dense factor; else (or when that factor refuses) the masked sparse one.
        const bool on_dense = dense != nullptr && in <= dense->capacity() && dense->set_mask(m_mask, cnt);
        if (!on_dense && !f.set_mask(m_mask, cnt, &m_donors)) return false;
        m_b.setZero();
        for (int r : m_members)
            m_b[universe[static_cast<size_t>(r)]] = m_scale[universe[static_cast<size_t>(r)]] * q[r];
        if (on_dense) {
            dense->solve(m_b.data(), cnt);
            ++m_dense_solves;
        } else {
            f.solve(m_b.data(), cnt);
        }
        // z on the set only: the loop reads it nowhere else.
        for (int r : m_members) {
            const int j = universe[static_cast<size_t>(r)];
            m_z[j] = m_scale[j] * m_b[j];
        }
        ++cnt.lcp_iterations;
        return true;
    }

    /// 0 <= lam perp G(U, U) lam - q >= 0 over the block rows U = `universe`, warm-started from
    /// `set` (per U row): a primal active-set method (Lawson and Hanson's NNLS loop on the convex
    /// QP min 1/2 lam'G lam - q'lam, lam >= 0) that keeps lam feasible and F decreasing, so a
    /// set moves by the rows that really enter or leave and each move is a row modification
    /// of the set's factor. Block principal pivoting, which flips every infeasible row at once,
    /// cycled here: on flank_press frame 0 it took 946 pivots and 8933 row flips (Murty's single
    /// flips ran up to 71 pivots in one LCP). Rows flagged in `fixed` are equalities (lam of
    /// either sign, never leave). At most lcp_max_pivots + 2 |U| steps, then PGS.
    /// `dense` (may be null): the set's dense factor, used while the set has at most its capacity rows.
    bool lcp(const std::vector<int>& universe, const double* q, const char* fixed, std::vector<char>& set,
             MaskedGramFactor& f, DenseSetFactor* dense, double* lam, Counters& cnt, LcpTally& tally)
    {
        ++tally.solves;
        const size_t ku = universe.size();
        for (size_t r = 0; r < ku; ++r) lam[r] = 0.0;
        if (ku == 0) return true;
        if (set.size() != ku) set.assign(ku, 0);
        auto is_fixed = [&](size_t r) { return fixed != nullptr && fixed[r] != 0; };
        double qinf = 0.0;
        for (size_t r = 0; r < ku; ++r) {
            if (is_fixed(r)) set[r] = 1;
            qinf = std::max(qinf, std::abs(q[r]));
        }
        const double tol_w = 1e-12 * std::max(1.0, qinf);
        m_added.assign(ku, 0);
        bool cold = true;  // no warm set: the first LCP of this use
        for (size_t r = 0; r < ku && cold; ++r) cold = !set[r] || (fixed != nullptr && fixed[r]);
        // A feasible start from the warm set: the set's solution with its negative rows dropped.
        m_cur.setZero();
        bool solved = solve_on_set(universe, q, set, f, dense, cnt);
        bool dropped = false;  // else m_z is already the first step's solve on the same set
        long leaving = 0;
        if (solved) {
            for (size_t r = 0; r < ku; ++r) {
                if (!set[r]) continue;
                const int j = universe[r];
                if (is_fixed(r) || m_z[j] > 0.0) {
                    m_cur[j] = m_z[j];
                } else {
                    set[r] = 0;
                    dropped = true;
                    ++leaving;
                }
            }
        }
        // At most once per LCP, a drop of more rows than a factor modification takes: dropping every
        // negative row of the set's solution overshoots on strongly coupled rows (their neighbours
        // then come back, for a dozen steps of hundreds of row changes on flank_press's cold
        // projection); projected Gauss-Seidel sweeps from the clipped solution land near the final
        // set, at about a fortieth of a refactorisation a sweep.
        bool swept = m_sweep_start_sweeps <= 0;
        auto sweep_if_far = [&]() {
            if (swept || leaving <= std::max(m_max_updates, SWEEP_START_MIN_ROWS)) return;
            swept = true;
            sweep_start(universe, q, fixed, set, cold, cnt);
        };
        sweep_if_far();
        // Blocks of rows leave (every negative one) and enter (every one with w < 0) while the
        // objective at the set minimisers decreases; after a step that did not, or an addition undone
        // at once, the method goes careful: ratio tests and one entering row at a time (finite).
        bool careful = false;
        double best_f = std::numeric_limits<double>::infinity();
        const long max_steps = m_max_pivots + 2 * static_cast<long>(ku);
        for (long step = 0; solved && step < max_steps; ++step) {
            if ((step > 0 || dropped) && !(solved = solve_on_set(universe, q, set, f, dense, cnt))) break;
            // The set's rows (m_members, ascending, as solved): a step's passes go over them, not
            // over all of U (the in-loop projections' sets hold 10-100 of flank_press's 1152 rows).
            double zinf = 0.0;
            for (int r : m_members) zinf = std::max(zinf, std::abs(m_z[universe[static_cast<size_t>(r)]]));
            const double tol_l = 1e-12 * std::max(1e-300, zinf);
            // Ratio test: the longest step from m_cur towards z that keeps lam >= 0.
            double alpha = 1.0;
            bool blocked = false;
            for (int rr : m_members) {
                const size_t r = static_cast<size_t>(rr);
                const int j = universe[r];
                if (is_fixed(r) || !(m_z[j] < -tol_l)) continue;
                alpha = std::min(alpha, m_cur[j] / (m_cur[j] - m_z[j]));
                blocked = true;
            }
            if (blocked && !careful) {
                leaving = 0;
                for (int rr : m_members) {
                    const size_t r = static_cast<size_t>(rr);
                    const int j = universe[r];
                    if (!is_fixed(r) && m_z[j] < -tol_l) {
                        set[r] = 0;
                        m_cur[j] = 0.0;
                        ++leaving;
                    } else {
                        m_cur[j] = is_fixed(r) ? m_z[j] : std::max(0.0, m_z[j]);
                    }
                }
                sweep_if_far();
                continue;
            }
            if (blocked) {
                bool undid_addition = false;
                for (int rr : m_members) {
                    const size_t r = static_cast<size_t>(rr);
                    const int j = universe[r];
                    m_cur[j] += alpha * (m_z[j] - m_cur[j]);
                    if (!is_fixed(r) && m_z[j] < -tol_l && m_cur[j] <= tol_l) {
                        set[r] = 0;
                        m_cur[j] = 0.0;
                        undid_addition = undid_addition || (m_added[r] && alpha == 0.0);
                    }
                }
                careful = careful || undid_addition;
                continue;
            }
            // z >= 0 on the set: the minimiser there. Rows off the set with w < 0 enter.
            for (int rr : m_members) {
                const size_t r = static_cast<size_t>(rr);
                m_cur[universe[r]] = is_fixed(r) ? m_z[universe[r]] : std::max(0.0, m_z[universe[r]]);
            }
            // w = G cur over the columns of the set only (cur is zero off it; U ascending, so the
            // same sums in the same order as the full product).
            m_w.setZero();
            long touched = 0;
            for (int rr : m_members) {
                const int j = universe[static_cast<size_t>(rr)];
                const double cj = m_cur[j];
                if (cj == 0.0) continue;
                for (SpMatCol::InnerIterator it(m_gram, j); it; ++it) m_w[it.index()] += it.value() * cj;
                touched += m_gram.outerIndexPtr()[j + 1] - m_gram.outerIndexPtr()[j];
            }
            cnt.work_flops += sparse_product_flops(static_cast<double>(touched));
            double f_set = 0.0;  // 1/2 lam'G lam - q'lam
            for (int r : m_members)
                f_set += m_cur[universe[static_cast<size_t>(r)]] * (0.5 * m_w[universe[static_cast<size_t>(r)]] - q[r]);
            careful = careful || !(f_set < best_f);
            best_f = std::min(best_f, f_set);
            const bool single = careful;
            std::fill(m_added.begin(), m_added.end(), 0);
            size_t worst = ku;
            double worst_w = -tol_w;
            bool entered = false;
            for (size_t r = 0; r < ku; ++r) {
                if (set[r]) continue;
                const double w = m_w[universe[r]] - q[r];
                if (!(w < -tol_w)) continue;
                if (!single) {
                    set[r] = m_added[r] = 1;
                    entered = true;
                } else if (w < worst_w) {
                    worst_w = w;
                    worst = r;
                }
            }
            if (single && worst < ku) {
                set[worst] = m_added[worst] = 1;
                entered = true;
            }
            if (!entered) {
                for (size_t r = 0; r < ku; ++r) lam[r] = m_cur[universe[r]];
                return true;
            }
        }
        ++tally.pgs_fallbacks;
        const SpMatCol M = submatrix(m_gram, universe);
        Vec lambda(static_cast<Eigen::Index>(ku));
        for (size_t r = 0; r < ku; ++r) lambda[static_cast<Eigen::Index>(r)] = m_cur[universe[r]];
        const bool ok = projected_gauss_seidel(M, Eigen::Map<const Vec>(q, static_cast<Eigen::Index>(ku)), fixed, set,
                                               lambda, cnt, m_max_sweeps);
        Eigen::Map<Vec>(lam, static_cast<Eigen::Index>(ku)) = lambda;
        return ok;
    }

    bool m_jacobi;
    long m_max_pivots, m_max_sweeps;
    long m_max_updates;  // a set change of more rows refactors; a drop of more picks the set by sweeps
    long m_sweep_start_sweeps;
    SpMatCol m_gram;  // J_B J_B' in block order, unscaled
    Vec m_scale, m_scale_d;
    std::unique_ptr<MaskedGramFactor> m_face_factor, m_face_factor_d, m_chopped_factor;
    std::array<std::unique_ptr<MaskedGramFactor>, PROJECTION_USES> m_projection_factors;
    std::array<std::vector<char>, PROJECTION_USES> m_use_sets;
    std::vector<const MaskedGramFactor*> m_donors;
    SpMatCol m_scaled;            // the scaled, shifted J_B J_B' (the dense set factors read it)
    bool m_face_d_stale = false;  // m_face_factor_d not yet on the current face
    std::array<std::unique_ptr<DenseSetFactor>, PROJECTION_USES> m_dense_sets;
    long m_dense_solves = 0;
    std::vector<int> m_all, m_bad;
    std::vector<int> m_members;  // solve_on_set: the set's U positions, ascending
    std::vector<char> m_mask, m_added;
    Vec m_b, m_z, m_cur, m_w;
    Vec m_y, m_inv_diag;  // sweep_start's scaled iterate (0 off its universe) and 1 / diag(m_scaled)
};

}  // namespace

std::unique_ptr<RowBlock> make_global_block(const SpMat& J, std::vector<int> rows, const Vec& dinv,
                                            const CoupledOperatorOptions& opt)
{
    return std::make_unique<SparseBlock>(J, std::move(rows), dinv, opt);
}

std::unique_ptr<RowBlock> make_large_block(const SpMat& J, std::vector<int> rows, const Vec& dinv,
                                           const CoupledOperatorOptions& opt)
{
    return std::make_unique<LargeBlock>(J, std::move(rows), dinv, opt);
}

}  // namespace cb
