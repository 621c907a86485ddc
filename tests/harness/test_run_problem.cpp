// The problem a solver is given (harness/run_problem): a decoupled run sees the kept rows of J and
// c and the original's A, b and x0 themselves, not copies (a copy of A was the largest array of a
// decoupled run's setup: 0.55 GB on a 1M-DOF frame).
#include "harness/run_problem.hpp"
#include "problems/synthetic.hpp"
#include "solvers/mprgp/decouple.hpp"

#include <gtest/gtest.h>

using namespace cb;

TEST(RunProblem, DecoupledRowsViewTheOriginalsAAndBAndX0)
{
    const Qp qp = make_synthetic("coupled", nlohmann::json::object(), 5);
    ASSERT_FALSE(is_decoupled(qp.J));
    RunOptions options;
    options.decouple = "authors";
    SolverProblem problem;
    choose_solver_problem(qp, false, options, problem);
    ASSERT_TRUE(problem.applied);
    ASSERT_LT(static_cast<Eigen::Index>(problem.kept_rows.size()), qp.m());
    const QpView view = problem.view();
    EXPECT_EQ(&view.A, &qp.A);
    EXPECT_EQ(&view.b, &qp.b);
    EXPECT_EQ(&view.x0, &qp.x0);
    EXPECT_EQ(view.length, &qp.length);
    // J and c: the kept rows, as select_rows() gives them.
    const Qp reference = select_rows(qp, problem.kept_rows);
    EXPECT_EQ(view.m(), reference.m());
    EXPECT_EQ(Eigen::MatrixXd(view.J), Eigen::MatrixXd(reference.J));
    EXPECT_EQ(view.c, reference.c);
    EXPECT_EQ(problem.decouple["rows_after"], reference.m());

    SolverProblem all;
    options.decouple = "none";
    choose_solver_problem(qp, false, options, all);
    EXPECT_FALSE(all.applied);
    EXPECT_EQ(&all.view().J, &qp.J);
}
