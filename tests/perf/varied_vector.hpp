#pragma once
/// A seeded vector of n entries of both signs and magnitudes from 10^-3 to 10^3 (the product tests' x
/// and w; shared by the product tests of tests/perf).
#include "solvers/core/types.hpp"

#include <cmath>
#include <cstdint>
#include <random>

namespace cb::test {

inline Vec varied(Eigen::Index n, std::uint64_t seed)
{
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    Vec v(n);
    for (Eigen::Index i = 0; i < n; ++i) v[i] = u(rng) * std::pow(10.0, 3.0 * u(rng));
    return v;
}

}  // namespace cb::test
