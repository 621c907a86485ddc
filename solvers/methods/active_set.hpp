#pragma once
/// `active-set`: the reference solver (ALGORITHMS.md §8). A Goldfarb-Idnani dual active-set
/// method on a CHOLMOD factor of A, with a dense Cholesky factor of the working-set Schur
/// complement S_W = J_W A^-1 J_W' updated as rows enter (append) and leave (Givens).
/// It starts from the unconstrained minimiser A^-1 b, so it needs no feasible start and it
/// detects an empty feasible set (status INFEASIBLE). At the end the equality QP on the final
/// working set is polished by iterative refinement.
/// Ref: D. Goldfarb, A. Idnani, "A numerically stable dual method for solving strictly convex
/// quadratic programs", Math. Programming 27 (1983) 1-33; Nocedal-Wright, Numerical
/// Optimization, 2nd ed., Sec. 16.5 (Schur-complement form of the KKT system).
#include "solvers/core/registry.hpp"
#include "solvers/core/settings.hpp"
#include "solvers/core/solver.hpp"

#include <Eigen/Dense>
#include <vector>

namespace cb {

/// active-set's default tol: the reference accuracy (harness/reference.cpp judges every other
/// solver's answer against this one, so its error sits far below their common 1e-6).
constexpr double ACTIVE_SET_DEFAULT_TOL = 1e-10;

struct ActiveSetSettings {
    CommonSettings common = CommonSettings{}.with_tol(ACTIVE_SET_DEFAULT_TOL);
    long monitor_every = 1;         ///< call the monitor every k-th pivot (0: only start and end);
                                    ///< each call costs one (untimed) solve to form x
    long polish_rounds = 4;         ///< iterative-refinement rounds on the final working set
    double dependency_tol = 1e-10;  ///< a row is dependent on the working set when its Schur
                                    ///< pivot is <= dependency_tol * (J_p A^-1 J_p')

    static ActiveSetSettings from_json(const nlohmann::json& settings);  ///< throws InputError
    nlohmann::json to_json() const;
};

/// Dense lower Cholesky factor L (S = L L') of a small SPD matrix that grows by one row and
/// column at a time and loses arbitrary ones. O(q^2) per change.
class GrowingCholesky {
public:
    int size() const { return m_size; }
    /// The factor L (a copy; for tests and diagnostics).
    Eigen::MatrixXd factor() const { return m_buffer.topLeftCorner(m_size, m_size); }
    /// Solves L y = d (forward substitution).
    Vec forward(const Vec& d) const;
    /// Solves L' r = y (back substitution).
    Vec backward(const Vec& y) const;
    /// Solves S r = d.
    Vec solve(const Vec& d) const { return backward(forward(d)); }
    /// Appends a row/column with forward part l = L^-1 (S new column) and pivot^2 > 0.
    void append(const Vec& l, double pivot_squared);
    /// Removes row/column k, restoring the triangle with Givens rotations.
    void remove(int k);
    void clear() { m_size = 0; }

private:
    Eigen::MatrixXd m_buffer;  ///< capacity x capacity; L is its leading m_size block
    int m_size = 0;
};

class ActiveSetSolver final : public Solver {
public:
    explicit ActiveSetSolver(const ActiveSetSettings& settings) : m_settings(settings) {}
    std::string name() const override { return "active-set"; }
    nlohmann::json settings() const override { return m_settings.to_json(); }
    SolverResult solve(const QpView& qp, const SolveContext& context) override;

private:
    ActiveSetSettings m_settings;
};

/// Registry entry (factory, description, setting docs) for builtin_solvers.cpp.
SolverEntry active_set_entry();

}  // namespace cb
