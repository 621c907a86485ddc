#pragma once
/// Shared by the tests of the factors on row sets (DenseSetFactor, MaskedGramFactor): a random
/// sparse SPD Gram matrix, and the error of a factor's solve against a dense LLT solve on S(set, set).
#include "solvers/core/solver.hpp"
#include "solvers/core/types.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

namespace cb::set_solve_check {

/// A sparse SPD matrix with unit diagonal: B B' scaled, B a random sparse k x 2k matrix of full row rank.
inline SpMatCol random_gram(int k, std::mt19937& rng)
{
    std::uniform_real_distribution<double> val(-1.0, 1.0);
    std::uniform_int_distribution<int> col(0, 2 * k - 1);
    std::vector<Triplet> t;
    for (int i = 0; i < k; ++i) {
        t.emplace_back(i, 2 * i, 1.0);  // full row rank
        for (int e = 0; e < 3; ++e) t.emplace_back(i, col(rng), val(rng));
    }
    SpMat B(k, 2 * static_cast<Eigen::Index>(k));
    B.setFromTriplets(t.begin(), t.end());
    SpMatCol G = SpMatCol(B * B.transpose());
    Vec sc = G.diagonal().cwiseSqrt().cwiseInverse();
    return SpMatCol(sc.asDiagonal() * G * sc.asDiagonal());
}

/// max |x - S(set, set)^-1 b| over the set and |x| off it, for a random b on the set, where x is
/// what `factor.solve(b, counters)` (in place) returns.
template <class Factor>
double solve_error(Factor& factor, const SpMatCol& S, const std::vector<char>& mask, std::mt19937& rng)
{
    const int k = static_cast<int>(S.rows());
    std::vector<int> idx;
    for (int i = 0; i < k; ++i)
        if (mask[static_cast<size_t>(i)]) idx.push_back(i);
    std::uniform_real_distribution<double> val(-1.0, 1.0);
    Vec b = Vec::Zero(k);
    for (int i : idx) b[i] = val(rng);
    const Eigen::MatrixXd dense = Eigen::MatrixXd(S);
    const auto s = static_cast<Eigen::Index>(idx.size());
    Eigen::MatrixXd sub(s, s);
    Vec rhs(s);
    for (Eigen::Index r = 0; r < s; ++r) {
        rhs[r] = b[idx[static_cast<size_t>(r)]];
        for (Eigen::Index c = 0; c < s; ++c)
            sub(r, c) = dense(idx[static_cast<size_t>(r)], idx[static_cast<size_t>(c)]);
    }
    const Vec expect = s == 0 ? Vec() : Vec(sub.llt().solve(rhs));
    Counters cnt;
    factor.solve(b.data(), cnt);
    double err = 0.0;
    for (Eigen::Index r = 0; r < s; ++r) {
        err = std::max(err, std::abs(b[idx[static_cast<size_t>(r)]] - expect[r]));
        b[idx[static_cast<size_t>(r)]] = 0.0;
    }
    return std::max(err, b.lpNorm<Eigen::Infinity>());  // zero off the set
}

}  // namespace cb::set_solve_check
