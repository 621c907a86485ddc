// Tests of `mprgp-coupled` (ALGORITHMS.md §4): general J on per-component subproblems, agreement with
// the active-set reference, dependent rows, both preconditioner settings, safeguard counts.
#include "problems/synthetic.hpp"
#include "solvers/core/registry.hpp"
#include "solvers/measure/accuracy.hpp"
#include "solvers/mprgp/decouple.hpp"
#include "tests/solvers/dual_test_problems.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <vector>

namespace {

using cb::Qp;
using cb::SolveStatus;

class Recorder : public cb::Monitor {
public:
    bool on_iteration(const cb::IterationInfo& info) override
    {
        steps.push_back(info.step);
        return true;
    }
    std::vector<cb::StepKind> steps;
};

void expect_agreement(const Qp& qp, const nlohmann::json& settings, const std::string& what, long* safeguards = nullptr)
{
    const cb::SolverResult ref = cb::builtin_registry().create("active-set", {{"tol", 1e-12}})->solve(qp.view(), {});
    ASSERT_EQ(ref.status, SolveStatus::CONVERGED) << what << ": " << ref.message;
    const double f_ref = cb::objective(qp.view(), ref.x);
    nlohmann::json s = settings;
    s["tol"] = 1e-10;
    s["max_iterations"] = 20000;
    Recorder recorder;
    cb::SolveContext context;
    context.monitor = &recorder;
    const cb::SolverResult r = cb::builtin_registry().create("mprgp-coupled", s)->solve(qp.view(), context);
    ASSERT_EQ(r.status, SolveStatus::CONVERGED) << what << ": " << r.message;
    EXPECT_LE(std::abs(cb::objective(qp.view(), r.x) - f_ref), 1e-8 * std::abs(f_ref)) << what;
    EXPECT_LE(cb::test::relative_kkt(qp, r.x, r.lambda), 1e-8) << what;
    EXPECT_LE(cb::max_violation(qp.view(), r.x), 1e-9) << what;
    // The face operators ran: some component's face was factored (dense or CHOLMOD).
    EXPECT_GT(r.info["components"]["face_refactorizations"].get<long>(), 0) << what;
    EXPECT_EQ(r.counters.iterations, r.counters.cg_steps + r.counters.expansion_steps + r.counters.proportioning_steps);
    EXPECT_EQ(r.info["safeguard_firings"].get<long>(), r.counters.safeguard_steps);
    EXPECT_EQ(static_cast<long>(recorder.steps.size()), r.iterations + 1);  // one call per outer iteration + start
    if (safeguards) *safeguards = r.counters.safeguard_steps;
}

TEST(MprgpCoupled, AgreesWithActiveSetOnCoupledRows)
{
    for (std::uint64_t seed : {1u, 2u}) {
        const Qp qp = cb::make_synthetic("coupled", {{"nx", 3}, {"ny", 2}, {"nz", 3}}, seed);
        ASSERT_FALSE(cb::is_decoupled(qp.J));
        expect_agreement(qp, {}, "coupled jacobi seed " + std::to_string(seed));
        expect_agreement(qp, {{"precond", "none"}}, "coupled none seed " + std::to_string(seed));
    }
}

TEST(MprgpCoupled, DependentRowsAreHandled)
{
    const Qp qp = cb::make_synthetic("duplicate-rows", {{"nx", 3}, {"ny", 2}, {"nz", 3}}, 3);
    ASSERT_FALSE(cb::is_decoupled(qp.J));  // a duplicated row shares its vertex with its twin
    expect_agreement(qp, {}, "duplicate rows");
    const Qp scaled = cb::make_synthetic("scaled-rows", {{"nx", 3}, {"ny", 2}, {"nz", 3}}, 3);
    expect_agreement(scaled, {}, "scaled rows");
}

TEST(MprgpCoupled, DecoupledProblemsNeedNoSafeguard)
{
    const Qp qp = cb::make_synthetic("plane", {{"nx", 4}, {"ny", 3}, {"nz", 4}}, 4);
    long safeguards = -1;
    expect_agreement(qp, {}, "plane", &safeguards);
    EXPECT_EQ(safeguards, 0);
    const Qp coupled = cb::make_synthetic("coupled", {{"nx", 3}, {"ny", 2}, {"nz", 3}}, 5);
    const cb::DecoupleReport rep = cb::decouple_rows(coupled.view(), coupled.contacts, cb::DecoupleOrder::DEPTH, 0);
    expect_agreement(cb::select_rows(coupled, rep.kept_rows), {}, "decoupled coupled", &safeguards);
    EXPECT_EQ(safeguards, 0);
}

TEST(MprgpCoupled, NonConvergenceIsReported)
{
    const Qp qp = cb::make_synthetic("coupled", {{"nx", 3}, {"ny", 2}, {"nz", 3}}, 1);
    const cb::SolverResult r =
        cb::builtin_registry().create("mprgp-coupled", {{"tol", 1e-14}, {"max_iterations", 2}})->solve(qp.view(), {});
    EXPECT_EQ(r.status, SolveStatus::MAX_ITERATIONS);
    EXPECT_EQ(r.criterion, cb::StopCriterion::NONE);
    EXPECT_EQ(r.message.rfind("mprgp-coupled: iteration cap 2 reached; accuracy error ", 0), 0u) << r.message;
}

}  // namespace

namespace {

TEST(MprgpCoupled, OneProductPerCgStep)
{
    // Difference form of F(P(y)): a CG trial costs one A-product, an expansion one more (the exact
    // gradient after it), a proportioning step or safeguard repeat one; plus the start, the
    // convergence confirmations and the final point (a few). The old direct F cost 5.5 per iteration.
    for (std::uint64_t seed : {1u, 2u, 3u}) {
        const Qp qp = cb::make_synthetic("coupled", {{"nx", 6}, {"ny", 2}, {"nz", 6}}, seed);
        const cb::SolverResult r =
            cb::builtin_registry().create("mprgp-coupled", {{"tol", 1e-8}})->solve(qp.view(), {});
        ASSERT_EQ(r.status, SolveStatus::CONVERGED) << r.message;
        const cb::Counters& c = r.counters;
        EXPECT_LE(c.a_products - c.power_products, c.iterations + c.expansion_steps + c.safeguard_steps + 5)
            << "seed " << seed;
        EXPECT_EQ(r.info["components"]["operators"], "components");
        EXPECT_EQ(r.info["chain"]["rejected_infeasible_trials"].get<long>() +
                      r.info["chain"]["rejected_feasible_trials"].get<long>() +
                      r.info["chain"]["infeasible_not_proportional"].get<long>() +
                      r.info["chain"]["face_done_expansions"].get<long>(),
                  c.expansion_steps)
            << "every expansion has one counted cause";
    }
}

}  // namespace

namespace {

class CoupledStepRecorder : public cb::Monitor {
public:
    bool on_iteration(const cb::IterationInfo& info) override
    {
        steps.push_back(info.step);
        return true;
    }
    std::vector<cb::StepKind> steps;
};

cb::SolverResult run_recorded(const Qp& qp, const std::string& solver, nlohmann::json settings,
                              CoupledStepRecorder& rec)
{
    settings["tol"] = 1e-10;
    settings["max_iterations"] = 20000;
    cb::SolveContext context;
    context.monitor = &rec;
    return cb::builtin_registry().create(solver, settings)->solve(qp.view(), context);
}

TEST(MprgpCoupled, ReducesToMprgpOnDecoupledRows)
{
    // Rows that share no vertex: the coupled chain is the paper's Alg. 1-3, so it must take the
    // step kinds of `mprgp` iteration by iteration (the projection keeping the face or not: on
    // decoupled rows no correction reaches a face row). Measured the same on two_dinos_5910 frame 11
    // decoupled (285 iterations, 3 expansions, 2 proportioning steps each).
    const Qp coupled = cb::make_synthetic("coupled", {{"nx", 6}, {"ny", 2}, {"nz", 6}}, 5);
    const cb::DecoupleReport rep = cb::decouple_rows(coupled.view(), coupled.contacts, cb::DecoupleOrder::DEPTH, 0);
    const Qp decoupled = cb::select_rows(coupled, rep.kept_rows);
    ASSERT_TRUE(cb::is_decoupled(decoupled.J));
    const Qp plane = cb::make_synthetic("plane", {{"nx", 5}, {"ny", 3}, {"nz", 5}, {"margin", 4.0}}, 4);
    // The body started above the ground (every row free at x0): the CG chain crosses rows, the face
    // grows by expansions.
    Qp lifted = plane;
    for (Eigen::Index j = 1; j < lifted.n(); j += 3) lifted.x0[j] += 0.2 * cb::accuracy_scale(plane.view()).length;
    long expansions = 0;
    for (const Qp* qp : std::vector<const Qp*>{&decoupled, &plane, &lifted}) {
        CoupledStepRecorder ref_steps;
        const cb::SolverResult ref = run_recorded(*qp, "mprgp", {}, ref_steps);
        ASSERT_EQ(ref.status, SolveStatus::CONVERGED) << ref.message;
        expansions += ref.counters.expansion_steps;
        const double l = cb::accuracy_scale(qp->view()).length;
        for (const char* projection : {"face", "all"}) {
            CoupledStepRecorder steps;
            const cb::SolverResult r =
                run_recorded(*qp, "mprgp-coupled", {{"expansion_projection", projection}}, steps);
            ASSERT_EQ(r.status, SolveStatus::CONVERGED) << projection << ": " << r.message;
            // The last monitor call reports the end (mprgp marks it FINAL), not a step; the stop
            // test (each solver's own form of the error) may fall one iteration apart at tol 1e-10.
            EXPECT_LE(std::abs(r.iterations - ref.iterations), 1) << projection;
            const size_t common = std::min(steps.steps.size(), ref_steps.steps.size()) - 1;
            size_t first = 0;
            while (first < common && steps.steps[first] == ref_steps.steps[first]) ++first;
            EXPECT_EQ(first, common) << projection << ": first different step " << first << " of " << steps.steps.size()
                                     << " / " << ref_steps.steps.size();
            EXPECT_EQ(r.counters.expansion_steps, ref.counters.expansion_steps) << projection;
            EXPECT_EQ(r.counters.proportioning_steps, ref.counters.proportioning_steps) << projection;
            EXPECT_LE((r.x - ref.x).lpNorm<Eigen::Infinity>() / l, 1e-9) << projection;
        }
    }
    EXPECT_GT(expansions, 0);  // the comparison covers the expansion step
}

TEST(MprgpCoupled, FaceKeepingExpansionsOnCoupledRows)
{
    // Coupled rows: a plain projection after the expansion step may lift face rows off through a
    // neighbour's correction; keeping the face never does, so it takes no more expansions here
    // (on two_dinos_5910 frame 11: 10 expansions against 347).
    for (const std::string precond : {"jacobi", "scaled"}) {
        long face_expansions = 0, all_expansions = 0;
        for (std::uint64_t seed : {1u, 2u, 3u}) {
            // Started with the rows opened (x0 moved along J'1): the chain crosses rows, expansions follow.
            Qp qp = cb::make_synthetic("coupled", {{"nx", 6}, {"ny", 2}, {"nz", 6}}, seed);
            const cb::Vec open = qp.J.transpose() * cb::Vec::Ones(qp.m());
            qp.x0 += open * (0.05 * cb::accuracy_scale(qp.view()).length / open.lpNorm<Eigen::Infinity>());
            CoupledStepRecorder face_steps, all_steps;
            const cb::SolverResult face =
                run_recorded(qp, "mprgp-coupled", {{"expansion_projection", "face"}, {"precond", precond}}, face_steps);
            const cb::SolverResult all =
                run_recorded(qp, "mprgp-coupled", {{"expansion_projection", "all"}, {"precond", precond}}, all_steps);
            ASSERT_EQ(face.status, SolveStatus::CONVERGED) << face.message;
            ASSERT_EQ(all.status, SolveStatus::CONVERGED) << all.message;
            EXPECT_LE(cb::test::relative_kkt(qp, face.x, face.lambda), 1e-9);
            EXPECT_LE(face.counters.expansion_steps, all.counters.expansion_steps) << precond << ", seed " << seed;
            const double l = cb::accuracy_scale(qp.view()).length;
            EXPECT_LE((face.x - all.x).lpNorm<Eigen::Infinity>() / l, 1e-8) << precond << ", seed " << seed;
            face_expansions += face.counters.expansion_steps;
            all_expansions += all.counters.expansion_steps;
        }
        // jacobi: measured 10 against 224 over the three seeds (iterations 419 against 621) before both
        // of the expansion's projections kept the face, 5 since; scaled: 4 against 24.
        const long factor = precond == "jacobi" ? 10 : 5;
        EXPECT_LE(factor * face_expansions, all_expansions)
            << precond << ": " << face_expansions << " against " << all_expansions;
    }
}

}  // namespace
