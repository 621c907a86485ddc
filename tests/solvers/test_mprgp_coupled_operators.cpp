// `mprgp-coupled` with operators=components against the global CHOLMOD operators (the oracle):
// the same step kinds and iterates to rounding, compared on x and J'lambda (dependent rows make
// lambda itself non-unique), on QPs with components of 1 to ~200 rows, dependent rows and face
// changes. Also the row-graph components themselves (solvers/linalg/row_components.hpp).
#include "coupled_test_qps.hpp"
#include "problems/synthetic.hpp"
#include "solvers/core/registry.hpp"
#include "solvers/linalg/row_components.hpp"
#include "solvers/measure/accuracy.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>

namespace {

using cb::Qp;
using cb::SolveStatus;
using cb::Vec;
using cb::coupled_test_qps::loaded;
using cb::coupled_test_qps::scene_size;
using cb::coupled_test_qps::with_dependent_row;

class OperatorIterateRecorder : public cb::Monitor {
public:
    bool on_iteration(const cb::IterationInfo& info) override
    {
        steps.push_back(info.step);
        xs.push_back(*info.x);
        return true;
    }
    std::vector<cb::StepKind> steps;
    std::vector<Vec> xs;
};

struct OperatorRun {
    cb::SolverResult result;
    OperatorIterateRecorder recorder;
};

void solve_with_operators(const Qp& qp, const std::string& operators, const std::string& precond, OperatorRun& run,
                          long dense_max_rows = 400)
{
    const nlohmann::json s = {{"tol", 1e-10},
                              {"max_iterations", 20000},
                              {"operators", operators},
                              {"precond", precond},
                              {"dense_max_rows", dense_max_rows}};
    cb::SolveContext context;
    context.monitor = &run.recorder;
    run.result = cb::builtin_registry().create("mprgp-coupled", s)->solve(qp.view(), context);
}

/// Component statistics of a QP's row graph.
cb::RowComponents components(const Qp& qp) { return cb::find_row_components(qp.J); }

/// @param dense_max_rows  400: every component dense; 1: every component of 2+ rows on CHOLMOD
void expect_same_run(const Qp& qp, const std::string& precond, const std::string& what, long dense_max_rows = 400)
{
    OperatorRun global, comp;
    solve_with_operators(qp, "global", precond, global);
    solve_with_operators(qp, "components", precond, comp, dense_max_rows);
    ASSERT_EQ(global.result.status, SolveStatus::CONVERGED) << what << ": " << global.result.message;
    ASSERT_EQ(comp.result.status, SolveStatus::CONVERGED) << what << ": " << comp.result.message;
    // Same step kinds, iteration by iteration.
    size_t first = 0;
    while (first < std::min(global.recorder.steps.size(), comp.recorder.steps.size()) &&
           global.recorder.steps[first] == comp.recorder.steps[first])
        ++first;
    // The stop test may fall one iteration apart when the error crosses tol within rounding.
    const size_t shorter = std::min(global.recorder.steps.size(), comp.recorder.steps.size());
    const size_t longer = std::max(global.recorder.steps.size(), comp.recorder.steps.size());
    ASSERT_TRUE(first == shorter && longer - shorter <= 1)
        << what << ": first difference at iteration " << first << " of " << global.recorder.steps.size() << " / "
        << comp.recorder.steps.size() << " (" << global.result.message << " | " << comp.result.message << ")";
    const double l = scene_size(qp);
    double worst = 0.0;
    for (size_t k = 0; k < shorter; ++k)
        worst = std::max(worst, (global.recorder.xs[k] - comp.recorder.xs[k]).lpNorm<Eigen::Infinity>());
    // CG chains of 200+ steps amplify the rounding of the two factorizations (measured <= 1.6e-8).
    EXPECT_LE(worst / l, 1e-7) << what << ": largest iterate difference over " << global.recorder.xs.size();
    EXPECT_LE((global.result.x - comp.result.x).lpNorm<Eigen::Infinity>() / l, 1e-9) << what;
    const Vec fg = qp.J.transpose() * global.result.lambda, fc = qp.J.transpose() * comp.result.lambda;
    EXPECT_LE((fg - fc).lpNorm<Eigen::Infinity>(), 1e-7 * std::max(1.0, fg.lpNorm<Eigen::Infinity>())) << what;
    // Both are exact on the original QP.
    EXPECT_LE(cb::accuracy(qp.view(), comp.result.x, comp.result.lambda).max(), 1e-9) << what;
    // The oracle ran on one CHOLMOD block, the components on dense ones.
    EXPECT_EQ(global.result.info["components"]["sparse_blocks"].get<long>(), 1) << what;
    const cb::RowComponents rc = cb::find_row_components(qp.J);
    long large = 0;  // components above dense_max_rows (a row of its own is never one: closed form)
    for (int k = 0; k < rc.count(); ++k) large += rc.size(k) > std::max(1L, dense_max_rows);
    EXPECT_EQ(comp.result.info["components"]["sparse_blocks"].get<long>(), large) << what;
    EXPECT_GT(comp.result.info["components"]["face_refactorizations"].get<long>(), 1) << what;  // face changes
    if (dense_max_rows >= rc.largest()) {
        EXPECT_EQ(comp.result.counters.cholmod_factorizations, 0) << what;
    }
}

TEST(RowComponents, SharedVerticesJoinRowsAndExplicitZerosDoNot)
{
    // Rows 0 and 1 share vertex 1 (columns 3..5); row 2 touches vertex 1 only through an explicit
    // zero and vertex 3 otherwise; row 3 is a zero row.
    cb::SpMat J(4, 12);
    std::vector<cb::Triplet> t = {{0, 0, 1.0}, {0, 4, 1.0}, {1, 5, -1.0}, {1, 7, 2.0}, {2, 3, 0.0}, {2, 10, 1.0}};
    J.setFromTriplets(t.begin(), t.end());
    const cb::RowComponents rc = cb::find_row_components(J);
    ASSERT_EQ(rc.count(), 3);
    EXPECT_EQ(rc.of_row[0], rc.of_row[1]);
    EXPECT_NE(rc.of_row[2], rc.of_row[0]);
    EXPECT_NE(rc.of_row[3], rc.of_row[2]);
    EXPECT_EQ(rc.largest(), 2);
    EXPECT_EQ(rc.singletons(), 2);
}

TEST(MprgpCoupledOperators, ComponentsAgreeWithGlobalOnCoupledRows)
{
    // nx = nz = 3, 6, 13: one patch of 16, 49 and 196 rows sharing vertices.
    for (int nx : {3, 6, 13}) {
        const Qp qp = loaded(cb::make_synthetic("coupled", {{"nx", nx}, {"ny", 2}, {"nz", nx}}, 7), 7);
        const cb::RowComponents rc = components(qp);
        EXPECT_GE(rc.largest(), nx == 13 ? 150 : 2);
        EXPECT_LE(rc.largest(), 200);
        for (const char* precond : {"jacobi", "none", "scaled"})
            expect_same_run(qp, precond, "coupled nx " + std::to_string(nx) + " " + precond);
        expect_same_run(qp, "jacobi", "coupled nx " + std::to_string(nx) + " sparse components", 1);
    }
}

TEST(MprgpCoupledOperators, ComponentsAgreeWithGlobalOnDependentAndScaledRows)
{
    const Qp dup = loaded(cb::make_synthetic("duplicate-rows", {{"nx", 4}, {"ny", 2}, {"nz", 4}}, 3), 3);
    const cb::RowComponents rc = components(dup);
    EXPECT_GT(rc.count() - rc.singletons(), 0);  // twins form components of 2 dependent rows
    expect_same_run(dup, "jacobi", "duplicate rows");
    const Qp scaled = loaded(cb::make_synthetic("scaled-rows", {{"nx", 4}, {"ny", 2}, {"nz", 4}}, 3), 3);
    EXPECT_EQ(components(scaled).largest(), 1);
    expect_same_run(scaled, "jacobi", "scaled rows");
}

}  // namespace

TEST(MprgpCoupledOperators, LargeComponentRowUpdatesAgreeWithGlobal)
{
    // A 196-row patch above the default dense_max_rows = 128: its face changes several times and
    // its masked sparse factors follow by row additions and deletions (and refactorisations).
    const Qp qp = loaded(cb::make_synthetic("coupled", {{"nx", 13}, {"ny", 2}, {"nz", 13}}, 7), 7);
    ASSERT_GT(components(qp).largest(), 128);
    for (long max_updates : {1L, 64L}) {
        ::OperatorRun comp;
        // precond = jacobi: two masked face factors (J J' and J D^-1 J') and more face changes to follow
        const nlohmann::json s = {
            {"tol", 1e-10}, {"max_iterations", 20000}, {"sparse_max_updates", max_updates}, {"precond", "jacobi"}};
        cb::SolveContext context;
        context.monitor = &comp.recorder;
        comp.result = cb::builtin_registry().create("mprgp-coupled", s)->solve(qp.view(), context);
        ASSERT_EQ(comp.result.status, SolveStatus::CONVERGED) << comp.result.message;
        const nlohmann::json& st = comp.result.info["components"];
        EXPECT_EQ(st["sparse_blocks"].get<long>(), 1);
        EXPECT_GE(st["face_refactorizations"].get<long>(), 3) << "the face changes several times";
        EXPECT_GT(st["sparse_row_additions"].get<long>(), 0);
        EXPECT_GT(st["sparse_row_deletions"].get<long>(), 0);
        EXPECT_GT(st["sparse_refactorizations"].get<long>(), 0);
        EXPECT_EQ(st["lcp_failures"].get<long>(), 0);
        EXPECT_LE(cb::accuracy(qp.view(), comp.result.x, comp.result.lambda).max(), 1e-9);
    }
    expect_same_run(qp, "jacobi", "196-row patch, default dense_max_rows", 128);
    expect_same_run(qp, "none", "196-row patch, default dense_max_rows, precond none", 128);
    expect_same_run(qp, "scaled", "196-row patch, default dense_max_rows, precond scaled", 128);
    // A duplicated and a parallel (scaled) row inside the large component.
    const Qp dep = with_dependent_row(with_dependent_row(qp, 40, 1.0), 90, 3.0);
    ASSERT_EQ(components(dep).largest(), components(qp).largest() + 2);
    expect_same_run(dep, "jacobi", "196-row patch with a duplicated and a parallel row", 128);
    expect_same_run(dep, "scaled", "196-row patch with a duplicated and a parallel row, scaled", 128);
}
