// The sparse blocks' LCPs (solvers/mprgp/coupled_sparse_lcp.hpp).
#include "solvers/mprgp/coupled_sparse_lcp.hpp"

#include "solvers/measure/work_units.hpp"
#include "solvers/mprgp/coupled_row_block.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace cb {

SpMatCol submatrix(const SpMatCol& M, const std::vector<int>& idx)
{
    std::vector<int> local(static_cast<size_t>(M.rows()), -1);
    for (size_t k = 0; k < idx.size(); ++k) local[static_cast<size_t>(idx[k])] = static_cast<int>(k);
    std::vector<Triplet> t;
    for (size_t k = 0; k < idx.size(); ++k)
        for (SpMatCol::InnerIterator it(M, idx[k]); it; ++it)
            if (local[static_cast<size_t>(it.row())] >= 0)
                t.emplace_back(local[static_cast<size_t>(it.row())], static_cast<int>(k), it.value());
    SpMatCol S(static_cast<Eigen::Index>(idx.size()), static_cast<Eigen::Index>(idx.size()));
    S.setFromTriplets(t.begin(), t.end());
    return S;
}

bool SparseFactor::compute(const SpMatCol& S, Counters& cnt)
{
    scale.resize(S.rows());
    for (Eigen::Index i = 0; i < S.rows(); ++i) {
        const double d = S.coeff(i, i);
        scale[i] = d > 0.0 ? 1.0 / std::sqrt(d) : 1.0;
    }
    const SpMatCol scaled = SpMatCol(scale.asDiagonal() * S * scale.asDiagonal());
    chol = std::make_unique<Cholmod>();
    chol->setShift(GRAM_SHIFT);
    chol->compute(scaled);
    ++cnt.cholmod_analyses;
    ++cnt.cholmod_factorizations;
    cnt.work_flops += cholmod_factor_flops(chol->cholmod());
    ok = chol->info() == Eigen::Success;
    return ok;
}

Vec SparseFactor::solve(const Vec& rhs, Counters& cnt)
{
    ++cnt.cholmod_solves;
    cnt.work_flops += cholmod_solve_flops(chol->cholmod());
    return scale.cwiseProduct(Vec(chol->solve(Vec(scale.cwiseProduct(rhs)))));
}

bool projected_gauss_seidel(const SpMatCol& M, const Vec& q, const char* fixed, std::vector<char>& set, Vec& lambda,
                            Counters& cnt, long max_sweeps)
{
    const Eigen::Index k = q.size();
    auto is_fixed = [&](Eigen::Index i) { return fixed != nullptr && fixed[i] != 0; };
    for (Eigen::Index i = 0; i < k; ++i)
        if (!is_fixed(i)) lambda[i] = std::max(0.0, lambda[i]);
    const Vec diag = M.diagonal();
    for (long sweep = 0; sweep < max_sweeps; ++sweep) {
        double change = 0.0;
        for (Eigen::Index i = 0; i < k; ++i) {
            if (!(diag[i] > 0.0)) continue;
            double mi = 0.0;
            for (SpMatCol::InnerIterator it(M, i); it; ++it) mi += it.value() * lambda[it.row()];  // symmetric
            const double step = lambda[i] - (mi - q[i]) / diag[i];
            const double next = is_fixed(i) ? step : std::max(0.0, step);
            change = std::max(change, std::abs(next - lambda[i]));
            lambda[i] = next;
        }
        ++cnt.pgs_sweeps;
        ++cnt.lcp_iterations;
        cnt.work_flops += sparse_product_flops(static_cast<double>(M.nonZeros()));
        if (change <= 1e-14 * std::max(1.0, lambda.lpNorm<Eigen::Infinity>())) break;
    }
    Vec w = M * lambda - q;
    for (Eigen::Index i = 0; i < k; ++i) {
        set[static_cast<size_t>(i)] = lambda[i] > 0.0 || is_fixed(i);
        if (is_fixed(i)) w[i] = -std::abs(w[i]);
    }
    return w.minCoeff() >= -1e-8 * std::max(1.0, q.lpNorm<Eigen::Infinity>());
}

void flip_infeasible(const std::vector<int>& bad, std::vector<char>& set, long& best, int& chances)
{
    const long count = static_cast<long>(bad.size());
    if (count < best) {
        best = count;
        chances = 3;
        for (int i : bad) set[static_cast<size_t>(i)] ^= 1;
    } else if (chances > 0) {
        --chances;
        for (int i : bad) set[static_cast<size_t>(i)] ^= 1;
    } else {
        set[static_cast<size_t>(bad.back())] ^= 1;  // Murty: finite for P-matrices
    }
}

bool sparse_lcp(const SpMatCol& M, const Vec& q, const char* fixed, std::vector<char>& set, Vec& lambda, Counters& cnt,
                long max_pivots, long max_sweeps, long& pgs_fallbacks)
{
    const Eigen::Index k = q.size();
    lambda = Vec::Zero(k);
    if (k == 0) return true;
    if (static_cast<Eigen::Index>(set.size()) != k) set.assign(static_cast<size_t>(k), 0);
    auto is_fixed = [&](Eigen::Index i) { return fixed != nullptr && fixed[i] != 0; };
    for (Eigen::Index i = 0; i < k; ++i)
        if (is_fixed(i)) set[static_cast<size_t>(i)] = 1;
    const double tol_w = 1e-12 * std::max(1.0, q.lpNorm<Eigen::Infinity>());
    long best = std::numeric_limits<long>::max();
    int chances = 3;
    for (long it = 0; it < max_pivots; ++it) {
        std::vector<int> idx;
        for (Eigen::Index i = 0; i < k; ++i)
            if (set[static_cast<size_t>(i)]) idx.push_back(static_cast<int>(i));
        lambda.setZero();
        if (!idx.empty()) {
            SparseFactor f;
            if (!f.compute(submatrix(M, idx), cnt)) break;
            Vec rhs(static_cast<Eigen::Index>(idx.size()));
            for (size_t r = 0; r < idx.size(); ++r) rhs[static_cast<Eigen::Index>(r)] = q[idx[r]];
            const Vec sol = f.solve(rhs, cnt);
            for (size_t r = 0; r < idx.size(); ++r) lambda[idx[r]] = sol[static_cast<Eigen::Index>(r)];
        }
        ++cnt.lcp_iterations;
        const Vec w = M * lambda - q;
        cnt.work_flops += sparse_product_flops(static_cast<double>(M.nonZeros()));
        const double tol_l = 1e-12 * std::max(1e-300, lambda.lpNorm<Eigen::Infinity>());
        std::vector<int> bad;
        for (Eigen::Index i = 0; i < k; ++i) {
            if (!is_fixed(i) && (set[static_cast<size_t>(i)] ? lambda[i] < -tol_l : w[i] < -tol_w))
                bad.push_back(static_cast<int>(i));
        }
        if (bad.empty()) {
            for (Eigen::Index i = 0; i < k; ++i)
                if (!is_fixed(i)) lambda[i] = std::max(0.0, lambda[i]);
            return true;
        }
        flip_infeasible(bad, set, best, chances);
    }
    ++pgs_fallbacks;
    return projected_gauss_seidel(M, q, fixed, set, lambda, cnt, max_sweeps);
}

}  // namespace cb
