// `mprgp-coupled` runs the chopped gradient's LCP only when a decision needs it (ALGORITHMS.md §4):
// the proportioning test is first tried on upper bounds of beta'beta, the convergence test on a
// lower bound of the accuracy error, and a monitor gets the exact multipliers from notify's
// prepare. Checked here: a monitor that reads the iterate (and so has the LCP solved every
// iteration) and one that does not see the same step kinds and the same solution; the multipliers
// and native residual the monitor sees are the exact ones (||A x - b - J'lambda||); the deferral
// really happens on a 196-row component (above dense_max_rows).
#include "problems/synthetic.hpp"
#include "solvers/core/registry.hpp"
#include "solvers/linalg/row_components.hpp"
#include "solvers/measure/accuracy.hpp"
#include "tests/solvers/coupled_test_qps.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>

namespace {

using cb::Qp;
using cb::SolveStatus;
using cb::Vec;

/// Step kinds only: wants_iterate() false, so the solver skips the monitor's preparation.
class ChoppedStepRecorder : public cb::Monitor {
public:
    bool on_iteration(const cb::IterationInfo& info) override
    {
        steps.push_back(info.step);
        return true;
    }
    bool wants_iterate() const override { return false; }
    std::vector<cb::StepKind> steps;
};

/// Step kinds and the largest gap between the native residual shown and ||W (A x - b - J'lambda)||
/// (W = I, or D^-1/2 with precond = scaled: the solver's own residual is that of y = D^1/2 x).
class ResidualRecorder : public cb::Monitor {
public:
    ResidualRecorder(const Qp& qp, const std::string& precond)
        : m_qp(qp),
          m_weight(precond == "scaled" ? Vec(qp.A.diagonal().cwiseSqrt().cwiseInverse()) : Vec(Vec::Ones(qp.n())))
    {
    }
    bool on_iteration(const cb::IterationInfo& info) override
    {
        steps.push_back(info.step);
        if (info.x == nullptr || info.lambda == nullptr) {
            ++missing;
            return true;
        }
        const Vec r = m_weight.cwiseProduct(m_qp.A * *info.x - m_qp.b - m_qp.J.transpose() * *info.lambda);
        worst_gap = std::max(worst_gap, std::abs(r.norm() - info.native_residual) / std::max(1.0, r.norm()));
        worst_negative = std::max(worst_negative, -info.lambda->minCoeff());
        return true;
    }
    std::vector<cb::StepKind> steps;
    long missing = 0;
    double worst_gap = 0.0, worst_negative = 0.0;

private:
    const Qp& m_qp;
    Vec m_weight;
};

/// The 196-row coupled patch of test_mprgp_coupled_operators.cpp with a random extra load, so
/// that the face changes during the solve.
Qp loaded_patch(std::uint64_t seed)
{
    Qp qp = cb::make_synthetic("coupled", {{"nx", 13}, {"ny", 2}, {"nz", 13}}, seed);
    std::srand(static_cast<unsigned>(seed));
    const Vec push = Vec::Random(qp.n()) * 0.5 * cb::coupled_test_qps::scene_size(qp) / 10.0;
    qp.b += qp.A * push;
    return qp;
}

cb::SolverResult solve_chopped(const Qp& qp, cb::Monitor& monitor, const std::string& operators,
                               const std::string& stop, const std::string& precond)
{
    const nlohmann::json s = {
        {"tol", 1e-8}, {"max_iterations", 20000}, {"operators", operators}, {"stop", stop}, {"precond", precond}};
    cb::SolveContext context;
    context.monitor = &monitor;
    return cb::builtin_registry().create("mprgp-coupled", s)->solve(qp.view(), context);
}

}  // namespace

TEST(MprgpCoupledChoppedBound, MonitorSeesExactMultipliersAndChangesNoStep)
{
    for (std::uint64_t seed : {7u, 11u}) {
        const Qp qp = loaded_patch(seed);
        ASSERT_GT(cb::find_row_components(qp.J).largest(), 128);
        for (const std::string operators : {"components", "global"}) {
            for (const std::string stop : {"kkt", "native"}) {
                for (const std::string precond : {"jacobi", "scaled"}) {
                    std::string what = "seed " + std::to_string(seed);
                    what += ", " + operators;
                    what += ", stop " + stop;
                    what += ", " + precond;
                    ChoppedStepRecorder quiet;
                    ResidualRecorder reader(qp, precond);
                    const cb::SolverResult a = solve_chopped(qp, quiet, operators, stop, precond);
                    const cb::SolverResult b = solve_chopped(qp, reader, operators, stop, precond);
                    ASSERT_EQ(a.status, SolveStatus::CONVERGED) << what << ": " << a.message;
                    ASSERT_EQ(b.status, SolveStatus::CONVERGED) << what << ": " << b.message;
                    EXPECT_EQ(quiet.steps, reader.steps) << what;
                    EXPECT_EQ(a.counters.iterations, b.counters.iterations) << what;
                    EXPECT_LE((a.x - b.x).lpNorm<Eigen::Infinity>() / cb::coupled_test_qps::scene_size(qp), 1e-9)
                        << what;
                    // Every iteration the monitor saw carried x, lambda >= 0 and the exact native residual.
                    EXPECT_EQ(reader.missing, 0) << what;
                    EXPECT_LE(reader.worst_gap, 1e-8) << what;
                    EXPECT_LE(reader.worst_negative, 0.0) << what;
                    // The monitor's LCP solves count only when the solver needs them too: the same decisions
                    // and solves either way (the pivots differ: the monitor's solves warm-start the next).
                    EXPECT_EQ(a.info["chopped_lcp"], b.info["chopped_lcp"]) << what;
                    EXPECT_EQ(a.counters.a_products, b.counters.a_products) << what;
                    // The returned multipliers are the exact ones.
                    EXPECT_LE(cb::accuracy(qp.view(), a.x, a.lambda).max(), 1e-8) << what;
                    // The deferral happened: fewer chopped LCPs than iterations, most tests by the bounds.
                    const nlohmann::json& ch = a.info["chopped_lcp"];
                    EXPECT_GT(ch["deferred"].get<long>(), 0) << what;
                    EXPECT_LT(ch["solved"].get<long>(), a.counters.iterations) << what;
                    EXPECT_GT(ch["proportional_by_bound"].get<long>() + ch["proportional_by_sweeps"].get<long>(), 0)
                        << what;
                }
            }
        }
    }
}
