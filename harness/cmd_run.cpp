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
#include "harness/process_pool.hpp"
#include "harness/provenance.hpp"
#include "harness/reference.hpp"
#include "harness/reference_prefetch.hpp"
#include "harness/results.hpp"
#include "harness/runner.hpp"
#include "harness/slurm.hpp"
#include "harness/suite.hpp"
#include "problems/qpsnap.hpp"
#include "solvers/registry.hpp"

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
#include <unistd.h>

namespace cb {

namespace fs = std::filesystem;

namespace {

const char* const kUsage =
    "contactbench run SUITE.json [--out DIR] [--shard i/N] [--force] [--fresh] [--jobs N [--jobs-timed]]";

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
    const nlohmann::json no_accuracy = {{"stationarity", nullptr},    {"primal", nullptr}, {"dual", nullptr},
                                        {"complementarity", nullptr}, {"gap", nullptr},    {"max", nullptr}};
    return {{"solver", sv.solver},
            {"label", sv.label},
            {"settings", settings},
            {"snapshot", snapshot},
            {"decouple", {{"applied", false}}},
            {"status", status},
            {"criterion", ""},
            {"message", message},
            {"iterations", 0},
            {"objective", nullptr},
            {"accuracy", no_accuracy},
            {"violation", nullptr},
            {"native_residual", nullptr},
            {"lambda_fitted", false},
            {"nonfinite", false},
            {"monotone", true},
            {"status_confirmed", true},
            {"tol", tol},
            {"counters", Counters{}.to_json()},
            {"time", {{"setup_s", 0.0}, {"solve_s", 0.0}, {"total_s", 0.0}, {"repeat", 0}}},
            {"info", nlohmann::json::object()},
            {"provenance", provenance()}};
}

/// Holds an exclusive flock on DIR/.lock for the life of the process (released by the kernel
/// when the process ends, however it ends).
void lock_out_dir(const std::string& out)
{
    const std::string path = (fs::path(out) / ".lock").string();
    // O_NOFOLLOW: a symlink planted as .lock would make the ftruncate below empty its target.
    const int fd = ::open(path.c_str(), O_RDWR | O_CREAT | O_NOFOLLOW | O_NONBLOCK | O_CLOEXEC, 0644);
    if (fd < 0) throw_input_error(path, "", std::string("cannot create the lock file: ") + std::strerror(errno));
    struct stat st {};
    if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
        ::close(fd);
        throw_input_error(path, "", "not a regular file: not used as the lock");
    }
    if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
        char holder[32] = {0};
        const ssize_t got = ::pread(fd, holder, sizeof holder - 1, 0);
        std::string pid = got > 0 ? std::string(holder, size_t(got)) : std::string("?");
        while (!pid.empty() && (pid.back() == '\n' || pid.back() == ' ')) pid.pop_back();
        ::close(fd);
        throw_input_error(out, "",
                          "another `contactbench run` (pid " + pid +
                              ") is writing to this folder; wait for it to finish or use another --out");
    }
    const std::string me = std::to_string(::getpid()) + "\n";
    if (::ftruncate(fd, 0) == 0 && ::pwrite(fd, me.data(), me.size(), 0) < 0) {
        // the pid is only for the message of a second run
    }
    // fd stays open (and locked) until exit
}

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

/// --fresh: removes what `run` writes in DIR (and nothing else).
void clear_out_dir(const std::string& out)
{
    std::error_code ec;
    const fs::path runs = fs::path(out) / "runs";
    if (fs::is_directory(runs))
        for (const auto& entry : fs::directory_iterator(runs))
            if (entry.path().extension() == ".json") fs::remove(entry.path(), ec);
    for (const char* name : {"summary.csv", "suite.json", "suite.pending.json", "provenance.json", "jobs.json"})
        fs::remove(fs::path(out) / name, ec);
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

}  // namespace

int cmd_run(const Args& args)
{
    const CommandLine cl("run", args, {"--out", "--shard", "--jobs"}, {"--force", "--fresh", "--jobs-timed"});
    if (cl.help()) {
        std::cout << "usage: " << kUsage
                  << "\n\nRuns every (snapshot, solver label) of a suite; writes DIR/runs/<id>__<label>.json,\n"
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
        return 0;
    }
    cl.expect_positional(1, 1, kUsage);
    Suite suite = load_suite(cl.positional()[0]);
    for (const std::string& notice : drop_unbuilt_optional_solvers(suite, builtin_registry().names()))
        std::cerr << "run: " << notice << "\n";
    std::string out = cl.path("--out", "results/" + suite.name);
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
    {
        std::error_code ec;
        fs::create_directories(fs::path(out) / "runs", ec);
        if (ec) throw_input_error(out, "--out", "cannot create the results folder: " + ec.message());
    }
    lock_out_dir(out);
    if (cl.has("--fresh")) clear_out_dir(out);

    const size_t labels = suite.solvers.size();
    auto in_shard = [&](size_t s, size_t v) {
        const size_t key = suite.chain ? v : s * labels + v;
        return static_cast<long>(key % static_cast<size_t>(shard.count)) == shard.index - 1 &&
               solver_applies(suite.solvers[v], snapshots[s].id);  // a job that does not apply is none
    };
    auto run_path = [&](size_t s, size_t v) {
        return (fs::path(out) / "runs" / run_file_name(snapshots[s].id, suite.solvers[v].label)).string();
    };
    const std::string how_to_force = "use another --out, or --fresh to discard the results in " + out;
    // One DIR holds one suite: another suite's results are never mixed into this summary.
    const nlohmann::json held = suite_in(out);
    if (held.is_object() && held.value("name", std::string()) != suite.name)
        throw_input_error(out, "suite.json",
                          "holds results of suite '" + held.value("name", std::string("?")) + "', not '" + suite.name +
                              "'; " + how_to_force);
    std::set<std::string> job_files;
    for (size_t s = 0; s < snapshots.size(); ++s)
        for (size_t v = 0; v < labels; ++v)
            if (in_shard(s, v)) job_files.insert(run_file_name(snapshots[s].id, suite.solvers[v].label));
    std::vector<std::string> foreign;
    for (const auto& entry : fs::directory_iterator(fs::path(out) / "runs"))
        if (entry.path().extension() == ".json" && !job_files.count(entry.path().filename().string()))
            foreign.push_back(entry.path().string());
    std::sort(foreign.begin(), foreign.end());
    if (!foreign.empty())
        throw_input_error(foreign.front(), "",
                          "not a job of suite '" + suite.name + "'" +
                              (shard.count > 1 ? " shard " + cl.value("--shard") : "") + " (" +
                              std::to_string(foreign.size()) + " such run files: an earlier suite or shard?); " +
                              how_to_force);

    // Identities: what each job's result depends on (the snapshot by content).
    std::vector<nlohmann::json> hashes(snapshots.size());
    for (size_t s = 0; s < snapshots.size(); ++s) {
        bool needed = false;
        for (size_t v = 0; v < labels; ++v) needed = needed || in_shard(s, v);
        if (!needed) continue;
        try {
            hashes[s] = qpsnap_content_hash(snapshots[s].path);
        } catch (const InputError&) {
            hashes[s] = nullptr;  // the run fails on loading and is retried next time
        }
    }
    const nlohmann::json options_entry = {{"tol", suite.tol},
                                          {"time_limit_s", suite.time_limit_s},
                                          {"repeat", suite.repeat},
                                          {"history_max", suite.history_max},
                                          {"reference", suite.reference},
                                          {"decouple", suite.decouple},
                                          {"decouple_seed", suite.decouple_seed},
                                          {"chain", suite.chain}};
    auto settings_of = [&](size_t v) {
        nlohmann::json settings = suite.solvers[v].settings;
        // Suite-wide tol and time limit are defaults: a solver's own setting wins.
        if (!settings.contains("tol")) settings["tol"] = suite.tol;
        if (!settings.contains("time_limit_s")) settings["time_limit_s"] = suite.time_limit_s;
        return settings;
    };
    auto identity_of = [&](size_t s, size_t v) {
        const nlohmann::json entry = {{"snapshot", snapshots[s].id},
                                      {"path", snapshots[s].path},
                                      {"generated", snapshots[s].generated},
                                      {"label", suite.solvers[v].label},
                                      {"options", options_entry}};
        return run_identity(hashes[s], suite.solvers[v].solver, settings_of(v), entry);
    };
    // Why each stored run cannot be reused ("" = reusable; "missing" = not run yet).
    std::vector<std::vector<std::string>> stale(snapshots.size(), std::vector<std::string>(labels));
    for (size_t s = 0; s < snapshots.size(); ++s)
        for (size_t v = 0; v < labels; ++v) {
            if (!in_shard(s, v)) continue;
            const std::string path = run_path(s, v);
            if (!fs::exists(fs::symlink_status(path))) {
                stale[s][v] = "missing";
                continue;
            }
            try {
                stale[s][v] = stale_reason(read_json_file(path), identity_of(s, v));
            } catch (const InputError&) {
                stale[s][v] = "the run file is damaged";
            }
        }
    // Which jobs run: chains whole per label, others one by one.
    std::vector<std::vector<bool>> todo(snapshots.size(), std::vector<bool>(labels, false));
    size_t total = 0;
    for (size_t v = 0; v < labels; ++v) {
        bool chain_complete = true;
        for (size_t s = 0; s < snapshots.size(); ++s)
            if (in_shard(s, v) && !stale[s][v].empty()) chain_complete = false;
        for (size_t s = 0; s < snapshots.size(); ++s) {
            if (!in_shard(s, v)) continue;
            ++total;
            todo[s][v] = force || (suite.chain ? !chain_complete : !stale[s][v].empty());
        }
    }
    // suite.json describes what DIR holds: while jobs of this suite run, it is suite.pending.json.
    bool any_todo = false;
    for (const auto& row : todo)
        for (bool t : row) any_todo = any_todo || t;
    if (any_todo) {
        write_json_atomic((fs::path(out) / "suite.pending.json").string(), suite.raw);
        std::error_code ec;
        fs::remove(fs::path(out) / "suite.json", ec);
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
    std::map<std::string, WarmState> warm;             // by label
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
                info = {{"id", snap.id},
                        {"path", snap.path},
                        {"hash", hashes[s].is_string() ? hashes[s] : nlohmann::json(qpsnap_content_hash(snap.path))},
                        {"n", qp->n()},
                        {"m", qp->m()},
                        {"meta", qp->meta},
                        {"generated", snap.generated}};
            } catch (const InputError& e) {
                load_error = e.what();
                info = {{"id", snap.id}, {"path", snap.path}, {"generated", snap.generated}};
            }
        }
        for (size_t v = 0; v < labels; ++v) {
            if (!in_shard(s, v)) continue;
            ++done;
            const SuiteSolver& sv = suite.solvers[v];
            const std::string prefix =
                "[" + std::to_string(done) + "/" + std::to_string(total) + "] " + snap.id + " x " + sv.label + ": ";
            if (!todo[s][v]) {
                std::cerr << prefix << "done before, skipped\n";
                continue;
            }
            if (!stale[s][v].empty() && stale[s][v] != "missing")
                std::cerr << prefix << "stored run not reused: " << stale[s][v] << "\n";
            if (pool.delegate()) {  // --jobs: a child process does this job
                ++ran;
                continue;
            }
            const nlohmann::json settings = settings_of(v);
            nlohmann::json record;
            if (!load_error.empty()) {
                record = failed_record(sv, settings, info, "invalid_input", load_error, suite.tol);
                record["final"] = false;  // the snapshot could not be read: retried on resume
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
                    if (suite.reference) {
                        // F* of the QP in the file (docs/accuracy.md), whatever rows the solver kept.
                        const std::string key = info["hash"].get<std::string>();
                        if (!references.count(key)) references[key] = reference_solution(*qp, key);
                        attach_reference(record, references[key]);
                    }
                } catch (const InputError& e) {
                    record = failed_record(sv, settings, info, "invalid_input", e.what(), suite.tol);
                } catch (const std::exception& e) {
                    record = failed_record(sv, settings, info, "internal_error", e.what(), suite.tol);
                    record["final"] = false;  // a harness failure (out of memory, ...): retried on resume
                }
            }
            record["label"] = sv.label;
            record["suite"] = suite.name;
            record["mode"] = suite.chain ? "chain" : "cold";
            if (pool.parallel()) record["concurrent_jobs"] = jobs;  // its time shared the machine
            // Final: the solver's outcome, or a refusal that the identity fully determines (an
            // unregistered solver, bad settings: a rebuild or an edit changes the identity).
            if (!record.contains("final")) record["final"] = true;
            record["identity"] = identity_of(s, v);
            write_json_atomic(run_path(s, v), record);
            ++ran;
            std::string line = prefix + record["status"].get<std::string>();
            if (record["accuracy"]["max"].is_number()) {
                line += " in " + record["iterations"].dump() + " it, accuracy " +
                        sci(record["accuracy"]["max"].get<double>()) + ", " +
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
        throw std::runtime_error(std::to_string(failed) +
                                 " parallel job(s) failed; rerun to redo them (finished runs are kept)");
    const size_t runs = write_summary(out, suite.name);
    // Which jobs this folder holds, for `merge` to check that the shards are complete and of one suite.
    size_t all_jobs = 0, done_jobs = 0, final_jobs = 0;
    for (size_t s = 0; s < snapshots.size(); ++s)
        for (size_t v = 0; v < labels; ++v) all_jobs += solver_applies(suite.solvers[v], snapshots[s].id) ? 1 : 0;
    nlohmann::json shard_jobs = nlohmann::json::array();
    for (size_t s = 0; s < snapshots.size(); ++s)
        for (size_t v = 0; v < labels; ++v)
            if (in_shard(s, v)) {
                shard_jobs.push_back(run_file_name(snapshots[s].id, suite.solvers[v].label));
                if (fs::exists(run_path(s, v))) ++done_jobs;
                try {
                    if (read_json_file(run_path(s, v)).value("final", true)) ++final_jobs;
                } catch (const InputError&) {
                }
            }
    write_json_atomic((fs::path(out) / "jobs.json").string(),
                      {{"suite", suite.name},
                       {"suite_hash", fnv1a_hex(suite.raw.dump())},
                       {"shard", {{"index", shard.index}, {"count", shard.count}}},
                       {"all_jobs", all_jobs},
                       {"jobs", shard_jobs},
                       {"complete", done_jobs == shard_jobs.size()},
                       {"retry", shard_jobs.size() - final_jobs}});
    write_json_atomic((fs::path(out) / "provenance.json").string(), provenance());
    write_json_atomic((fs::path(out) / "suite.json").string(), suite.raw);
    std::error_code ec;
    fs::remove(fs::path(out) / "suite.pending.json", ec);
    std::cerr << "ran " << ran << " of " << total << " jobs; " << runs << " runs in " << out << "/summary.csv\n";
    return 0;
}

}  // namespace cb
