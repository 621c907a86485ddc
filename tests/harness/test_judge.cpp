// `judge` measures a saved solution exactly as `solve` measured the run (every registry solver),
// rebuilds the run's status from its record, and refuses malformed solutions naming file and field.
#include "harness/commands.hpp"
#include "harness/judge.hpp"
#include "harness/results.hpp"
#include "harness/runner.hpp"
#include "problems/qpsnap.hpp"
#include "problems/solution_io.hpp"
#include "problems/synthetic.hpp"
#include "solvers/core/registry.hpp"

#include "tests/harness/cli_test_util.hpp"
#include "tests/solvers/friction_test_qps.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>

namespace fs = std::filesystem;
using namespace cb;

namespace {

const fs::path& judge_work_dir()
{
    static const fs::path dir = test::make_test_work_dir("judge");
    return dir;
}

/// The scratch folder goes when the tests end.
class JudgeCleanUp : public ::testing::Environment {
public:
    void TearDown() override { fs::remove_all(judge_work_dir()); }
};
const auto* const JUDGE_CLEAN_UP = ::testing::AddGlobalTestEnvironment(new JudgeCleanUp);

/// Runs a subcommand in this process with its standard output captured.
std::string run_command(int (*command)(const Args&), const Args& args)
{
    std::ostringstream captured;
    std::streambuf* old = std::cout.rdbuf(captured.rdbuf());
    try {
        EXPECT_EQ(command(args), 0);
    } catch (...) {
        std::cout.rdbuf(old);
        throw;
    }
    std::cout.rdbuf(old);
    return captured.str();
}

/// The snapshots every solver runs on: bounds, decoupled plane rows, coupled rows.
std::vector<std::string> snapshots()
{
    static std::vector<std::string> paths;
    if (!paths.empty()) return paths;
    const std::vector<std::pair<std::string, nlohmann::json>> families = {{"box", {{"nx", 2}, {"ny", 2}, {"nz", 2}}},
                                                                          {"plane", {{"nx", 2}, {"ny", 2}, {"nz", 2}}},
                                                                          {"coupled", nlohmann::json::object()}};
    for (const auto& [family, params] : families) {
        const fs::path p = judge_work_dir() / (family + ".qpsnap");
        write_qpsnap(p.string(), make_synthetic(family, params, 3));
        paths.push_back(p.string());
    }
    return paths;
}

void write_text(const fs::path& p, const std::string& text)
{
    std::ofstream out(p, std::ios::binary);
    out << text;
}

/// A float64 .npy vector (numpy's format 1.0), written by hand so the test needs no numpy.
void write_npy(const fs::path& p, const std::vector<double>& v, const std::string& descr = "<f8")
{
    std::string header =
        "{'descr': '" + descr + "', 'fortran_order': False, 'shape': (" + std::to_string(v.size()) + ",), }";
    while ((10 + header.size() + 1) % 64) header += ' ';
    header += '\n';
    std::string bytes = "\x93NUMPY";
    bytes += char(1);
    bytes += char(0);
    bytes += char(header.size() & 0xff);
    bytes += char(header.size() >> 8);
    bytes += header;
    bytes.append(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(double));
    write_text(p, bytes);
}

std::string input_error_of(const std::function<void()>& f)
{
    try {
        f();
    } catch (const InputError& e) {
        return e.what();
    }
    return "(no InputError)";
}

}  // namespace

// The acceptance test of issue 28: for every solver of the registry and three problem classes,
// judge on the saved solution gives solve's e to the last bit, the same verdict at tol, and with
// the record the same run status (solved_relaxation and unconfirmed included).
TEST(Judge, SameErrorVerdictAndStatusAsSolveForEveryRegistrySolver)
{
    int judged = 0;
    for (const std::string& snap : snapshots()) {
        for (const std::string& name : builtin_registry().names()) {
            if (builtin_registry().entry(name).needs_settings)
                continue;  // command: tests/python/test_command_solver.py
            SCOPED_TRACE(std::string(name).append(" on ").append(snap));
            const fs::path dir = judge_work_dir() / (fs::path(snap).stem().string() + "_" + name);
            const std::string record_path = (dir / "run.json").string();
            fs::create_directories(dir);
            run_command(cmd_solve, {snap, "--solver", name, "--set", "max_iterations=300", "--json", record_path,
                                    "--save-solution", (dir / "sol").string()});
            const nlohmann::json record = read_json_file(record_path);
            const std::string judge_json = (dir / "judge.json").string();
            run_command(cmd_judge, {snap, (dir / "sol").string(), "--record", record_path, "--json", judge_json});
            const nlohmann::json judged_record = read_json_file(judge_json);
            const double tol = record["accuracy_tol"].get<double>();
            if (record["accuracy"]["max"].is_null()) {
                EXPECT_TRUE(judged_record["accuracy"]["max"].is_null());
            } else {
                const double e_solve = record["accuracy"]["max"].get<double>();
                EXPECT_EQ(judged_record["accuracy"]["max"].get<double>(), e_solve);
                EXPECT_EQ(judged_record["verdict"] == "converged", e_solve <= tol * (1 + 1e-9));
            }
            EXPECT_EQ(judged_record["tol"].get<double>(), tol);
            EXPECT_EQ(judged_record["status"], record["status"]);
            // Without the record: the verdict on the point alone, never a run status.
            run_command(cmd_judge,
                        {snap, (dir / "sol").string(), "--tol", nlohmann::json(tol).dump(), "--json", judge_json});
            const nlohmann::json point_only = read_json_file(judge_json);
            EXPECT_TRUE(point_only["status"].is_null());
            EXPECT_EQ(point_only["accuracy"]["max"], judged_record["accuracy"]["max"]);
            ++judged;
        }
    }
    EXPECT_GE(judged, 3 * 7);  // the seven built-in solvers at least, on each snapshot
}

TEST(Judge, StatusesThatNeedTheRecordAppearOnlyWithIt)
{
    // mprgp decouples the coupled rows: a converged run on the decoupled QP misses tol on the original.
    const std::string snap = snapshots()[2];
    const fs::path dir = judge_work_dir() / "relaxation";
    fs::create_directories(dir);
    run_command(cmd_solve, {snap, "--solver", "mprgp", "--json", (dir / "run.json").string(), "--save-solution",
                            (dir / "sol").string()});
    const nlohmann::json record = read_json_file((dir / "run.json").string());
    ASSERT_EQ(record["status"], STATUS_SOLVED_RELAXATION);
    const Qp qp = read_qpsnap(snap);
    const SolutionPoint point = read_solution((dir / "sol").string(), qp.n(), qp.m());
    JudgeOptions options;
    options.look_up_reference = false;
    EXPECT_EQ(judge_point(qp, point, options).status, "");
    EXPECT_FALSE(judge_point(qp, point, options).meets_tol);
    options.record = record;
    options.record_path = "run.json";
    const Judgement with_record = judge_point(qp, point, options);
    EXPECT_EQ(with_record.status, STATUS_SOLVED_RELAXATION);
    EXPECT_LE(with_record.accuracy_solved.max(), 1e-6);
    // A record that claims convergence for this point on the unchanged problem: unconfirmed.
    nlohmann::json lie = record;
    lie.erase("solved_problem");
    options.record = lie;
    EXPECT_EQ(judge_point(qp, point, options).status, STATUS_UNCONFIRMED);
    // The record of another snapshot is refused.
    options.record = record;
    options.snapshot_hash = "0000000000000000";
    EXPECT_NE(input_error_of([&] {
                  judge_point(qp, point, options);
              }).find("run.json: /snapshot/hash: the run was on another snapshot"),
              std::string::npos);
}

TEST(Judge, ReadsNpyMatrixMarketAndTextTheSame)
{
    const std::string snap = snapshots()[0];
    const Qp qp = read_qpsnap(snap);
    const fs::path dir = judge_work_dir() / "formats";
    fs::create_directories(dir);
    run_command(cmd_solve, {snap, "--solver", "active-set", "--save-solution", (dir / "sol").string()});
    const SolutionPoint mtx = read_solution((dir / "sol").string(), qp.n(), qp.m());
    std::vector<double> x(mtx.x.data(), mtx.x.data() + mtx.x.size());
    write_npy(dir / "x.npy", x);
    std::ostringstream text;
    text << "# x of the box, one per line\n";
    text.precision(17);
    for (double v : x) text << v << "\n";
    write_text(dir / "x.txt", text.str());
    const SolutionPoint npy = read_solution((dir / "x.npy").string(), qp.n(), qp.m());
    const SolutionPoint txt = read_solution((dir / "x.txt").string(), qp.n(), qp.m());
    EXPECT_EQ((npy.x - mtx.x).cwiseAbs().maxCoeff(), 0.0);
    EXPECT_EQ((txt.x - mtx.x).cwiseAbs().maxCoeff(), 0.0);
    EXPECT_EQ(npy.lambda.size(), 0);
    // x alone: the measure fits the multipliers and reaches the same verdict.
    JudgeOptions options;
    options.look_up_reference = false;
    const Judgement with_lambda = judge_point(qp, mtx, options), fitted = judge_point(qp, npy, options);
    EXPECT_FALSE(with_lambda.lambda_fitted);
    EXPECT_TRUE(fitted.lambda_fitted);
    EXPECT_TRUE(with_lambda.meets_tol);
    EXPECT_TRUE(fitted.meets_tol);
    EXPECT_LE(fitted.accuracy.max(), 1e-6);
}

TEST(Judge, MalformedSolutionsNameTheFileAndTheField)
{
    const std::string snap = snapshots()[0];
    const Qp qp = read_qpsnap(snap);
    const long n = qp.n(), m = qp.m();
    const fs::path dir = judge_work_dir() / "malformed";
    fs::create_directories(dir);
    auto error_for = [&](const fs::path& p) { return input_error_of([&] { read_solution(p.string(), n, m); }); };
    write_npy(dir / "short.npy", std::vector<double>(static_cast<size_t>(n - 1), 0.0));
    EXPECT_EQ(error_for(dir / "short.npy"), (dir / "short.npy").string() + ": x: expected " + std::to_string(n) +
                                                " entries (n of the snapshot), got " + std::to_string(n - 1));
    std::vector<double> with_nan(static_cast<size_t>(n), 0.0);
    with_nan[5] = std::nan("");
    write_npy(dir / "nan.npy", with_nan);
    EXPECT_EQ(error_for(dir / "nan.npy"), (dir / "nan.npy").string() + ": x[5]: not finite (nan)");
    write_text(dir / "inf.txt", "1 2 inf\n");
    EXPECT_EQ(error_for(dir / "inf.txt"), (dir / "inf.txt").string() + ": x[2]: not finite (inf)");
    write_text(dir / "garbage.txt", "1.0\n2.0\nabc\n");
    EXPECT_EQ(error_for(dir / "garbage.txt"),
              (dir / "garbage.txt").string() + ": line 3: expected a number of x, got 'abc'");
    EXPECT_EQ(error_for(dir / "missing.npy"), (dir / "missing.npy").string() + ": x: no such file or folder");
    write_text(dir / "header.npy", std::string("\x93NUMPX\x01", 7) + '\0');  // a wrong magic
    EXPECT_EQ(error_for(dir / "header.npy"),
              (dir / "header.npy").string() + ": header: not a .npy file (no \\x93NUMPY magic)");
    write_npy(dir / "int.npy", std::vector<double>(static_cast<size_t>(n), 0.0), "<i8");
    EXPECT_NE(error_for(dir / "int.npy").find("int.npy: x: dtype '<i8' not supported"), std::string::npos);
    fs::create_directories(dir / "empty_folder");
    EXPECT_EQ(error_for(dir / "empty_folder"),
              (dir / "empty_folder").string() + ": x: missing: the folder has no x.mtx, x.npy or x.txt");
    // A folder with x right and lambda of the wrong length names lambda.
    fs::create_directories(dir / "bad_lambda");
    write_npy(dir / "bad_lambda" / "x.npy", std::vector<double>(static_cast<size_t>(n), 0.0));
    write_npy(dir / "bad_lambda" / "lambda.npy", std::vector<double>(static_cast<size_t>(m + 2), 0.0));
    EXPECT_EQ(error_for(dir / "bad_lambda"), (dir / "bad_lambda" / "lambda.npy").string() + ": lambda: expected " +
                                                 std::to_string(m) + " entries (m of the snapshot), got " +
                                                 std::to_string(m + 2));
}

// Issue 48: a frictional run's solution carries lambda_t (solve --save-solution writes it) and
// judge measures the friction with it, as solve did; without it judge says it judged the
// frictionless relaxation, and never calls the point converged.
TEST(Judge, FrictionalRunIsJudgedWithItsTangentialMultipliersOrNamedARelaxation)
{
    const fs::path dir = judge_work_dir() / "friction";
    fs::create_directories(dir);
    const std::string snap = (dir / "pushed.qpsnap").string();
    write_qpsnap(snap, testing_qps::pushed_plane(0.2, 0.5));
    const std::string record_path = (dir / "run.json").string(), sol = (dir / "sol").string();
    run_command(cmd_solve, {snap, "--solver", "nsgs-friction", "--set", "tol=1e-8", "--set", "max_iterations=100000",
                            "--json", record_path, "--save-solution", sol});
    const nlohmann::json record = read_json_file(record_path);
    ASSERT_EQ(record["status"], "converged") << record["message"];
    ASSERT_TRUE(fs::exists(dir / "sol" / "lambda_t.mtx"));

    const std::string judge_json = (dir / "judge.json").string();
    std::string text = run_command(cmd_judge, {snap, sol, "--record", record_path, "--json", judge_json});
    nlohmann::json judged = read_json_file(judge_json);
    EXPECT_EQ(judged["judged_problem"], "frictional");
    EXPECT_EQ(judged["accuracy"]["max"].get<double>(), record["accuracy"]["max"].get<double>());
    EXPECT_EQ(judged["accuracy"]["friction"].get<double>(), record["accuracy"]["friction"].get<double>());
    EXPECT_EQ(judged["fclib_error"].get<double>(), record["fclib_error"].get<double>());
    EXPECT_EQ(judged["verdict"], "converged");
    EXPECT_EQ(judged["status"], "converged");
    EXPECT_NE(text.find("friction    judged on the frictional problem; FCLIB relative error"), std::string::npos)
        << text;

    // Without lambda_t: the frictionless relaxation, said so, at best solved_relaxation.
    fs::remove(dir / "sol" / "lambda_t.mtx");
    text = run_command(cmd_judge, {snap, sol, "--record", record_path, "--json", judge_json});
    judged = read_json_file(judge_json);
    EXPECT_EQ(judged["judged_problem"], "frictionless_relaxation");
    EXPECT_FALSE(judged["accuracy"].contains("friction"));
    EXPECT_TRUE(judged["fclib_error"].is_null());
    EXPECT_NE(judged["verdict"], "converged");
    EXPECT_NE(judged["status"], "converged");
    EXPECT_NE(text.find("friction    no lambda_t given: judged on the frictionless relaxation (mu = 0), not on the "
                        "frictional problem"),
              std::string::npos)
        << text;
    // Given with --lambda-t, the same numbers as from the folder.
    run_command(cmd_solve, {snap, "--solver", "nsgs-friction", "--set", "tol=1e-8", "--set", "max_iterations=100000",
                            "--save-solution", (dir / "again").string()});
    run_command(cmd_judge, {snap, sol, "--lambda-t", (dir / "again" / "lambda_t.mtx").string(), "--record", record_path,
                            "--json", judge_json});
    EXPECT_EQ(read_json_file(judge_json)["accuracy"]["max"].get<double>(), record["accuracy"]["max"].get<double>());

    // A frictionless solver's run (solved_relaxation) is judged the same with or without a record.
    run_command(cmd_solve, {snap, "--solver", "pgs", "--set", "tol=1e-8", "--json", record_path, "--save-solution",
                            (dir / "pgs").string()});
    EXPECT_FALSE(fs::exists(dir / "pgs" / "lambda_t.mtx"));
    run_command(cmd_judge, {snap, (dir / "pgs").string(), "--record", record_path, "--json", judge_json});
    EXPECT_EQ(read_json_file(judge_json)["status"], read_json_file(record_path)["status"]);
    EXPECT_EQ(read_json_file(judge_json)["status"], "solved_relaxation");

    // lambda_t on a snapshot without tangent rows, or of the wrong size: refused, naming it.
    EXPECT_EQ(input_error_of([&] { read_solution(sol, 3, 1, "", (dir / "again" / "lambda_t.mtx").string(), 0); }),
              (dir / "again" / "lambda_t.mtx").string() +
                  ": lambda_t: given, but the snapshot has no friction (no tangent rows T): remove it, or judge the "
                  "frictional snapshot it answers");
    const Qp qp = read_qpsnap(snap);
    write_text(dir / "short.txt", "1 2 3\n");
    EXPECT_EQ(input_error_of([&] { read_solution(sol, qp.n(), qp.m(), "", (dir / "short.txt").string(), 2 * qp.m()); }),
              (dir / "short.txt").string() + ": lambda_t: expected " + std::to_string(2 * qp.m()) +
                  " entries (2m of the snapshot), got 3");
}
