#pragma once
/// Shared by the mprgp-coupled tests (operators, preconditioners): the synthetic coupled scenes
/// with a random extra load, so that the face changes during a solve, and with dependent rows.
#include "solvers/core/qp.hpp"
#include "solvers/measure/accuracy.hpp"

#include <cstdint>
#include <cstdlib>
#include <vector>

namespace cb::coupled_test_qps {

inline double scene_size(const Qp& qp) { return accuracy_scale(qp.view()).length; }

/// The scene with a random extra load, so that some rows separate and others press harder: the
/// face changes during the solve.
inline Qp loaded(Qp qp, std::uint64_t seed)
{
    std::srand(static_cast<unsigned>(seed));
    const Vec push = Vec::Random(qp.n()) * 0.5 * scene_size(qp) / 10.0;
    qp.b += qp.A * push;
    return qp;
}

/// qp with row `row` of J appended again scaled by `factor` (c scaled alike): a dependent row in
/// the same component, so the Gram matrices are singular but for their shift.
inline Qp with_dependent_row(Qp qp, int row, double factor)
{
    std::vector<Triplet> t;
    for (int i = 0; i < qp.J.rows(); ++i)
        for (SpMat::InnerIterator it(qp.J, i); it; ++it) t.emplace_back(i, static_cast<int>(it.col()), it.value());
    const int m = static_cast<int>(qp.J.rows());
    for (SpMat::InnerIterator it(qp.J, row); it; ++it)
        t.emplace_back(m, static_cast<int>(it.col()), factor * it.value());
    SpMat J(m + 1, qp.J.cols());
    J.setFromTriplets(t.begin(), t.end());
    Vec c(m + 1);
    c << qp.c, factor * qp.c[row];
    qp.J = J;
    qp.c = c;
    return qp;
}

}  // namespace cb::coupled_test_qps
