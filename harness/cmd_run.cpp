// `contactbench run SUITE.json [--out DIR] [--shard i/N] [--force]`: every (snapshot, solver
// label) of a suite, one results file each, resumable, shardable (DESIGN.md "Runs and chains").
//
// Resume: a job is skipped when DIR/runs/<id>__<label>.json exists (--force reruns it). In a
// chain ("chain": true) warm state is carried per label from snapshot to snapshot, so a label's
// chain is rerun whole unless every one of its runs exists, and shards split a chain suite by
// label (label k runs in shard i iff k % N == i-1), never inside a chain. Otherwise job j
// (snapshot-major order: j = snapshot * labels + label) runs in shard i iff j % N == i-1.
#include "harness/cli.hpp"
#include "harness/commands.hpp"
#include "harness/process_pool.hpp"
#include "harness/provenance.hpp"
#include "harness/reference.hpp"
#include "harness/reference_prefetch.hpp"
#include "harness/results.hpp"
#include "harness/runner.hpp"
#include "harness/slurm.hpp"
#include "harness/suite.hpp"
#include "problems/qpsnap.hpp"
#include "solvers/decouple.hpp"  // select_rows
#include "solvers/registry.hpp"

#include <cstdio>
#include <filesystem>
#include <iostream>
#include <map>
#include <memory>
#include <optional>

namespace cb {

namespace fs = std::filesystem;

namespace {

const char* const kUsage = "contactbench run SUITE.json [--out DIR] [--shard i/N] [--force] [--jobs N [--jobs-timed]]";

struct Shard {
    long index = 1, count = 1;  ///< 1-based index of count
};

Shard parse_shard(const std::string& text)
{
    Shard s;
    const auto slash = text.find('/');
    char* end = nullptr;
    bool ok = slash != std::string::npos && slash > 0;
    if (ok) {
        // Keep the substrings alive while `end` points into them (ASan: stack-use-after-scope).
        const std::string index_text = text.substr(0, slash), count_text = text.substr(slash + 1);
        s.index = std::strtol(index_text.c_str(), &end, 10);
        ok = *end == '\0';
        s.count = std::strtol(count_text.c_str(), &end, 10);
        ok = ok && *end == '\0' && !count_text.empty();
    }
    if (!ok || s.count < 1 || s.index < 1 || s.index > s.count)
        throw_input_error("run", "--shard", "expected i/N with 1 <= i <= N, got '" + text + "'");
    return s;
}

/// A record with every schema key for a run that could not happen (unknown solver, bad settings).
nlohmann::json failed_record(const SuiteSolver& sv, const nlohmann::json& settings, const nlohmann::json& snapshot,
                             const std::string& status, const std::string& message, double tol)
{
    const nlohmann::json null_kkt = {{"stationarity", nullptr}, {"primal", nullptr}, {"dual", nullptr},
                                     {"complementarity", nullptr}, {"max", nullptr}};
    return {{"solver", sv.solver}, {"label", sv.label}, {"settings", settings}, {"snapshot", snapshot},
            {"decouple", {{"applied", false}}}, {"status", status}, {"criterion", ""}, {"message", message},
            {"iterations", 0}, {"objective", nullptr}, {"kkt", null_kkt}, {"kkt_relative", null_kkt},
            {"violation", nullptr}, {"native_residual", nullptr}, {"lambda_fitted", false}, {"nonfinite", false},
            {"monotone", true}, {"status_confirmed", true}, {"tol", tol}, {"counters", Counters{}.to_json()},
            {"time", {{"setup_s", 0.0}, {"solve_s", 0.0}, {"total_s", 0.0}, {"repeat", 0}}},
            {"info", nlohmann::json::object()}, {"provenance", provenance()}};
}

std::string sci(double v)
{
    char buffer[32];
    std::snprintf(buffer, sizeof(buffer), "%.2g", v);
    return buffer;
}

/// Warm state of one label along a chain.
struct WarmState {
    Vec lambda;
    Vec eigenvector;
    bool has_lambda = false;
};

} // namespace

int cmd_run(const Args& args)
{
    const CommandLine cl("run", args, {"--out", "--shard", "--jobs"}, {"--force", "--jobs-timed"});
    if (cl.help()) {
        std::cout << "usage: " << kUsage
                  << "\n\nRuns every (snapshot, solver label) of a suite; writes DIR/runs/<id>__<label>.json,\n"
                     "DIR/summary.csv, DIR/suite.json and DIR/provenance.json (DIR defaults to\n"
                     "results/<suite name>). Finished runs are skipped unless --force. --shard i/N runs\n"
                     "job j iff j % N == i-1; `contactbench merge` joins the shard folders. In a Slurm array\n"
                     "task without --shard, the shard comes from SLURM_ARRAY_TASK_ID/MIN/COUNT and the runs\n"
                     "go to DIR/shard-<i>-of-<N> (see `contactbench cluster --help`).\n"
                     "--jobs N runs N jobs at a time in child processes when the suite's times are not judged\n"
                     "(\"timed\": false); timed suites still run one at a time unless --jobs-timed. With\n"
                     "\"reference\": true, the reference solutions are computed N snapshots at a time first.\n";
        return 0;
    }
    cl.expect_positional(1, 1, kUsage);
    const Suite suite = load_suite(cl.positional()[0]);
    std::string out = cl.value("--out", "results/" + suite.name);
    Shard shard = cl.has("--shard") ? parse_shard(cl.value("--shard")) : Shard{};
    if (!cl.has("--shard")) {
        // A Slurm array task: its shard from the array variables, its own folder inside --out.
        if (const std::optional<ArrayShard> task = shard_from_slurm(slurm_environment())) {
            shard = {task->index, task->count};
            out = (fs::path(out) / shard_folder_name(task->index, task->count)).string();
            std::cerr << "run: Slurm array task " << slurm_environment()["SLURM_ARRAY_TASK_ID"] << ": shard "
                      << shard.index << "/" << shard.count << " -> " << out << "\n";
        }
    }
    const bool force = cl.has("--force");
    const long jobs = cl.integer("--jobs", 1);
    if (jobs < 1) throw_input_error("run", "--jobs", "must be >= 1, got " + std::to_string(jobs));
    std::string jobs_note;
    ProcessPool pool(concurrent_jobs(jobs, suite.timed, suite.chain, cl.has("--jobs-timed"), jobs_note));
    if (!jobs_note.empty()) std::cerr << "run: " << jobs_note << "\n";
    const std::vector<SuiteSnapshot> snapshots = resolve_snapshots(suite);
    const auto& registry = builtin_registry();
    fs::create_directories(fs::path(out) / "runs");

    const size_t labels = suite.solvers.size();
    auto in_shard = [&](size_t s, size_t v) {
        const size_t key = suite.chain ? v : s * labels + v;
        return static_cast<long>(key % static_cast<size_t>(shard.count)) == shard.index - 1;
    };
    auto run_path = [&](size_t s, size_t v) {
        return (fs::path(out) / "runs" / run_file_name(snapshots[s].id, suite.solvers[v].label)).string();
    };
    // Which jobs run: chains whole per label, others one by one.
    std::vector<std::vector<bool>> todo(snapshots.size(), std::vector<bool>(labels, false));
    size_t total = 0;
    for (size_t v = 0; v < labels; ++v) {
        bool chain_complete = true;
        for (size_t s = 0; s < snapshots.size(); ++s)
            if (in_shard(s, v) && !fs::exists(run_path(s, v))) chain_complete = false;
        for (size_t s = 0; s < snapshots.size(); ++s) {
            if (!in_shard(s, v)) continue;
            ++total;
            todo[s][v] = force || (suite.chain ? !chain_complete : !fs::exists(run_path(s, v)));
        }
    }

    if (suite.reference && jobs > 1) {  // untimed work: N snapshots at a time, before the runs
        const size_t prefetched = prefetch_references(suite, snapshots, todo, jobs);
        std::cerr << "run: --jobs " << jobs << ": reference solutions of " << prefetched << " snapshot(s) computed "
                  << jobs << " at a time before the runs\n";
    }
    RunOptions options;
    options.history_max = suite.history_max;
    options.decouple = suite.decouple;
    options.decouple_seed = suite.decouple_seed;
    options.repeat = suite.repeat;
    std::map<std::string, nlohmann::json> references;  // by key, within this process
    std::map<std::string, WarmState> warm;            // by label
    size_t done = 0, ran = 0;
    for (size_t s = 0; s < snapshots.size(); ++s) {
        bool any = false;
        for (size_t v = 0; v < labels; ++v) any = any || todo[s][v];
        std::unique_ptr<Qp> qp;
        nlohmann::json info;
        const SuiteSnapshot& snap = snapshots[s];
        std::string load_error;  // a bad snapshot fails its runs, not the suite
        if (any) {
            try {
                qp = std::make_unique<Qp>(read_qpsnap(snap.path));
                info = {{"id", snap.id}, {"path", snap.path}, {"hash", qpsnap_content_hash(snap.path)},
                        {"n", qp->n()}, {"m", qp->m()}, {"meta", qp->meta}, {"generated", snap.generated}};
            } catch (const InputError& e) {
                load_error = e.what();
                info = {{"id", snap.id}, {"path", snap.path}, {"generated", snap.generated}};
            }
        }
        for (size_t v = 0; v < labels; ++v) {
            if (!in_shard(s, v)) continue;
            ++done;
            const SuiteSolver& sv = suite.solvers[v];
            const std::string prefix = "[" + std::to_string(done) + "/" + std::to_string(total) + "] " + snap.id +
                                       " x " + sv.label + ": ";
            if (!todo[s][v]) {
                std::cerr << prefix << "done before, skipped\n";
                continue;
            }
            if (pool.delegate()) {  // --jobs: a child process does this job
                ++ran;
                continue;
            }
            nlohmann::json settings = sv.settings;
            // Suite-wide tol and time limit are defaults: a solver's own setting wins.
            if (!settings.contains("tol")) settings["tol"] = suite.tol;
            if (!settings.contains("time_limit_s")) settings["time_limit_s"] = suite.time_limit_s;
            nlohmann::json record;
            if (!load_error.empty()) {
                record = failed_record(sv, settings, info, "invalid_input", load_error, suite.tol);
            } else if (!registry.contains(sv.solver)) {
                std::string known;
                for (const auto& n : registry.names()) known += (known.empty() ? "" : ", ") + n;
                record = failed_record(sv, settings, info, "invalid_input",
                                       "solver '" + sv.solver + "' is not registered; known: " + known, suite.tol);
            } else {
                try {
                    SolveContext context;
                    WarmState& state = warm[sv.label];
                    if (suite.chain) {
                        context.eigenvector = &state.eigenvector;
                        if (state.has_lambda) context.lambda0 = &state.lambda;
                    }
                    RunOutcome run = run_solver(*qp, sv.solver, settings, options, info, context);
                    if (suite.chain) {
                        state.lambda = run.lambda_full;  // original rows: matched by index next step
                        state.has_lambda = run.lambda_full.size() > 0;
                    }
                    record = std::move(run.record);
                    const std::vector<int> kept_rows = std::move(run.kept_rows);
                    if (suite.reference) {
                        // F* of the QP the solver saw (decoupled or not).
                        std::string key = info["hash"].get<std::string>();
                        const nlohmann::json& dec = record["decouple"];
                        const bool decoupled = dec.value("applied", false);
                        if (decoupled) key += "-" + dec["order"].get<std::string>() + "-" + dec["seed"].dump();
                        if (!references.count(key)) {
                            if (decoupled) {
                                references[key] = reference_solution(select_rows(*qp, kept_rows), key);
                            } else {
                                references[key] = reference_solution(*qp, key);
                            }
                        }
                        attach_reference(record, references[key]);
                    }
                } catch (const InputError& e) {
                    record = failed_record(sv, settings, info, "invalid_input", e.what(), suite.tol);
                } catch (const std::exception& e) {
                    record = failed_record(sv, settings, info, "internal_error", e.what(), suite.tol);
                }
            }
            record["label"] = sv.label;
            record["suite"] = suite.name;
            record["mode"] = suite.chain ? "chain" : "cold";
            if (pool.parallel()) record["concurrent_jobs"] = jobs;  // its time shared the machine
            write_json_atomic(run_path(s, v), record);
            ++ran;
            std::string line = prefix + record["status"].get<std::string>();
            if (record["kkt_relative"]["max"].is_number()) {
                line += " in " + record["iterations"].dump() + " it, kkt_rel " +
                        sci(record["kkt_relative"]["max"].get<double>()) + ", " +
                        sci(record["time"]["total_s"].get<double>()) + " s";
                if (!record.value("status_confirmed", true)) line += " (NOT CONFIRMED)";
            } else {
                line += ": " + record["message"].get<std::string>();
            }
            std::cerr << line << "\n";
            pool.job_done();  // a child ends here
        }
    }
    if (const size_t failed = pool.wait_all())
        throw std::runtime_error(std::to_string(failed) + " parallel job(s) failed; rerun to redo them (finished runs are kept)");
    const size_t runs = write_summary(out, suite.name);
    write_json_atomic((fs::path(out) / "suite.json").string(), suite.raw);
    write_json_atomic((fs::path(out) / "provenance.json").string(), provenance());
    std::cerr << "ran " << ran << " of " << total << " jobs; " << runs << " runs in " << out << "/summary.csv\n";
    return 0;
}

} // namespace cb
