// Tests of `mprgp-box` (ALGORITHMS.md §5): bounds from signed unit rows (both sides), agreement
// with the active-set reference and with `mprgp`, statuses.
#include "problems/synthetic.hpp"
#include "solvers/core/registry.hpp"
#include "solvers/measure/accuracy.hpp"
#include "solvers/mprgp/mprgp_box.hpp"
#include "tests/solvers/dual_test_problems.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace {

using cb::Qp;
using cb::SolveStatus;

class Monotone : public cb::Monitor {
public:
    explicit Monotone(const Qp& qp) : m_qp(qp) {}
    bool on_iteration(const cb::IterationInfo& info) override
    {
        values.push_back(cb::objective(m_qp.view(), *info.x));
        return true;
    }
    std::vector<double> values;

private:
    const Qp& m_qp;
};

TEST(MprgpBox, BoundRowsAreRecognised)
{
    const Qp box = cb::make_synthetic("box", {{"nx", 3}, {"ny", 3}, {"nz", 3}}, 1);
    EXPECT_TRUE(cb::is_bound_rows(box.J));
    const Qp plane = cb::make_synthetic("plane", {{"nx", 3}, {"ny", 3}, {"nz", 3}}, 1);
    EXPECT_TRUE(cb::is_bound_rows(plane.J));  // normal (0, 1, 0): explicit zeros do not count
    const Qp tilted = cb::make_synthetic("plane", {{"nx", 3}, {"ny", 3}, {"nz", 3}, {"tilt_deg", 10.0}}, 1);
    EXPECT_FALSE(cb::is_bound_rows(tilted.J));
    const cb::SolverResult r = cb::builtin_registry().create("mprgp-box", {})->solve(tilted.view(), {});
    EXPECT_EQ(r.status, SolveStatus::NOT_APPLICABLE);
    EXPECT_NE(r.message.find("nonzeros (bound rows only"), std::string::npos) << r.message;
}

TEST(MprgpBox, AgreesWithActiveSetOnLowerAndUpperBounds)
{
    for (const char* family : {"box", "plane"}) {
        for (std::uint64_t seed : {1u, 2u, 3u}) {
            const Qp qp = cb::make_synthetic(family, {{"nx", 4}, {"ny", 3}, {"nz", 4}}, seed);
            ASSERT_TRUE(cb::is_bound_rows(qp.J));
            bool has_upper = false;
            for (Eigen::Index i = 0; i < qp.m(); ++i)
                for (cb::SpMat::InnerIterator it(qp.J, i); it; ++it) has_upper = has_upper || it.value() < 0.0;
            if (std::string(family) == "box") {
                EXPECT_TRUE(has_upper);
            }
            const cb::SolverResult ref =
                cb::builtin_registry().create("active-set", {{"tol", 1e-12}})->solve(qp.view(), {});
            ASSERT_EQ(ref.status, SolveStatus::CONVERGED) << ref.message;
            const double f_ref = cb::objective(qp.view(), ref.x);
            for (const char* precond : {"jacobi", "none"}) {
                Monotone monitor(qp);
                cb::SolveContext context;
                context.monitor = &monitor;
                const cb::SolverResult r =
                    cb::builtin_registry()
                        .create("mprgp-box", {{"tol", 1e-10}, {"precond", precond}, {"max_iterations", 50000}})
                        ->solve(qp.view(), context);
                ASSERT_EQ(r.status, SolveStatus::CONVERGED) << family << " " << precond << ": " << r.message;
                EXPECT_LE(std::abs(cb::objective(qp.view(), r.x) - f_ref), 1e-8 * std::abs(f_ref)) << family;
                EXPECT_LE(cb::test::relative_kkt(qp, r.x, r.lambda), 1e-8) << family;
                EXPECT_LE(cb::max_violation(qp.view(), r.x), 1e-12);
                for (size_t k = 1; k < monitor.values.size(); ++k)
                    EXPECT_LE(monitor.values[k], monitor.values[k - 1] + 1e-11 * std::abs(monitor.values[k - 1]));
            }
            if (std::string(family) == "plane") {
                const cb::SolverResult m =
                    cb::builtin_registry().create("mprgp", {{"tol", 1e-10}})->solve(qp.view(), {});
                ASSERT_EQ(m.status, SolveStatus::CONVERGED);
                EXPECT_LE(std::abs(cb::objective(qp.view(), m.x) - f_ref), 1e-8 * std::abs(f_ref));
            }
        }
    }
}

TEST(MprgpBox, ContradictoryBoundsAreInfeasibleAndCapsAreReported)
{
    Qp qp;
    qp.A.resize(3, 3);
    qp.A.setIdentity();
    qp.b = cb::Vec::Zero(3);
    qp.x0 = cb::Vec::Zero(3);
    qp.J.resize(2, 3);
    std::vector<cb::Triplet> t = {{0, 1, 1.0}, {1, 1, -1.0}};  // x1 >= 1 and -x1 >= 0
    qp.J.setFromTriplets(t.begin(), t.end());
    qp.c = cb::Vec(2);
    qp.c << 1.0, 0.0;
    const cb::SolverResult r = cb::builtin_registry().create("mprgp-box", {})->solve(qp.view(), {});
    EXPECT_EQ(r.status, SolveStatus::INFEASIBLE);
    EXPECT_NE(r.message.find("DOF 1"), std::string::npos) << r.message;

    const Qp box = cb::make_synthetic("box", {{"nx", 4}, {"ny", 3}, {"nz", 4}}, 4);
    const cb::SolverResult capped =
        cb::builtin_registry().create("mprgp-box", {{"tol", 1e-14}, {"max_iterations", 2}})->solve(box.view(), {});
    EXPECT_EQ(capped.status, SolveStatus::MAX_ITERATIONS);
    EXPECT_EQ(capped.iterations, 2);
}

}  // namespace
