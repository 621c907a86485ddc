// `contactbench judge SNAP SOLUTION`: the accuracy measure of any program's answer, with units,
// the verdict at tol, the objective and its gap to a cached reference (harness/judge.hpp).
#include "harness/cli.hpp"
#include "harness/commands.hpp"
#include "harness/judge.hpp"
#include "harness/length_scale.hpp"
#include "harness/results.hpp"
#include "problems/format_sniff.hpp"
#include "problems/qpsnap.hpp"
#include "problems/solution_io.hpp"
#include "solvers/core/format_number.hpp"

#include <cstdio>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <sstream>

namespace cb {

namespace {

const char* const JUDGE_USAGE =
    "contactbench judge SNAP SOLUTION [--lambda FILE] [--lambda-t FILE] [--tol T] [--record RUN.json]\n"
    "                    [--json FILE] [--length-scale L]\n"
    "  SOLUTION: a folder with x.{mtx,npy,txt} and optionally lambda.{mtx,npy,txt} (solve --save-solution),\n"
    "            or one file holding x: .npy, .mtx, or plain text (numbers separated by white space)\n"
    "  A frictional snapshot is judged with its friction when the solution gives lambda_t (2m tangential\n"
    "  multipliers: lambda_t.{mtx,npy,txt} in the folder, or --lambda-t); without it, on the frictionless\n"
    "  relaxation (mu = 0), and the output says so";

}  // namespace

int cmd_judge(const Args& args)
{
    const CommandLine cl("judge", args, {"--lambda", "--lambda-t", "--tol", "--record", "--json", "--length-scale"},
                         {});
    if (cl.help()) {
        std::cout << "usage: " << JUDGE_USAGE << "\n";
        return 0;
    }
    cl.expect_positional(2, 2, JUDGE_USAGE);
    const std::string snap = cl.positional()[0];
    const std::string solution = cl.positional()[1];
    JudgeOptions options;
    options.tol = cl.number("--tol", 0.0);
    if (cl.has("--tol") && !(options.tol > 0.0)) throw_input_error("judge", "--tol", "must be > 0");
    if (cl.has("--record")) {
        options.record_path = cl.value("--record");
        options.record = read_json_file(options.record_path);
    }

    expect_qpsnap(snap, "judge");
    Qp qp = read_qpsnap(snap);
    options.snapshot_hash = qpsnap_content_hash(snap);
    // The run's scene size when the user gave it to the run; else the problem's own (the same
    // rule as solve and run: harness/length_scale.hpp).
    GivenLength given;
    if (cl.has("--length-scale")) {
        given = {parse_length_scale("judge", cl.value("--length-scale")), "given"};
    } else if (options.record.is_object()) {
        const std::string source = options.record.value("length_scale_source", std::string());
        const nlohmann::json l = options.record.value("length_scale", nlohmann::json());
        if ((source == "given" || source == "suite") && l.is_number() && l.get<double>() > 0.0)
            given = {l.get<double>(), source};
    }
    fix_length_scale(qp, snap, options.snapshot_hash, given);
    const SolutionPoint point = read_solution(solution, qp.n(), qp.m(), cl.value("--lambda"), cl.value("--lambda-t"),
                                              long(qp.friction.T.rows()));
    const Judgement j = judge_point(qp, point, options);

    std::ostringstream out;
    out << "snapshot    " << snap << " (n " << qp.n() << ", m " << qp.m() << ")\n";
    out << "solution    x from " << point.x_path;
    if (!point.lambda_path.empty()) out << ", lambda from " << point.lambda_path;
    if (!point.lambda_t_path.empty()) out << ", lambda_t from " << point.lambda_t_path;
    out << (j.lambda_fitted
                ? (point.lambda_path.empty() ? "; lambda fitted (none given)"
                                             : "; lambda fitted (the given one missed tol, the fit did better)")
                : "")
        << "\n";
    out << "error       " << format_g(j.accuracy.max(), 3) << " of the scene size l = " << format_g(j.scale.length, 3)
        << " (" << j.scale.length_source << "); stationarity " << format_g(j.accuracy.stationarity, 3) << ", primal "
        << format_g(j.accuracy.primal, 3) << ", dual " << format_g(j.accuracy.dual, 3) << ", complementarity "
        << format_g(j.accuracy.complementarity, 3) << ", gap " << format_g(j.accuracy.gap, 3) << "\n";
    out << "units       stationarity, primal, dual, complementarity: lengths / l; gap: energy / (d_ref l^2), d_ref "
        << format_g(j.scale.stiffness, 3) << "\n";
    if (j.relaxation)
        out << "friction    no lambda_t given: judged on the frictionless relaxation (mu = 0), not on the frictional "
               "problem (give lambda_t.{mtx,npy,txt} in the folder, or --lambda-t)\n";
    else if (j.frictional)
        out << "friction    judged on the frictional problem; FCLIB relative error " << format_g(j.fclib_error, 3)
            << "\n";
    out << "verdict     "
        << (!j.meets_tol   ? "not converged"
            : j.relaxation ? "solved_relaxation (of the frictionless relaxation)"
                           : "converged")
        << " at tol " << format_g(j.tol, 3) << " (e " << (j.meets_tol ? "<=" : ">") << " tol)\n";
    if (!j.status.empty()) {
        out << "status      " << j.status << " (with the run's record " << options.record_path << ")";
        if (j.have_solved) out << "; error on the problem it solved " << format_g(j.accuracy_solved.max(), 3);
        out << "\n";
    }
    out << "objective   " << std::setprecision(10) << j.objective << ", violation " << format_g(j.violation, 3) << "\n";
    if (j.reference.is_object() && j.reference["objective"].is_number())
        out << "reference   F* " << std::setprecision(10) << j.reference["objective"].get<double>() << ", energy gap "
            << format_g(j.energy_gap, 3) << " (|F - F*| / (d_ref l^2))\n";
    else
        out << "reference   none cached (a suite with \"reference\": true computes one)\n";
    std::cout << out.str();

    if (cl.has("--json")) {
        nlohmann::json record = j.to_json();
        record["snapshot"] = {{"path", snap}, {"hash", options.snapshot_hash}, {"n", qp.n()}, {"m", qp.m()}};
        record["solution"] = {
            {"x", point.x_path},
            {"lambda", point.lambda_path.empty() ? nlohmann::json() : nlohmann::json(point.lambda_path)},
            {"lambda_t", point.lambda_t_path.empty() ? nlohmann::json() : nlohmann::json(point.lambda_t_path)}};
        if (!options.record_path.empty()) record["record"] = options.record_path;
        write_json_atomic(cl.value("--json"), record);
    }
    return 0;
}

}  // namespace cb
