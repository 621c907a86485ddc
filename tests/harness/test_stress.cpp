// Tests of the stress suite: cases are generated, every run ends in an honest outcome, and the
// stability files have the columns the heat map reads.
#include "harness/stress.hpp"
#include "solvers/core/registry.hpp"
#include "solvers/measure/accuracy.hpp"

#include <gtest/gtest.h>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

namespace cb {
namespace {

TEST(StressCases, AreDistinctSeededAndBuildable)
{
    const auto all = stress_cases(false);
    EXPECT_GE(all.size(), 28u);
    std::set<std::string> ids;
    for (const auto& c : all) EXPECT_TRUE(ids.insert(c.id).second) << c.id;
    EXPECT_EQ(stress_cases(true).size(), 4u);
    // The custom degenerate modifiers: parallel rows and many rows on one vertex.
    const auto pick = select_stress_cases(all, {"rows-parallel", "rows-one-vertex"});
    ASSERT_EQ(pick.size(), 2u);
    const Qp base = make_stress_qp(select_stress_cases(all, {"baseline-plane"})[0]);
    const Qp parallel = make_stress_qp(pick[0]);
    EXPECT_EQ(parallel.m(), base.m() + (base.m() + 1) / 2);
    const Qp one_vertex = make_stress_qp(pick[1]);
    EXPECT_EQ(one_vertex.m(), base.m() + 20);
    // The 20 extra rows touch the same three DOFs.
    std::set<long> vertices;
    for (Eigen::Index r = base.m(); r < one_vertex.m(); ++r)
        for (SpMat::InnerIterator it(one_vertex.J, r); it; ++it) vertices.insert(it.col() / 3);
    EXPECT_EQ(vertices.size(), 1u);
    // Same case, same QP.
    const Qp again = make_stress_qp(pick[1]);
    EXPECT_EQ((again.J - one_vertex.J).norm(), 0.0);
    EXPECT_EQ(again.c, one_vertex.c);
    // Selection by family, and a named error for an unknown name.
    EXPECT_EQ(select_stress_cases(all, {"infeasible"}).size(), 2u);
    try {
        select_stress_cases(all, {"no-such-case"});
        FAIL();
    } catch (const InputError& e) {
        EXPECT_EQ(std::string(e.what()).rfind(
                      "--cases: no-such-case: no stress case or family of that name; known: baseline-plane, ", 0),
                  0u);
    }
}

TEST(StressRun, QuickRunGivesHonestOutcomesAndWritesTheTable)
{
    const std::string dir = (std::filesystem::temp_directory_path() / "cb_test_stress").string();
    std::filesystem::remove_all(dir);
    StressOptions options;
    options.quick = true;
    options.solvers = {"active-set", "pgs"};
    options.time_limit_s = 2.0;
    options.out_dir = dir;
    std::ostringstream progress;
    options.progress = &progress;
    const StressReport report = run_stress(options);
    ASSERT_EQ(report.rows.size(), 8u);
    for (const StressRow& r : report.rows) {
        SCOPED_TRACE(r.solver + " x " + r.case_id + ": " + r.status + ": " + r.message);
        EXPECT_NE(r.status, "crashed");
        EXPECT_NE(r.status, "hung");
        EXPECT_NE(r.status, "error");
        if (r.status == "converged") {
            EXPECT_TRUE(r.status_confirmed);
            EXPECT_LE(r.accuracy, r.tol * (1 + 1e-9));
        } else {
            EXPECT_FALSE(r.message.empty());
        }
        EXPECT_TRUE(r.honest());
        if (r.case_id.rfind("infeasible", 0) == 0) {
            EXPECT_NE(r.status, "converged");
        }
        if (r.case_id == "baseline-plane") {
            EXPECT_EQ(r.status, "converged");
        }
    }
    const std::string lines_text = progress.str();
    EXPECT_EQ(std::count(lines_text.begin(), lines_text.end(), '\n'), 8) << lines_text;

    std::ifstream csv(dir + "/stability.csv");
    std::string header;
    std::getline(csv, header);
    EXPECT_EQ(header,
              "solver,case,severity,status,accuracy,tol,violation,nonfinite,monotone,time_s,iterations,"
              "status_confirmed,message,family,n,m,criterion,m_solved,solver_status,accuracy_solved,primal,energy_gap");
    long lines = 0;
    for (std::string line; std::getline(csv, line);) ++lines;
    EXPECT_EQ(lines, 8);
    std::ifstream md(dir + "/stability.md");
    const std::string text((std::istreambuf_iterator<char>(md)), std::istreambuf_iterator<char>());
    EXPECT_NE(text.find("| case | sev | n | m | active-set | pgs |"), std::string::npos);
    EXPECT_NE(text.find("None: every solver's \"converged\" held under the accuracy measure on the problem it solved."),
              std::string::npos);
    EXPECT_NE(text.find("## Accuracy of converged runs"), std::string::npos);
    // The reference (active-set on the original QP) gives every converged run an energy gap.
    for (const StressRow& r : report.rows) {
        if (r.status == "converged") {
            EXPECT_TRUE(std::isfinite(r.energy_gap)) << r.solver << " x " << r.case_id;
            EXPECT_LT(r.energy_gap, 1e-6) << r.solver << " x " << r.case_id;
        }
    }
    EXPECT_TRUE(std::filesystem::exists(dir + "/runs/baseline-plane__pgs.json"));
    std::filesystem::remove_all(dir);
}

TEST(StressRun, RecordsRowsDroppedByDecoupling)
{
    if (!builtin_registry().contains("mprgp") || !builtin_registry().create("mprgp", {})->requires_decoupled())
        GTEST_SKIP() << "no registered solver requiring decoupled rows";
    StressOptions options;
    options.solvers = {"mprgp"};
    options.cases = {"infeasible-1"};
    options.isolate = false;
    options.reference = false;  // no in-process CHOLMOD before the next test's forks
    options.time_limit_s = 2.0;
    const StressReport report = run_stress(options);
    ASSERT_EQ(report.rows.size(), 1u);
    const StressRow& r = report.rows[0];
    // The contradictory pair touches one vertex: decoupling keeps at most one of its rows.
    EXPECT_LT(r.m_solved, r.m);
    // An infeasible set is never "converged": at best the solver solved its reduced problem.
    EXPECT_NE(r.status, "converged") << r.message;
    if (r.solver_status == "converged") {
        EXPECT_EQ(r.status, "solved_relaxation");
        EXPECT_LE(r.accuracy_solved, r.tol * (1 + 1e-9));
        EXPECT_GT(r.accuracy, r.tol);
        EXPECT_TRUE(r.honest());
    }
    EXPECT_NE(stability_markdown(report).find(" (" + std::to_string(r.m_solved) + " rows) |"), std::string::npos);
}

TEST(StressCases, FemSimSnapshotsHaveContactsAndActiveSetConverges)
{
    const auto all = stress_cases(false);
    const auto fem = select_stress_cases(all, {"fem-sim"});
    ASSERT_EQ(fem.size(), 2u);
    EXPECT_EQ(fem[0].id, "fem-stiff-1e10");
    EXPECT_EQ(fem[1].id, "fem-fast-50ms");
    std::vector<long> rows;
    for (const StressCase& c : fem) {
        SCOPED_TRACE(c.id);
        const Qp qp = make_stress_qp(c);
        EXPECT_EQ(qp.n(), 750);  // the demo scene: two 4x4x4-cube boxes, 250 vertices
        EXPECT_GT(qp.m(), 0);
        EXPECT_EQ(qp.meta.at("stress").at("family"), "fem-sim");
        // The contacts matter: the unconstrained minimiser (active-set's first iterate) violates
        // some row, so the reference solve below adds rows to its working set (checked there).
        // (Since the simulator's solves meet the accuracy measure, the stiff scene's bodies rest
        // and its start point x0 may already be feasible.)
        rows.push_back(static_cast<long>(qp.m()));
    }
    StressOptions options;
    options.solvers = {"active-set"};
    options.cases = {"fem-sim"};
    // Isolated: an in-process CHOLMOD solve starts BLAS threads, and a later fork (the next
    // test's isolated runs) can then deadlock in the child.
    options.isolate = true;
    options.time_limit_s = 5.0;
    const StressReport report = run_stress(options);
    ASSERT_EQ(report.rows.size(), 2u);
    for (size_t i = 0; i < report.rows.size(); ++i) {
        const StressRow& r = report.rows[i];
        SCOPED_TRACE(r.case_id + ": " + r.status + ": " + r.message);
        EXPECT_EQ(r.family, "fem-sim");
        EXPECT_EQ(r.m, rows[i]);  // same (deterministic) QP as generated above
        EXPECT_EQ(r.status, "converged");
        EXPECT_TRUE(r.status_confirmed);
        EXPECT_TRUE(r.honest());
        EXPECT_LE(r.accuracy, r.tol * (1 + 1e-9));
        EXPECT_GT(r.iterations, 0);  // working-set additions: rows active at the solution
        EXPECT_FALSE(r.nonfinite);
    }
}

TEST(StressCases, StiffFemSnapshotIsNotSolvedAtItsStart)
{
    // fem-stiff-1e10 takes the step where the stiff boxes collide: the resting steps before it
    // are solved at x0 (0 iterations), which tested nothing about stiffness.
    const Qp qp = make_stress_qp(select_stress_cases(stress_cases(false), {"fem-stiff-1e10"}).at(0));
    // Jacobi-preconditioned, the stiff boxes' rigid modes stay 6e-4 of the scene size off after
    // 10000 iterations (the measure counts each body's motion); ichol with its default rigid
    // deflation resolves them.
    const SolverResult r = builtin_registry()
                               .create("mprgp-coupled", {{"tol", 1e-6}, {"max_iterations", 20000}, {"precond", "ichol"}})
                               ->solve(qp.view(), {});
    EXPECT_EQ(r.status, SolveStatus::CONVERGED) << r.message;
    EXPECT_GT(r.iterations, 50);  // 443 at the time of writing
}

TEST(StressCases, StiffDinoHasTheReproducersRows)
{
    // Needs the authors' dino (make paper-data) or the CGAL stand-in (make meshes).
    const char* home = std::getenv("HOME");
    const char* cache_env = std::getenv("CB_CACHE");
    const std::string cache =
        cache_env && *cache_env ? cache_env : std::string(home ? home : ".") + "/.cache/contactbench";
    if (!std::filesystem::exists(cache + "/paper-data/meshes/dino_1303_4014.abq"))
        GTEST_SKIP() << "the authors' dino_1303_4014.abq is not in " << cache << "/paper-data";
    const Qp qp = make_stress_qp(select_stress_cases(stress_cases(false), {"dino-stiff-1e10"}).at(0));
    EXPECT_EQ(qp.n(), 3909);
    EXPECT_EQ(qp.m(), 292);  // scenes/stiff_dino.json's frame 1 (mprgp steps frame 0; 263 before the measure
                             // counted the bodies' motion, which changed frame 0's step)
    const Vec d = qp.A.diagonal();
    EXPECT_GT(d.maxCoeff() / d.minCoeff(), 50.0);  // 90: graded tets, as in the snapshot
}

TEST(StressRun, SolverSpecsWithSettingsAndTheStiffSection)
{
    const std::string dir = (std::filesystem::temp_directory_path() / "cb_test_stress_spec").string();
    std::filesystem::remove_all(dir);
    StressOptions options;
    options.solvers = {"mprgp:precond=ichol:gamma=10", "cg"};
    options.cases = {"stiffness-1e4"};
    options.reference = false;
    options.time_limit_s = 5.0;
    options.out_dir = dir;
    const StressReport report = run_stress(options);
    ASSERT_EQ(report.rows.size(), 2u);
    EXPECT_EQ(report.rows[0].solver, "mprgp:precond=ichol:gamma=10");
    EXPECT_EQ(report.rows[0].status, "converged") << report.rows[0].message;
    std::ifstream run_file(dir + "/runs/stiffness-1e4__mprgp:precond=ichol:gamma=10.json");
    ASSERT_TRUE(run_file.good());
    const nlohmann::json run = nlohmann::json::parse(run_file);
    EXPECT_EQ(run.at("settings").at("precond"), "ichol");
    EXPECT_EQ(run.at("settings").at("gamma"), 10.0);
    EXPECT_GE(run.at("history").at("rows").size(), 2u);  // kept for the stiff families
    const std::string md = stability_markdown(report);
    EXPECT_NE(md.find("## Stiff families: time and iterations"), std::string::npos);
    EXPECT_NE(md.find("figures/stiff_family.png"), std::string::npos);
    EXPECT_NE(md.find(" / " + std::to_string(report.rows[0].iterations) + " / ok |"), std::string::npos) << md;
    std::filesystem::remove_all(dir);

    StressOptions bad;
    bad.solvers = {"mprgp:precond"};
    bad.cases = {"stiffness-1e4"};
    try {
        run_stress(bad);
        ADD_FAILURE() << "expected an InputError";
    } catch (const InputError& e) {
        EXPECT_STREQ(e.what(), "stress: --solvers: 'mprgp:precond': expected NAME[:key=value...], got 'precond'");
    }
}

TEST(StressReportText, ListsAWrongStatus)
{
    StressReport report;
    report.tol = 1e-6;
    StressRow r;
    r.solver = "liar";
    r.case_id = "baseline-plane";
    r.status = "unconfirmed";
    r.solver_status = "converged";
    r.criterion = "native";
    r.accuracy = 0.25;
    r.accuracy_solved = 0.25;
    r.primal = 0.125;
    r.energy_gap = NAN;
    r.tol = 1e-6;
    r.violation = 0.01;
    r.status_confirmed = false;
    r.message = "residual small";
    report.rows.push_back(r);
    EXPECT_FALSE(r.honest());
    const std::string md = stability_markdown(report);
    EXPECT_NE(md.find("| baseline-plane | 0 | 0 | 0 | **unconf 2.5e-01!** |"), std::string::npos) << md;
    EXPECT_NE(md.find("- liar on baseline-plane: status unconfirmed (criterion native), error 2.5e-01 (on the problem "
                      "it solved 2.5e-01) vs tol 1.0e-06, violation 1.0e-02: residual small"),
              std::string::npos)
        << md;
    const std::string csv = stability_csv(report.rows);
    EXPECT_NE(csv.find("\nliar,baseline-plane,0,unconfirmed,0.25,1e-06,0.01,false,true,0,0,false,residual small,,0,0,"
                       "native,0,converged,0.25,0.125,nan\n"),
              std::string::npos)
        << csv;
}

}  // namespace
}  // namespace cb
