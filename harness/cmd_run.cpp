// `contactbench run SUITE.json [--out DIR] [--shard i/N] [--force] [--fresh]`: every (snapshot,
// solver label) of a suite, one results file each, resumable, shardable (DESIGN.md "Runs and chains").
//
// Resume: a job is skipped when DIR/runs/<id>__<label>.json holds a final run of the same identity
// (runner.hpp run_identity: snapshot content, solver, settings, suite entry, build); any other
// stored run is redone, and so is one that failed because its snapshot could not be read or on
// an internal error ("final": false). One DIR holds one suite (or one shard of it): run files of
// other jobs make `run` refuse (exit 2) unless --fresh. A lock (flock on DIR/.lock) keeps two
// runs on one DIR apart. In a chain ("chain": true) warm state is carried per label from
// snapshot to snapshot, so a label's chain is rerun whole unless every one of its runs is
// reusable, and shards split a chain suite by label (label k runs in shard i iff k % N == i-1),
// never inside a chain. Otherwise job j (snapshot-major order: j = snapshot * labels + label)
// runs in shard i iff j % N == i-1.
#include "harness/cli.hpp"
#include "harness/commands.hpp"
#include "harness/length_scale.hpp"
#include "harness/process_pool.hpp"
#include "harness/provenance.hpp"
#include "harness/reference.hpp"
#include "harness/reference_prefetch.hpp"
#include "harness/results.hpp"
#include "harness/run_lock.hpp"
#include "harness/run_plan.hpp"
#include "harness/run_record.hpp"
#include "harness/run_summary_table.hpp"
#include "harness/runner.hpp"
#include "harness/slurm.hpp"
#include "harness/suite.hpp"
#include "problems/format_sniff.hpp"
#include "problems/output_folder.hpp"
#include "problems/qpsnap.hpp"
#include "solvers/core/format_number.hpp"
#include "solvers/core/registry.hpp"

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fcntl.h>
#include <filesystem>
#include <iostream>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <sys/file.h>
#include <sys/stat.h>
#include <thread>
#include <unistd.h>

namespace cb {

namespace fs = std::filesystem;

namespace {

const char* const RUN_USAGE =
    "contactbench run SUITE.json [--out DIR] [--shard i/N] [--force] [--fresh] [--jobs N [--jobs-timed]]\n"
    "                 [--length-scale L]";

const char* const HELP = "\n\nRuns every (snapshot, solver label) of a suite; writes DIR/runs/<id>__<label>.json,\n"
                         "DIR/summary.csv, DIR/suite.json and DIR/provenance.json (DIR defaults to\n"
                         "results/<suite name>). A finished run is reused only when its snapshot content,\n"
                         "solver, settings, suite entry and build are unchanged; --force reruns every job,\n"
                         "--fresh first discards every result in DIR (needed when DIR holds another suite\n"
                         "or shard). --shard i/N runs job j iff j % N == i-1; `contactbench merge` joins\n"
                         "the shard folders. In a Slurm array task without --shard, the shard comes from\n"
                         "SLURM_ARRAY_TASK_ID/MIN/COUNT and the runs go to DIR/shard-<i>-of-<N> (see\n"
                         "`contactbench cluster --help`).\n"
                         "--jobs N runs N jobs at a time in child processes when the suite's times are not judged\n"
                         "(\"timed\": false); timed suites still run one at a time unless --jobs-timed. With\n"
                         "\"reference\": true, the reference solutions are computed N snapshots at a time first.\n";

/// The suite that DIR holds results of: DIR/suite.json, else DIR/suite.pending.json (a run that
/// was interrupted), else null.
nlohmann::json suite_in(const std::string& out)
{
    for (const char* name : {"suite.json", "suite.pending.json"}) {
        const fs::path p = fs::path(out) / name;
        if (fs::exists(fs::symlink_status(p))) return read_json_file(p.string());
    }
    return nullptr;
}

/// The files `run` writes at DIR's top level.
const char* const TOP_FILES[] = {"summary.csv", "suite.json", "suite.pending.json", "provenance.json", "jobs.json"};

/// --fresh: removes what `run` writes in DIR (and nothing else). open_out_dir has checked that
/// none of it is a link or a special file, and that DIR/runs is a real folder.
void clear_out_dir(const std::string& out)
{
    std::error_code ec;
    const fs::path runs = fs::path(out) / "runs";
    if (fs::symlink_status(runs, ec).type() == fs::file_type::directory)
        for (const auto& entry : fs::directory_iterator(runs))
            if (entry.path().extension() == ".json") fs::remove(entry.path(), ec);
    for (const char* name : TOP_FILES) fs::remove(fs::path(out) / name, ec);
}

/// Warm state of one label along a chain.
struct WarmState {
    Vec lambda;
    Vec eigenvector;
    bool has_lambda = false;
};

/// Where the results go and which shard this is: --out and --shard, or a Slurm array task's
/// shard (its own folder inside --out).
void choose_out_and_shard(const CommandLine& cl, const Suite& suite, std::string& out, Shard& shard)
{
    out = cl.path("--out", "results/" + suite.name);
    shard = cl.has("--shard") ? parse_shard(cl.value("--shard")) : Shard{};
    if (cl.has("--shard")) return;
    if (const std::optional<ArrayShard> task = shard_from_slurm(slurm_environment())) {
        shard = {task->index, task->count};
        out = (fs::path(out) / shard_folder_name(task->index, task->count)).string();
        std::cerr << "run: Slurm array task " << slurm_environment()["SLURM_ARRAY_TASK_ID"] << ": shard " << shard.index
                  << "/" << shard.count << " -> " << out << "\n";
    }
}

/// Creates DIR/runs, locks DIR, and with --fresh clears what an earlier run wrote. Nothing `run`
/// writes or deletes in DIR may be a link or a special file (problems/output_folder.hpp): a
/// planted DIR/runs link would send the run files, and --fresh's deletions, elsewhere.
void open_out_dir(const std::string& out, bool fresh)
{
    std::error_code ec;
    fs::create_directories(out, ec);
    if (ec) throw_input_error(out, "--out", "cannot create the results folder: " + ec.message());
    make_output_subfolder(out, "runs");
    for (const char* name : TOP_FILES) check_output_entry((fs::path(out) / name).string());
    check_output_entries((fs::path(out) / "runs").string(),
                         [](const std::string& name) { return fs::path(name).extension() == ".json"; });
    lock_output_folder(out, "run");
    if (fresh) clear_out_dir(out);
}

/// One DIR holds one suite (or shard): another suite's results, or run files that are no job of
/// this one, are never mixed into this summary (InputError, with how to force).
void refuse_foreign_results(const RunPlan& plan, const std::string& out, const std::string& shard_text)
{
    const Suite& suite = plan.suite();
    const std::string how_to_force = "use another --out, or --fresh to discard the results in " + out;
    const nlohmann::json held = suite_in(out);
    if (held.is_object() && held.value("name", std::string()) != suite.name)
        throw_input_error(out, "suite.json",
                          "holds results of suite '" + held.value("name", std::string("?")) + "', not '" + suite.name +
                              "'; " + how_to_force);
    const std::set<std::string> job_files = plan.job_files();
    std::vector<std::string> foreign;
    for (const auto& entry : fs::directory_iterator(fs::path(out) / "runs"))
        if (entry.path().extension() == ".json" && !job_files.count(entry.path().filename().string()))
            foreign.push_back(entry.path().string());
    std::sort(foreign.begin(), foreign.end());
    if (!foreign.empty())
        throw_input_error(
            foreign.front(), "",
            "not a job of suite '" + suite.name + "'" + (plan.shard().count > 1 ? " shard " + shard_text : "") + " (" +
                std::to_string(foreign.size()) + " such run files: an earlier suite or shard?); " + how_to_force);
}

/// A snapshot loaded for its jobs: the QP and the record's "snapshot" object, or the error that
/// fails its runs (a bad snapshot fails its runs, not the suite).
struct LoadedSnapshot {
    std::unique_ptr<Qp> qp;
    nlohmann::json info;
    std::string error;
};

LoadedSnapshot load_snapshot(const SuiteSnapshot& snap, const nlohmann::json& hash, const Suite& suite)
{
    LoadedSnapshot loaded;
    try {
        expect_qpsnap(snap.path, "run");
        loaded.qp = std::make_unique<Qp>(read_qpsnap(snap.path));
        // The scene size, fixed before any of the snapshot's jobs (the children of --jobs inherit it).
        const std::string key = hash.is_string() ? hash.get<std::string>() : qpsnap_content_hash(snap.path);
        fix_length_scale(*loaded.qp, snap.path, key, GivenLength{suite.length_scale, suite.length_scale_source});
        loaded.info = {{"id", snap.id},
                       {"path", snap.path},
                       {"hash", key},
                       {"n", loaded.qp->n()},
                       {"m", loaded.qp->m()},
                       {"meta", loaded.qp->meta},
                       {"generated", snap.generated}};
    } catch (const InputError& e) {
        loaded.error = e.what();
        loaded.info = {{"id", snap.id}, {"path", snap.path}, {"generated", snap.generated}};
    }
    return loaded;
}

/// What the jobs of one process share: the run options, the references computed so far (by
/// snapshot hash) and the warm state of each label along a chain.
struct JobContext {
    RunOptions options;
    std::map<std::string, nlohmann::json> references;
    std::map<std::string, WarmState> warm;
};

/// The record of one job: the run, or the record of a run that could not happen.
nlohmann::json run_job(const Suite& suite, const SuiteSolver& sv, const nlohmann::json& settings,
                       const LoadedSnapshot& snapshot, JobContext& jobs)
{
    const auto& registry = builtin_registry();
    const nlohmann::json& info = snapshot.info;
    if (!snapshot.error.empty()) {
        nlohmann::json record =
            failed_record(sv.solver, sv.label, settings, info, "invalid_input", snapshot.error, suite.tol);
        record["final"] = false;  // the snapshot could not be read: retried on resume
        return record;
    }
    if (!registry.contains(sv.solver)) {
        std::string known;
        for (const auto& n : registry.names()) known += (known.empty() ? "" : ", ") + n;
        return failed_record(sv.solver, sv.label, settings, info, "invalid_input",
                             "solver '" + sv.solver + "' is not registered; known: " + known, suite.tol);
    }
    try {
        SolveContext context;
        WarmState& state = jobs.warm[sv.label];
        if (suite.chain) {
            context.eigenvector = &state.eigenvector;
            if (state.has_lambda) context.lambda0 = &state.lambda;
        }
        RunOutcome run = run_solver(*snapshot.qp, sv.solver, settings, jobs.options, info, context);
        if (suite.chain) {
            state.lambda = run.lambda_full;  // original rows: matched by index next step
            state.has_lambda = run.lambda_full.size() > 0;
        }
        nlohmann::json record = std::move(run.record);
        if (suite.reference) {
            // F* of the QP in the file (docs/accuracy.md), whatever rows the solver kept.
            const std::string key = info["hash"].get<std::string>();
            if (!jobs.references.count(key)) jobs.references[key] = reference_solution(*snapshot.qp, key);
            attach_reference(record, jobs.references[key]);
        }
        return record;
    } catch (const InputError& e) {
        return failed_record(sv.solver, sv.label, settings, info, "invalid_input", e.what(), suite.tol);
    } catch (const std::exception& e) {
        nlohmann::json record =
            failed_record(sv.solver, sv.label, settings, info, "internal_error", e.what(), suite.tol);
        record["final"] = false;  // a harness failure (out of memory, ...): retried on resume
        return record;
    }
}

/// The progress line of a finished job.
std::string progress_line(const std::string& prefix, const nlohmann::json& record)
{
    std::string line = prefix + record["status"].get<std::string>();
    if (record["accuracy"]["max"].is_number()) {
        line += " in " + record["iterations"].dump() + " it, accuracy " +
                format_g(record["accuracy"]["max"].get<double>(), 2) + ", " +
                format_g(record["time"]["total_s"].get<double>(), 2) + " s";
        if (!record.value("status_confirmed", true)) line += " (NOT CONFIRMED)";
    } else {
        line += ": " + record["message"].get<std::string>();
    }
    return line;
}

/// Runs (or hands to a child) every job of the plan that needs running, snapshot by snapshot;
/// returns the number run.
size_t run_jobs(const RunPlan& plan, ProcessPool& pool, long jobs)
{
    const Suite& suite = plan.suite();
    JobContext context;
    context.options.history_max = suite.history_max;
    context.options.decouple = suite.decouple;
    context.options.decouple_seed = suite.decouple_seed;
    context.options.repeat = suite.repeat;
    size_t done = 0, ran = 0;
    for (size_t s = 0; s < plan.snapshots().size(); ++s) {
        const SuiteSnapshot& snap = plan.snapshots()[s];
        const LoadedSnapshot snapshot = plan.any_todo(s) ? load_snapshot(snap, plan.hash(s), suite) : LoadedSnapshot{};
        for (size_t v = 0; v < plan.labels(); ++v) {
            if (!plan.in_shard(s, v)) continue;
            ++done;
            const SuiteSolver& sv = suite.solvers[v];
            const std::string prefix = "[" + std::to_string(done) + "/" + std::to_string(plan.total()) + "] " +
                                       snap.id + " x " + sv.label + ": ";
            if (!plan.todo(s, v)) {
                std::cerr << prefix << "done before, skipped\n";
                continue;
            }
            if (!plan.stale(s, v).empty() && plan.stale(s, v) != "missing")
                std::cerr << prefix << "stored run not reused: " << plan.stale(s, v) << "\n";
            if (pool.delegate()) {  // --jobs: a child process does this job
                ++ran;
                continue;
            }
            // The suite's tol and time limit are in (settings_with_defaults), as the identity records them.
            nlohmann::json record = run_job(suite, sv, plan.settings_of(v), snapshot, context);
            record["label"] = sv.label;
            record["suite"] = suite.name;
            record["mode"] = suite.chain ? "chain" : "cold";
            if (pool.parallel()) record["concurrent_jobs"] = jobs;  // its time shared the machine
            // Final: the solver's outcome, or a refusal that the identity fully determines (an
            // unregistered solver, bad settings: a rebuild or an edit changes the identity).
            if (!record.contains("final")) record["final"] = true;
            record["identity"] = plan.identity_of(s, v);
            write_json_atomic(plan.run_path(s, v), record);
            ++ran;
            std::cerr << progress_line(prefix, record) << "\n";
            pool.job_done();  // a child ends here
        }
    }
    return ran;
}

/// DIR/jobs.json: which jobs this folder holds, for `merge` to check that the shards are complete
/// and of one suite.
void write_jobs_file(const RunPlan& plan, const std::string& out)
{
    const Suite& suite = plan.suite();
    size_t all_jobs = 0, done_jobs = 0, final_jobs = 0;
    for (size_t s = 0; s < plan.snapshots().size(); ++s)
        for (size_t v = 0; v < plan.labels(); ++v)
            all_jobs += solver_applies(suite.solvers[v], plan.snapshots()[s].id) ? 1 : 0;
    nlohmann::json shard_jobs = nlohmann::json::array();
    for (size_t s = 0; s < plan.snapshots().size(); ++s)
        for (size_t v = 0; v < plan.labels(); ++v)
            if (plan.in_shard(s, v)) {
                shard_jobs.push_back(run_file_name(plan.snapshots()[s].id, suite.solvers[v].label));
                if (fs::exists(plan.run_path(s, v))) ++done_jobs;
                try {
                    if (read_json_file(plan.run_path(s, v)).value("final", true)) ++final_jobs;
                } catch (const InputError&) {
                }
            }
    write_json_atomic((fs::path(out) / "jobs.json").string(),
                      {{"suite", suite.name},
                       {"suite_hash", fnv1a_hex(suite.raw.dump())},
                       {"shard", {{"index", plan.shard().index}, {"count", plan.shard().count}}},
                       {"all_jobs", all_jobs},
                       {"jobs", shard_jobs},
                       {"complete", done_jobs == shard_jobs.size()},
                       {"retry", shard_jobs.size() - final_jobs}});
}

}  // namespace

int cmd_run(const Args& args)
{
    const CommandLine cl("run", args, {"--out", "--shard", "--jobs", "--length-scale"},
                         {"--force", "--fresh", "--jobs-timed"});
    if (cl.help()) {
        std::cout << "usage: " << RUN_USAGE << HELP;
        return 0;
    }
    cl.expect_positional(1, 1, RUN_USAGE);
    Suite suite = load_suite(cl.positional()[0]);
    if (cl.has("--length-scale")) {
        suite.length_scale = parse_length_scale("run", cl.value("--length-scale"));
        suite.length_scale_source = "given";
    }
    for (const std::string& notice : drop_unbuilt_optional_solvers(suite, builtin_registry().names()))
        std::cerr << "run: " << notice << "\n";
    std::string out;
    Shard shard;
    choose_out_and_shard(cl, suite, out, shard);
    const long jobs = cl.integer("--jobs", 1);
    if (jobs < 1) throw_input_error("run", "--jobs", "must be >= 1, got " + std::to_string(jobs));
    std::string jobs_note;
    ProcessPool pool(concurrent_jobs(jobs, suite.timed, suite.chain, cl.has("--jobs-timed"), jobs_note));
    if (!jobs_note.empty()) std::cerr << "run: " << jobs_note << "\n";
    RunPlan plan(suite, resolve_snapshots(suite), shard, out);
    const std::string crowded =
        oversubscription_warning(pool.parallel() ? jobs : 1, most_threads(suite), std::thread::hardware_concurrency());
    if (!crowded.empty()) std::cerr << "run: " << crowded << "\n";
    open_out_dir(out, cl.has("--fresh"));
    refuse_foreign_results(plan, out, cl.value("--shard"));

    plan.hash_snapshots();
    plan.find_stale();
    plan.choose(cl.has("--force"));
    // suite.json describes what DIR holds: while jobs of this suite run, it is suite.pending.json.
    if (plan.any_todo()) {
        write_json_atomic((fs::path(out) / "suite.pending.json").string(), suite.raw);
        std::error_code ec;
        fs::remove(fs::path(out) / "suite.json", ec);
    }
    if (suite.reference && jobs > 1) {  // untimed work: N snapshots at a time, before the runs
        const size_t prefetched = prefetch_references(suite, plan.snapshots(), plan.todo_table(), jobs);
        std::cerr << "run: --jobs " << jobs << ": reference solutions of " << prefetched << " snapshot(s) computed "
                  << jobs << " at a time before the runs\n";
    }
    const size_t ran = run_jobs(plan, pool, jobs);
    if (const size_t failed = pool.wait_all())
        throw std::runtime_error(std::to_string(failed) +
                                 " parallel job(s) failed; rerun to redo them (finished runs are kept)");
    const size_t runs = write_summary(out, suite.name);
    write_jobs_file(plan, out);
    write_json_atomic((fs::path(out) / "provenance.json").string(), provenance());
    write_json_atomic((fs::path(out) / "suite.json").string(), suite.raw);
    std::error_code ec;
    fs::remove(fs::path(out) / "suite.pending.json", ec);
    std::cerr << "ran " << ran << " of " << plan.total() << " jobs; " << runs << " runs in " << out << "/summary.csv\n";
    release_output_folder_lock();                       // the folder is whole: the report may read it
    print_run_end(out, suite.time_limit_s, std::cout);  // the table per solver and the HTML report
    return 0;
}

}  // namespace cb
