// Issue 48: the `command` solver hands its program the snapshot as the suite gives it (version 2,
// friction included) and judges what comes back: x and lambda_t on the frictional problem, x
// alone as a solution of the frictionless relaxation (docs/INTERFACES.md "The command protocol").
#include "harness/results.hpp"
#include "harness/runner.hpp"
#include "problems/qpsnap.hpp"
#include "tests/harness/shell_quoted.hpp"

#include "tests/harness/cli_test_util.hpp"
#include "tests/solvers/friction_test_qps.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>

namespace fs = std::filesystem;
using namespace cb;

namespace {

void write_vector(const fs::path& p, const Vec& v)
{
    std::ofstream out(p);
    char buffer[40];
    for (Eigen::Index i = 0; i < v.size(); ++i) {
        std::snprintf(buffer, sizeof buffer, "%.17g\n", v[i]);
        out << buffer;
    }
}

/// A program that keeps the snapshot it was given and answers with the files of `answer`.
fs::path copying_program(const fs::path& dir, const fs::path& answer, const fs::path& kept)
{
    const fs::path p = dir / "answer.sh";
    std::ofstream(p) << "#!/bin/sh\ncp \"$1\" " << test::shell_quoted(kept) << "\ncp " << test::shell_quoted(answer)
                     << "/* \"$2\"\n";
    fs::permissions(p, fs::perms::owner_all);
    return p;
}

}  // namespace

TEST(CommandFriction, ProgramGetsTheFrictionAndIsJudgedOnWhatItReturns)
{
    const fs::path dir = test::make_test_work_dir("command_friction");
    const Qp qp = testing_qps::pushed_plane(0.2, 0.5);
    const fs::path snap = dir / "pushed.qpsnap";
    write_qpsnap(snap.string(), qp);
    RunOptions quiet;
    quiet.record_history = false;
    // The answers: our NSGS on the frictional problem, active-set on its relaxation.
    const RunOutcome fric = run_solver(qp, "nsgs-friction", {{"tol", 1e-8}, {"max_iterations", 100000}}, quiet);
    ASSERT_EQ(fric.status, "converged") << fric.result.message;
    Qp relaxed = qp;
    relaxed.friction = Friction{};
    const RunOutcome frictionless = run_solver(relaxed, "active-set", {{"tol", 1e-10}}, quiet);
    ASSERT_EQ(frictionless.status, "converged");

    struct Case {
        const char* name;
        Vec x, lambda, lambda_t;
    };
    const Case cases[] = {{"with_lambda_t", fric.result.x, fric.lambda_full, fric.result.lambda_t},
                          {"x_only", frictionless.result.x, frictionless.lambda_full, Vec()}};
    for (const Case& c : cases) {
        SCOPED_TRACE(c.name);
        const fs::path answer = dir / c.name / "answer", kept = dir / c.name / "given.qpsnap";
        fs::create_directories(answer);
        write_vector(answer / "x.txt", c.x);
        write_vector(answer / "lambda.txt", c.lambda);
        if (c.lambda_t.size()) write_vector(answer / "lambda_t.txt", c.lambda_t);
        const fs::path program = copying_program(dir / c.name, answer, kept);
        const std::string argv = nlohmann::json({program.string(), "{snapshot}", "{out}"}).dump();
        const fs::path record_path = dir / c.name / "run.json";
        const test::Output o =
            test::run_captured(test::contactbench_binary() + " solve " + test::shell_quoted(snap) +
                                   " --solver command --set 'argv=" + argv +
                                   "' --set tol=1e-8 --set time_limit_s=60 --json " + test::shell_quoted(record_path),
                               dir);
        ASSERT_EQ(o.status, 0) << o.err;

        // The program was given the frictional snapshot, friction and all.
        const Qp given = read_qpsnap(kept.string());
        ASSERT_TRUE(given.frictional());
        EXPECT_EQ(given.friction.mu, qp.friction.mu);
        EXPECT_EQ(SpMat(given.friction.T - qp.friction.T).norm(), 0.0);
        EXPECT_EQ(given.friction.cT, qp.friction.cT);

        const nlohmann::json record = read_json_file(record_path.string());
        if (c.lambda_t.size()) {
            // x and lambda_t: judged on the frictional problem, as nsgs-friction's run was.
            EXPECT_EQ(record["status"], "converged") << record["message"];
            EXPECT_FALSE(record.contains("solved_problem"));
            EXPECT_NEAR(record["fclib_error"].get<double>(), fric.fclib_error, 1e-12);
            EXPECT_NEAR(record["accuracy"]["max"].get<double>(), fric.accuracy.max(), 1e-12);
        } else {
            // x alone: a solution of the frictionless relaxation, said so, never converged.
            EXPECT_EQ(record["solved_problem"], "frictionless");
            EXPECT_EQ(record["status"], "solved_relaxation") << record["message"];
            EXPECT_LE(record["accuracy_solved"]["max"].get<double>(), 1e-8);
        }
    }
    fs::remove_all(dir);
}
