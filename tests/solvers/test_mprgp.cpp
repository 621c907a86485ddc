// Tests of `mprgp` (ALGORITHMS.md §3): agreement with the active-set reference on seeded
// synthetic families, monotone F(P(x)), no safeguard firing on decoupled J, options, statuses,
// and the iteration count against Jacobi-PCG on the same A (paper Fig. 8 claim).
#include "problems/synthetic.hpp"
#include "solvers/core/registry.hpp"
#include "solvers/measure/accuracy.hpp"
#include "solvers/methods/active_set.hpp"
#include "solvers/methods/cg.hpp"
#include "solvers/mprgp/decouple.hpp"
#include "solvers/mprgp/mprgp.hpp"
#include "solvers/mprgp/mprgp_kernels.hpp"
#include "tests/solvers/dual_test_problems.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <ostream>
#include <string>
#include <vector>

namespace {

using cb::Qp;
using cb::SolveStatus;

/// The reference solver by its registry name (the constructor directly until it is registered).
std::unique_ptr<cb::Solver> reference_solver()
{
    // 1e-11: a direct solve of the stiff case leaves its bodies' motion at 6e-12 (the QP's rounding floor).
    const nlohmann::json settings = {{"tol", 1e-11}};
    if (cb::builtin_registry().contains("active-set")) return cb::builtin_registry().create("active-set", settings);
    return cb::active_set_entry().make(settings);
}

std::unique_ptr<cb::Solver> mprgp(const nlohmann::json& settings)
{
    return cb::builtin_registry().create("mprgp", settings);
}

Qp decoupled(const Qp& qp, cb::DecoupleOrder order = cb::DecoupleOrder::RANDOM, std::uint64_t seed = 3)
{
    const cb::DecoupleReport report = cb::decouple_rows(qp.view(), qp.contacts, order, seed);
    return cb::select_rows(qp, report.kept_rows);
}

/// Records F(P(x)) at every monitor call (P computed here, with the closed form of §2).
class MprgpObjectiveRecorder : public cb::Monitor {
public:
    explicit MprgpObjectiveRecorder(const Qp& qp)
        : m_qp(qp), m_rows(cb::make_decoupled_rows(qp.J, cb::Vec::Ones(qp.n())))
    {
    }
    bool on_iteration(const cb::IterationInfo& info) override
    {
        cb::Vec y;
        cb::project_decoupled(m_qp.J, m_qp.c, m_rows, *info.x, y);
        values.push_back(cb::objective(m_qp.view(), y));
        steps.push_back(info.step);
        return true;
    }
    std::vector<double> values;
    std::vector<cb::StepKind> steps;

private:
    const Qp& m_qp;
    cb::DecoupledRows m_rows;
};

struct MprgpCase {
    const char* name;
    const char* family;
    nlohmann::json params;
    bool decouple;
};
/// ctest names an instance by its printed parameter: the case's name, not its bytes (pointers that
/// moved from build to build).
// NOLINTNEXTLINE(readability-identifier-naming): GoogleTest looks up this name
void PrintTo(const MprgpCase& c, std::ostream* os) { *os << c.name; }

class MprgpAgreement : public ::testing::TestWithParam<MprgpCase> {};

TEST_P(MprgpAgreement, MatchesActiveSetObjectiveAndKkt)
{
    const MprgpCase& tc = GetParam();
    for (std::uint64_t seed : {1u, 2u}) {
        Qp qp = cb::make_synthetic(tc.family, tc.params, seed);
        if (tc.decouple) qp = decoupled(qp);
        ASSERT_TRUE(cb::is_decoupled(qp.J)) << tc.name;
        ASSERT_GT(qp.m(), 0) << tc.name;
        const cb::SolverResult ref = reference_solver()->solve(qp.view(), {});
        ASSERT_EQ(ref.status, SolveStatus::CONVERGED) << tc.name << ": " << ref.message;
        const double f_ref = cb::objective(qp.view(), ref.x);

        MprgpObjectiveRecorder recorder(qp);
        cb::SolveContext context;
        context.monitor = &recorder;
        const cb::SolverResult r = mprgp({{"tol", 1e-10}, {"max_iterations", 20000}})->solve(qp.view(), context);
        ASSERT_EQ(r.status, SolveStatus::CONVERGED) << tc.name << " seed " << seed << ": " << r.message;
        const double f = cb::objective(qp.view(), r.x);
        EXPECT_LE(std::abs(f - f_ref), 1e-8 * std::max(std::abs(f_ref), 1e-300))
            << tc.name << " F " << f << " F* " << f_ref;
        EXPECT_LE(cb::test::relative_kkt(qp, r.x, r.lambda), 1e-8) << tc.name;
        EXPECT_LE(cb::max_violation(qp.view(), r.x), 1e-9 * std::max(1.0, qp.c.lpNorm<Eigen::Infinity>())) << tc.name;
        // Appendix B: with decoupled rows the safeguards never fire.
        EXPECT_EQ(r.counters.safeguard_steps, 0) << tc.name;
        // F(P(x)) is non-increasing over every accepted step.
        ASSERT_GE(recorder.values.size(), 2u);
        for (size_t k = 1; k < recorder.values.size(); ++k) {
            const double prev = recorder.values[k - 1], now = recorder.values[k];
            EXPECT_LE(now, prev + 1e-11 * (std::abs(prev) + std::abs(now))) << tc.name << " call " << k;
        }
        EXPECT_EQ(r.counters.iterations,
                  r.counters.cg_steps + r.counters.expansion_steps + r.counters.proportioning_steps);
        EXPECT_FALSE(r.lambda_fitted);
    }
}

const nlohmann::json small = {{"nx", 4}, {"ny", 3}, {"nz", 4}};
nlohmann::json with(nlohmann::json base, const nlohmann::json& extra)
{
    for (auto it = extra.begin(); it != extra.end(); ++it) base[it.key()] = it.value();
    return base;
}

const auto families = ::testing::Values(
    MprgpCase{"plane", "plane", small, false}, MprgpCase{"tilted", "plane", with(small, {{"tilt_deg", 17.0}}), false},
    MprgpCase{"stiff", "plane", with(small, {{"youngs", 1e10}}), false},
    MprgpCase{"mm", "plane", with(small, {{"length_scale", 1e-3}}), false}, MprgpCase{"box", "box", small, true},
    MprgpCase{"coupled", "coupled", {{"nx", 3}, {"ny", 2}, {"nz", 3}}, true},
    MprgpCase{"duplicate", "duplicate-rows", small, true}, MprgpCase{"scaled", "scaled-rows", small, true},
    MprgpCase{"zero", "zero-rows", small, true});
INSTANTIATE_TEST_SUITE_P(Families, MprgpAgreement, families,
                         [](const auto& info) { return std::string(info.param.name); });

// The literature expansion variants (docs/DESIGN.md "Adding an MPRGP variant") reach the
// active-set solution on every family (most take no expansion: then the variant is the default).
class MprgpExpansionVariants : public ::testing::TestWithParam<MprgpCase> {};

TEST_P(MprgpExpansionVariants, MatchActiveSetObjectiveAndKkt)
{
    const MprgpCase& tc = GetParam();
    Qp qp = cb::make_synthetic(tc.family, tc.params, 1);
    if (tc.decouple) qp = decoupled(qp);
    const cb::SolverResult ref = reference_solver()->solve(qp.view(), {});
    ASSERT_EQ(ref.status, SolveStatus::CONVERGED) << tc.name << ": " << ref.message;
    const double f_ref = cb::objective(qp.view(), ref.x);
    for (const char* expansion : {"bb", "projcg"}) {
        const cb::SolverResult r =
            mprgp({{"tol", 1e-10}, {"max_iterations", 20000}, {"expansion", expansion}})->solve(qp.view(), {});
        ASSERT_EQ(r.status, SolveStatus::CONVERGED) << tc.name << " " << expansion << ": " << r.message;
        const double f = cb::objective(qp.view(), r.x);
        EXPECT_LE(std::abs(f - f_ref), 1e-8 * std::max(std::abs(f_ref), 1e-300))
            << tc.name << " " << expansion << " F " << f << " F* " << f_ref;
        EXPECT_LE(cb::test::relative_kkt(qp, r.x, r.lambda), 1e-8) << tc.name << " " << expansion;
        EXPECT_LE(cb::max_violation(qp.view(), r.x), 1e-9 * std::max(1.0, qp.c.lpNorm<Eigen::Infinity>()))
            << tc.name << " " << expansion;
    }
}
INSTANTIATE_TEST_SUITE_P(Families, MprgpExpansionVariants, families,
                         [](const auto& info) { return std::string(info.param.name); });

// expansion = bb on the random SPD stress case with m near n (decoupled): long BB steps that raised
// F, repaired only by Alg. 3's capped safeguard, diverged (accuracy 5e149 after 8138 iterations);
// the fixed-step fallback keeps F(P(x)) non-increasing and reaches the active-set solution.
TEST(Mprgp, BarzilaiBorweinExpansionStaysMonotone)
{
    const Qp qp = decoupled(cb::make_synthetic("random-spd", {{"n", 200}, {"m", 190}}, 1));
    const cb::SolverResult ref = reference_solver()->solve(qp.view(), {});
    ASSERT_EQ(ref.status, SolveStatus::CONVERGED) << ref.message;
    MprgpObjectiveRecorder recorder(qp);
    cb::SolveContext context;
    context.monitor = &recorder;
    const cb::SolverResult r =
        mprgp({{"tol", 1e-10}, {"max_iterations", 20000}, {"expansion", "bb"}})->solve(qp.view(), context);
    ASSERT_EQ(r.status, SolveStatus::CONVERGED) << r.message;
    const double f_ref = cb::objective(qp.view(), ref.x);
    EXPECT_LE(std::abs(cb::objective(qp.view(), r.x) - f_ref), 1e-8 * std::abs(f_ref));
    EXPECT_LE(cb::test::relative_kkt(qp, r.x, r.lambda), 1e-8);
    EXPECT_GT(r.info.at("bb_fallbacks").get<long>(), 0);  // the case exercises the fallback
    for (size_t k = 1; k < recorder.values.size(); ++k) {
        const double prev = recorder.values[k - 1], now = recorder.values[k];
        ASSERT_LE(now, prev + 1e-11 * (std::abs(prev) + std::abs(now))) << "call " << k;
    }
}

// expansion = projcg on the same case: P(y) from the rejected CG trial, whose F(P(y)) rose by the
// monotone chain's rule, so Alg. 3's safeguard repairs it; F(P(x)) stays non-increasing.
TEST(Mprgp, ProjectedCgExpansionStaysMonotone)
{
    const Qp qp = decoupled(cb::make_synthetic("random-spd", {{"n", 200}, {"m", 190}}, 1));
    const cb::SolverResult ref = reference_solver()->solve(qp.view(), {});
    ASSERT_EQ(ref.status, SolveStatus::CONVERGED) << ref.message;
    MprgpObjectiveRecorder recorder(qp);
    cb::SolveContext context;
    context.monitor = &recorder;
    const cb::SolverResult r =
        mprgp({{"tol", 1e-10}, {"max_iterations", 20000}, {"expansion", "projcg"}})->solve(qp.view(), context);
    ASSERT_EQ(r.status, SolveStatus::CONVERGED) << r.message;
    const double f_ref = cb::objective(qp.view(), ref.x);
    EXPECT_LE(std::abs(cb::objective(qp.view(), r.x) - f_ref), 1e-8 * std::abs(f_ref));
    EXPECT_LE(cb::test::relative_kkt(qp, r.x, r.lambda), 1e-8);
    EXPECT_GT(r.counters.expansion_steps, 0);
    EXPECT_GT(r.counters.safeguard_steps, 0);  // P(y) raised F: the safeguard ran
    for (size_t k = 1; k < recorder.values.size(); ++k) {
        const double prev = recorder.values[k - 1], now = recorder.values[k];
        ASSERT_LE(now, prev + 1e-11 * (std::abs(prev) + std::abs(now))) << "call " << k;
    }
}

// A tiny hand-solved problem: min (x0^2+x1^2+x2^2) - 2 x1 s.t. x0 >= 1 (one row on vertex 0).
// x* = (1, 1, 0), lambda* = 2.
TEST(Mprgp, TinyHandSolvedProblem)
{
    Qp qp;
    qp.A.resize(3, 3);
    std::vector<cb::Triplet> t = {{0, 0, 2.0}, {1, 1, 2.0}, {2, 2, 2.0}};
    qp.A.setFromTriplets(t.begin(), t.end());
    qp.b = cb::Vec(3);
    qp.b << 0.0, 2.0, 0.0;
    qp.J.resize(1, 3);
    std::vector<cb::Triplet> tj = {{0, 0, 1.0}};
    qp.J.setFromTriplets(tj.begin(), tj.end());
    qp.c = cb::Vec::Ones(1);
    qp.x0 = cb::Vec::Zero(3);
    const cb::SolverResult r = mprgp({{"tol", 1e-12}})->solve(qp.view(), {});
    ASSERT_EQ(r.status, SolveStatus::CONVERGED) << r.message;
    EXPECT_NEAR(r.x[0], 1.0, 1e-12);
    EXPECT_NEAR(r.x[1], 1.0, 1e-12);
    EXPECT_NEAR(r.x[2], 0.0, 1e-12);
    EXPECT_NEAR(r.lambda[0], 2.0, 1e-10);
}

TEST(Mprgp, CoupledJIsInvalidInputWithAHint)
{
    const Qp qp = cb::make_synthetic("coupled", {{"nx", 3}, {"ny", 2}, {"nz", 3}}, 1);
    ASSERT_FALSE(cb::is_decoupled(qp.J));
    const cb::SolverResult r = mprgp({})->solve(qp.view(), {});
    EXPECT_EQ(r.status, SolveStatus::INVALID_INPUT);
    EXPECT_NE(r.message.find("not decoupled"), std::string::npos) << r.message;
    EXPECT_NE(r.message.find("decouple the problem first"), std::string::npos) << r.message;
    EXPECT_TRUE(mprgp({})->requires_decoupled());
}

TEST(Mprgp, OptionsReachTheSameSolution)
{
    const Qp qp = cb::make_synthetic("plane", small, 5);
    const cb::SolverResult ref = mprgp({{"tol", 1e-10}})->solve(qp.view(), {});
    ASSERT_EQ(ref.status, SolveStatus::CONVERGED) << ref.message;
    const double f_ref = cb::objective(qp.view(), ref.x);
    for (const nlohmann::json& s :
         {nlohmann::json{{"precond", "none"}}, nlohmann::json{{"alpha", "authors"}},
          nlohmann::json{{"objective", "recompute"}}, nlohmann::json{{"gamma", 0.5}}, nlohmann::json{{"power_max", 5}},
          nlohmann::json{{"expansion", "precond"}}, nlohmann::json{{"expansion", "precond"}, {"precond", "ichol"}}}) {
        nlohmann::json settings = s;
        settings["tol"] = 1e-10;
        settings["max_iterations"] = 20000;
        const cb::SolverResult r = mprgp(settings)->solve(qp.view(), {});
        ASSERT_EQ(r.status, SolveStatus::CONVERGED) << s.dump() << ": " << r.message;
        EXPECT_LE(std::abs(cb::objective(qp.view(), r.x) - f_ref), 1e-8 * std::abs(f_ref)) << s.dump();
        EXPECT_LE(cb::test::relative_kkt(qp, r.x, r.lambda), 1e-8) << s.dump();
    }
}

TEST(Mprgp, RecomputeObjectiveCostsTwoProductsPerCgStep)
{
    const Qp qp = cb::make_synthetic("plane", small, 6);
    const cb::SolverResult cheap = mprgp({{"tol", 1e-8}})->solve(qp.view(), {});
    const cb::SolverResult rec = mprgp({{"tol", 1e-8}, {"objective", "recompute"}})->solve(qp.view(), {});
    ASSERT_EQ(cheap.status, SolveStatus::CONVERGED) << cheap.message;
    ASSERT_EQ(rec.status, SolveStatus::CONVERGED) << rec.message;
    EXPECT_LE(std::abs(cb::objective(qp.view(), cheap.x) - cb::objective(qp.view(), rec.x)),
              1e-9 * std::abs(cb::objective(qp.view(), rec.x)));
    // Products outside the power method: cheap = one per CG step (+2 per expansion, +1 per
    // proportioning, +2 at start/end); recompute = two per CG step.
    const auto solve_products = [](const cb::SolverResult& r) {
        return r.counters.a_products - r.counters.power_products;
    };
    EXPECT_LE(solve_products(cheap), cheap.counters.cg_steps + 3 * cheap.counters.expansion_steps +
                                         2 * cheap.counters.proportioning_steps + 4);
    EXPECT_GE(solve_products(rec), 2 * rec.counters.cg_steps);
}

TEST(Mprgp, NativeStopMeetsPhiPlusBeta)
{
    const Qp qp = cb::make_synthetic("plane", small, 7);
    const double tol = 1e-7 * qp.b.norm();
    const cb::SolverResult r = mprgp({{"tol", tol}, {"stop", "native"}})->solve(qp.view(), {});
    ASSERT_EQ(r.status, SolveStatus::CONVERGED) << r.message;
    EXPECT_EQ(r.criterion, cb::StopCriterion::NATIVE);
    // ||phi + beta|| recomputed here with the kernels at the returned x.
    const cb::DecoupledRows rows = cb::make_decoupled_rows(qp.J, cb::Vec::Ones(qp.n()));
    std::vector<char> active;
    cb::active_rows(qp.J, qp.c, rows, r.x, active);
    const cb::Vec g = qp.A * r.x - qp.b;
    cb::Vec phi, beta;
    cb::free_gradient(qp.J, rows, active, g, phi);
    cb::chopped_gradient(qp.J, rows, active, g, beta);
    EXPECT_LE((phi + beta).norm(), tol);
    EXPECT_NEAR(r.native_residual, (phi + beta).norm(), 1e-9 * qp.b.norm());
}

TEST(Mprgp, NonConvergenceIsReported)
{
    const Qp qp = cb::make_synthetic("plane", small, 8);
    const cb::SolverResult r = mprgp({{"tol", 1e-12}, {"max_iterations", 3}})->solve(qp.view(), {});
    EXPECT_EQ(r.status, SolveStatus::MAX_ITERATIONS);
    EXPECT_EQ(r.iterations, 3);
    EXPECT_EQ(r.criterion, cb::StopCriterion::NONE);
    EXPECT_GT(cb::test::relative_kkt(qp, r.x, r.lambda), 1e-12);
    EXPECT_LE(cb::max_violation(qp.view(), r.x), 1e-9);  // the returned x is projected

    const Qp big = cb::make_synthetic("plane", {{"nx", 16}, {"ny", 8}, {"nz", 16}}, 8);
    const cb::SolverResult t =
        mprgp({{"tol", 1e-14}, {"time_limit_s", 1e-4}, {"max_iterations", 1000000}})->solve(big.view(), {});
    EXPECT_EQ(t.status, SolveStatus::TIME_LIMIT) << t.message;
}

TEST(Mprgp, WarmStartedPowerMethodNeedsFewerProducts)
{
    const Qp qp = cb::make_synthetic("plane", small, 9);
    cb::Vec eigenvector;
    cb::SolveContext context;
    context.eigenvector = &eigenvector;
    const cb::SolverResult cold = mprgp({{"tol", 1e-8}})->solve(qp.view(), context);
    ASSERT_EQ(eigenvector.size(), qp.n());
    const cb::SolverResult warm = mprgp({{"tol", 1e-8}})->solve(qp.view(), context);
    EXPECT_FALSE(cold.info["power"]["warm_start"].get<bool>());
    EXPECT_TRUE(warm.info["power"]["warm_start"].get<bool>());
    EXPECT_LT(warm.counters.power_products, cold.counters.power_products);
    EXPECT_EQ(cold.counters.a_products - cold.counters.power_products,
              warm.counters.a_products - warm.counters.power_products);
}

TEST(Mprgp, NoRowsStillPreconditionsLikeJacobiPcg)
{
    // Stiff material: diag(A) varies (corner/edge/interior vertices), so Jacobi visibly acts.
    const Qp qp = cb::make_synthetic("unconstrained", with(small, {{"youngs", 1e9}}), 10);
    ASSERT_EQ(qp.m(), 0);
    for (const char* precond : {"jacobi", "none"}) {
        const nlohmann::json settings = {{"tol", 1e-8}, {"precond", precond}};
        const cb::SolverResult r = mprgp(settings)->solve(qp.view(), {});
        ASSERT_EQ(r.status, SolveStatus::CONVERGED) << r.message;
        EXPECT_EQ(r.counters.expansion_steps + r.counters.proportioning_steps, 0);
        const auto cg = cb::builtin_registry().contains("cg") ? cb::builtin_registry().create("cg", settings)
                                                              : cb::cg_entry().make(settings);
        const cb::SolverResult pcg = cg->solve(qp.view(), {});
        ASSERT_EQ(pcg.status, SolveStatus::CONVERGED) << pcg.message;
        // Same preconditioner, same stopping measure: the same CG iterates up to rounding.
        EXPECT_NEAR(static_cast<double>(r.iterations), static_cast<double>(pcg.iterations), 2.0) << precond;
    }
}

TEST(Mprgp, BadSettingsNameTheKey)
{
    try {
        mprgp({{"gamma", -1.0}});
        FAIL() << "no throw";
    } catch (const cb::InputError& e) {
        EXPECT_NE(std::string(e.what()).find("mprgp: /gamma"), std::string::npos) << e.what();
    }
    EXPECT_THROW(mprgp({{"precond", "ilu"}}), cb::InputError);
    EXPECT_THROW(mprgp({{"unknown_key", 1}}), cb::InputError);
}

// The paper's Fig. 8 claim, checked fairly: to relative KKT 1e-6, mprgp needs at most 1.5x the
// iterations Jacobi-PCG needs on the same A without constraints.
TEST(Mprgp, IterationsWithinOneAndAHalfOfPcgOnTheSameMatrix)
{
    const nlohmann::json params = {{"nx", 14}, {"ny", 8}, {"nz", 14}};
    const Qp qp = cb::make_synthetic("plane", params, 11);
    ASSERT_GT(qp.m(), 50);
    const cb::SolverResult r = mprgp({{"tol", 1e-6}})->solve(qp.view(), {});
    ASSERT_EQ(r.status, SolveStatus::CONVERGED) << r.message;
    Qp free = qp;
    free.J.resize(0, qp.n());
    free.c.resize(0);
    const nlohmann::json cg_settings = {{"tol", 1e-6}, {"precond", "jacobi"}};
    const auto cg = cb::builtin_registry().contains("cg") ? cb::builtin_registry().create("cg", cg_settings)
                                                          : cb::cg_entry().make(cg_settings);
    const cb::SolverResult pcg = cg->solve(free.view(), {});
    ASSERT_EQ(pcg.status, SolveStatus::CONVERGED) << pcg.message;
    std::printf("mprgp %ld iterations (%ld cg, %ld expansion, %ld proportioning), PCG %ld\n", r.iterations,
                r.counters.cg_steps, r.counters.expansion_steps, r.counters.proportioning_steps, pcg.iterations);
    EXPECT_LE(static_cast<double>(r.iterations), 1.5 * static_cast<double>(pcg.iterations));
}

}  // namespace

namespace {

// A row's stored zero on another row's DOF does not couple the rows (cb::is_decoupled reads values,
// not the pattern), so `mprgp` must take it as absent: the same iterations and the same x. Guards the
// face correction of z, which visits every stored entry of a row: a pass that set z on one row's
// entries after another row had corrected them would lose that correction.
TEST(Mprgp, StoredZerosOnAnotherRowsDofsChangeNothing)
{
    const Qp qp = cb::make_synthetic("plane", {{"nx", 6}, {"ny", 4}, {"nz", 6}}, 21);
    ASSERT_GT(qp.m(), 8);
    Qp zeros = qp;
    std::vector<Eigen::Triplet<double>> entries;
    for (Eigen::Index i = 0; i < qp.m(); ++i) {
        for (cb::SpMat::InnerIterator it(qp.J, i); it; ++it) entries.emplace_back(i, it.col(), it.value());
        const Eigen::Index next = (i + 1) % qp.m();  // the next row's DOFs, as explicit zeros of row i
        for (cb::SpMat::InnerIterator it(qp.J, next); it; ++it) entries.emplace_back(i, it.col(), 0.0);
    }
    zeros.J.setFromTriplets(entries.begin(), entries.end());
    zeros.J.makeCompressed();
    ASSERT_GT(zeros.J.nonZeros(), qp.J.nonZeros());
    ASSERT_TRUE(cb::is_decoupled(zeros.J));

    const nlohmann::json settings = {{"tol", 1e-10}};
    const cb::SolverResult plain = mprgp(settings)->solve(qp.view(), {});
    const cb::SolverResult stored = mprgp(settings)->solve(zeros.view(), {});
    ASSERT_EQ(plain.status, SolveStatus::CONVERGED) << plain.message;
    EXPECT_EQ(stored.status, SolveStatus::CONVERGED) << stored.message;
    EXPECT_GT(plain.counters.cg_steps, 5);
    const cb::Vec slack = qp.J * plain.x - qp.c;
    EXPECT_GT(slack.minCoeff(), -1e-9);            // feasible,
    EXPECT_LT(slack.cwiseAbs().minCoeff(), 1e-9);  // with a face for the correction to act on
    EXPECT_EQ(stored.iterations, plain.iterations);
    EXPECT_LE((stored.x - plain.x).cwiseAbs().maxCoeff(), 1e-13 * plain.x.cwiseAbs().maxCoeff());
}

}  // namespace

namespace {

// The setup's parts in the result (info.setup_phases_s, SolveLoop::setup_phase): the phases each
// MPRGP solver names, and info.power.seconds as the power method's own time, not the whole setup.
TEST(Mprgp, SetupPhasesNameWhereTheSetupWent)
{
    const Qp qp = cb::make_synthetic("plane", small, 5);
    const std::map<std::string, std::vector<std::string>> expected = {
        {"mprgp", {"a_prepare", "measure_scale", "other", "power", "rows_and_diagonal"}},
        {"mprgp-coupled", {"a_prepare", "face_operators", "measure_scale", "other", "power", "precond_and_scaling"}},
    };
    for (const auto& [name, keys] : expected) {
        const cb::SolverResult r = cb::builtin_registry().create(name, {{"tol", 1e-8}})->solve(qp.view(), {});
        ASSERT_EQ(r.status, SolveStatus::CONVERGED) << name << ": " << r.message;
        ASSERT_TRUE(r.info.contains("setup_phases_s")) << name;
        const nlohmann::json& p = r.info["setup_phases_s"];
        std::vector<std::string> got;
        double sum = 0.0;
        for (const auto& [key, value] : p.items()) {
            got.push_back(key);
            EXPECT_GE(value.get<double>(), 0.0) << name << " " << key;
            sum += value.get<double>();
        }
        EXPECT_EQ(got, keys) << name;  // nlohmann's object: keys in sorted order
        EXPECT_NEAR(sum, r.setup_s, 1e-9) << name;
    }
    const cb::SolverResult d = mprgp({{"tol", 1e-8}})->solve(qp.view(), {});
    EXPECT_NEAR(d.info["power"]["seconds"].get<double>(), d.info["setup_phases_s"]["power"].get<double>(), 1e-12);
    EXPECT_LT(d.info["power"]["seconds"].get<double>(), d.setup_s);
    // A setup's optional parts get names of their own, not their neighbours'.
    const cb::SolverResult rigid = mprgp({{"tol", 1e-8}, {"deflation", "rigid"}})->solve(qp.view(), {});
    EXPECT_TRUE(rigid.info["setup_phases_s"].contains("deflation")) << rigid.info["setup_phases_s"].dump();
    const cb::SolverResult ichol =
        cb::builtin_registry().create("mprgp-coupled", {{"tol", 1e-8}, {"precond", "ichol"}})->solve(qp.view(), {});
    EXPECT_TRUE(ichol.info["setup_phases_s"].contains("preconditioner")) << ichol.info["setup_phases_s"].dump();
}

}  // namespace
