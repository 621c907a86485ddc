// `contactbench merge OUT DIR1 DIR2 ...`: joins the shard folders of one suite run.
#include "harness/cli.hpp"
#include "harness/commands.hpp"
#include "harness/provenance.hpp"
#include "harness/results.hpp"
#include "harness/results_folder.hpp"
#include "harness/run_lock.hpp"
#include "harness/runner.hpp"  // the harness's own statuses
#include "harness/suite.hpp"   // fnv1a_hex
#include "harness/timing_hygiene.hpp"
#include "problems/io_util.hpp"
#include "problems/output_folder.hpp"
#include "solvers/core/solver.hpp"  // solve_status_from_string

#include <filesystem>
#include <iostream>
#include <map>
#include <set>
#include <vector>

namespace cb {

namespace fs = std::filesystem;

namespace {

const char* const MERGE_USAGE = "contactbench merge OUT DIR1 DIR2 ...";

std::string slurp(const fs::path& p) { return read_regular_file(p.string()); }

/// One run file of a shard: its name and its bytes (checked, copied as read).
struct RunFile {
    std::string name, bytes;
};

/// A shard folder of `contactbench run --shard i/N`, read and checked whole.
struct ShardFolder {
    fs::path dir;
    nlohmann::json jobs, suite_json, provenance;
    std::string suite, suite_hash;
    long index = 0, count = 0;
    size_t all_jobs = 0;
    std::vector<RunFile> runs;
    std::string jobs_path() const { return (dir / "jobs.json").string(); }
};

/// Statuses a run file may hold: the solvers' (solvers/core/solver.hpp) and the harness's own.
bool known_status(const std::string& status)
{
    if (status == "internal_error" || status == STATUS_SOLVED_RELAXATION || status == STATUS_UNCONFIRMED) return true;
    try {
        solve_status_from_string(status);
        return true;
    } catch (const InputError&) {
        return false;
    }
}

/// The jobs file, suite file and every run file of the shard at `folder`, each checked: the jobs
/// file's fields and types, i of N with 1 <= i <= N, the suite file matching the jobs file's
/// suite hash, every listed run file present, a JSON object of this suite with a known status.
ShardFolder read_shard(const std::string& folder)
{
    ShardFolder shard;
    shard.dir = folder;
    if (!fs::is_directory(shard.dir / "runs"))
        throw_input_error(folder, "runs/", "missing: not a results folder of `contactbench run`");
    require_unlocked(folder);  // a run still writing the shard: not finished
    if (fs::exists(fs::symlink_status(shard.dir / "suite.pending.json")))
        throw_input_error((shard.dir / "suite.pending.json").string(), "",
                          "present: the shard's `contactbench run` was interrupted or is still running (run it again)");
    const std::string jobs_path = shard.jobs_path();
    if (!fs::exists(jobs_path))
        throw_input_error(jobs_path, "", "missing: the shard's `contactbench run` did not finish (run it again)");
    shard.jobs = read_json_file(jobs_path);
    const nlohmann::json& jobs = shard.jobs;
    auto field = [&](const char* name, bool ok, const std::string& expected) {
        if (!jobs.is_object()) throw_input_error(jobs_path, "", "not a jobs file of `contactbench run`");
        if (!jobs.contains(name) || !ok)
            throw_input_error(jobs_path, name,
                              "expected " + expected + ", got " +
                                  (jobs.contains(name) ? jobs[name].dump() : "nothing"));
    };
    field("suite", jobs.is_object() && jobs.value("suite", nlohmann::json()).is_string(), "the suite's name");
    field("suite_hash", jobs.value("suite_hash", nlohmann::json()).is_string(), "the suite's hash");
    field("all_jobs", jobs.value("all_jobs", nlohmann::json()).is_number_unsigned(), "a count of jobs");
    field("jobs", jobs.value("jobs", nlohmann::json()).is_array(), "the list of run files");
    const nlohmann::json shard_field = jobs.value("shard", nlohmann::json());
    field("shard",
          shard_field.is_object() && shard_field.value("index", nlohmann::json()).is_number_integer() &&
              shard_field.value("count", nlohmann::json()).is_number_integer(),
          "{\"index\": i, \"count\": N}");
    shard.suite = jobs["suite"].get<std::string>();
    shard.suite_hash = jobs["suite_hash"].get<std::string>();
    shard.all_jobs = jobs["all_jobs"].get<size_t>();
    shard.index = shard_field["index"].get<long>();
    shard.count = shard_field["count"].get<long>();
    if (shard.count < 1 || shard.count > 100000 || shard.index < 1 || shard.index > shard.count)
        throw_input_error(jobs_path, "shard",
                          "shard " + std::to_string(shard.index) + " of " + std::to_string(shard.count) +
                              ": expected 1 <= i <= N <= 100000");
    const fs::path suite_path = shard.dir / "suite.json";
    if (!fs::exists(suite_path))
        throw_input_error(suite_path.string(), "", "missing: the shard's `contactbench run` did not finish");
    shard.suite_json = read_json_file(suite_path.string());
    if (!shard.suite_json.is_object() || fnv1a_hex(shard.suite_json.dump()) != shard.suite_hash)
        throw_input_error(suite_path.string(), "",
                          "does not match the suite hash " + shard.suite_hash + " of " + jobs_path + " (edited?)");
    if (fs::is_regular_file(shard.dir / "provenance.json"))
        shard.provenance = read_json_file((shard.dir / "provenance.json").string());
    std::set<std::string> seen;
    for (const auto& f : jobs["jobs"]) {
        if (!f.is_string() || f.get<std::string>().empty() ||
            fs::path(f.get<std::string>()).filename() != f.get<std::string>() || f.get<std::string>() == "." ||
            f.get<std::string>() == "..")
            throw_input_error(jobs_path, "jobs", "expected run file names, got " + f.dump());
        const std::string name = f.get<std::string>();
        if (!seen.insert(name).second) throw_input_error(jobs_path, "jobs", name + " listed twice");
        const fs::path path = shard.dir / "runs" / name;
        std::error_code ec;  // present but a FIFO or link loop: read_regular_file names it below
        if (!fs::exists(fs::symlink_status(path, ec)))
            throw_input_error(path.string(), "",
                              "missing: shard " + std::to_string(shard.index) + " is incomplete (run it again)");
        RunFile run{name, read_regular_file(path.string(), std::uint64_t(256) << 20)};
        const nlohmann::json record = parse_json_text(run.bytes, path.string());
        check_run_record(record, path.string(), name);  // its own job's, and final
        if (record.value("suite", nlohmann::json()) != jobs["suite"])
            throw_input_error(path.string(), "suite",
                              "expected \"" + shard.suite + "\" (the shard's suite), got " +
                                  record.value("suite", nlohmann::json()).dump());
        const nlohmann::json status = record.value("status", nlohmann::json());
        if (!status.is_string() || !known_status(status.get<std::string>()))
            throw_input_error(path.string(), "status", "not a known run status: " + status.dump());
        shard.runs.push_back(std::move(run));
    }
    return shard;
}

/// Throws unless `shard` is of the same suite and shard count as `first`.
void same_suite(const ShardFolder& shard, const ShardFolder& first)
{
    if (shard.suite_hash != first.suite_hash || shard.suite != first.suite)
        throw_input_error(shard.jobs_path(), "suite",
                          "shard of suite \"" + shard.suite + "\" (hash \"" + shard.suite_hash + "\"), but " +
                              first.dir.string() + " is of suite \"" + first.suite + "\" (hash \"" + first.suite_hash +
                              "\"): not one suite");
    if (shard.count != first.count || shard.all_jobs != first.all_jobs)
        throw_input_error(shard.jobs_path(), "shard",
                          "of " + std::to_string(shard.count) + " shards, but " + first.dir.string() + " is of " +
                              std::to_string(first.count));
}

/// An OUT that already holds results of another suite is not mixed with these.
void refuse_foreign_out(const std::string& out, const ShardFolder& first)
{
    const fs::path jobs = fs::path(out) / "jobs.json";
    if (!fs::exists(fs::symlink_status(jobs))) return;
    const nlohmann::json existing = read_json_file(jobs.string());
    if (!existing.is_object() || existing.value("suite_hash", nlohmann::json()) != first.suite_hash)
        throw_input_error(jobs.string(), "suite_hash",
                          "OUT holds results of another suite (" + existing.value("suite", nlohmann::json()).dump() +
                              "); merge into a new folder");
}

/// Shards run on a cluster may land on different CPU models: say so when the suite is timed.
void warn_mixed_cpu_models(const std::string& out, const nlohmann::json& suite)
{
    if (suite.is_object() && !suite.value("timed", true)) return;  // "timed": false: times are not judged
    const std::string warning = mixed_cpu_warning(cpu_models_of_timed_runs(read_runs(out)));
    if (!warning.empty()) std::cerr << "merge: warning: " << warning << "\n";
}

}  // namespace

int cmd_merge(const Args& args)
{
    const CommandLine cl("merge", args, {}, {});
    if (cl.help()) {
        std::cout << "usage: " << MERGE_USAGE
                  << "\n\nChecks that DIR1 DIR2 ... are the complete shards i/N (every i once) of one suite,\n"
                     "each finished (DIRk/jobs.json lists every job, each has its run file, of that suite\n"
                     "and with a known status), then copies DIRk/runs/*.json into OUT/runs and rewrites\n"
                     "OUT/summary.csv. Nothing is written unless every shard passes.\n";
        return 0;
    }
    cl.expect_positional(2, 100000, MERGE_USAGE);
    const std::string out = cl.positional()[0];
    if (out.empty()) throw_input_error("merge", "OUT", "expects a folder name, got \"\"");
    // Every shard is checked, and every run file read and checked, before anything is written.
    std::vector<ShardFolder> shards;
    std::map<std::string, std::string> shard_of_file;  // run file name -> the shard folder holding it
    std::map<long, std::string> folder_of_index;
    for (size_t k = 1; k < cl.positional().size(); ++k) {
        ShardFolder shard = read_shard(cl.positional()[k]);
        if (!shards.empty()) same_suite(shard, shards.front());
        const auto [previous, fresh] = folder_of_index.emplace(shard.index, shard.dir.string());
        if (!fresh)
            throw_input_error(shard.jobs_path(), "shard",
                              "shard " + std::to_string(shard.index) + " of " + std::to_string(shard.count) +
                                  " given twice (also " + previous->second + ")");
        for (const auto& run : shard.runs) {
            const auto [other, unique] = shard_of_file.emplace(run.name, shard.dir.string());
            if (!unique)
                throw_input_error(shard.jobs_path(), "jobs",
                                  run.name + " is also a job of " + other->second + ": the shards overlap");
        }
        shards.push_back(std::move(shard));
    }
    const ShardFolder& first = shards.front();
    std::string missing;
    for (long i = 1; i <= first.count; ++i)
        if (!folder_of_index.count(i))
            missing += (missing.empty() ? "" : ", ") + std::to_string(i) + "/" + std::to_string(first.count);
    if (!missing.empty())
        throw_input_error("merge", "shards", "missing shard(s) " + missing + " of suite \"" + first.suite + "\"");
    if (shard_of_file.size() != first.all_jobs)
        throw_input_error("merge", "shards",
                          "the shards hold " + std::to_string(shard_of_file.size()) + " jobs, the suite has " +
                              std::to_string(first.all_jobs));
    // OUT under DIR/.lock, as `run` holds it: a run writing OUT and this merge never mix.
    std::error_code ec;
    const bool existed = fs::exists(fs::symlink_status(out, ec));
    if (existed) lock_output_folder(out, "merge");
    refuse_foreign_out(out, first);
    make_output_subfolder(out, "runs");  // issue 40: never through a planted OUT/runs link
    if (!existed) lock_output_folder(out, "merge");
    nlohmann::json merged_from = nlohmann::json::array();
    size_t copied = 0, duplicates = 0;
    for (const ShardFolder& shard : shards) {
        if (!shard.provenance.is_null())
            merged_from.push_back({{"dir", shard.dir.string()}, {"provenance", shard.provenance}});
        for (const auto& run : shard.runs) {
            const fs::path target = fs::path(out) / "runs" / run.name;
            if (fs::equivalent(shard.dir / "runs", target.parent_path(), ec)) continue;  // OUT is one of the shards
            if (fs::is_regular_file(target) && slurp(target) == run.bytes) {
                ++duplicates;
                continue;
            }
            write_file_atomic(target.string(), run.bytes);
            ++copied;
        }
    }
    nlohmann::json merged_jobs = first.jobs;
    merged_jobs["shard"] = {{"index", 1}, {"count", 1}};
    nlohmann::json names = nlohmann::json::array();
    for (const auto& item : shard_of_file) names.push_back(item.first);
    merged_jobs["jobs"] = names;
    merged_jobs["complete"] = true;
    write_json_atomic((fs::path(out) / "jobs.json").string(), merged_jobs);
    write_json_atomic((fs::path(out) / "suite.json").string(), first.suite_json);
    nlohmann::json prov = provenance();
    prov["merged_from"] = merged_from;
    write_json_atomic((fs::path(out) / "provenance.json").string(), prov);
    const std::string name = first.suite_json.value("name", std::string("merged"));
    const size_t runs = write_summary(out, name);
    warn_mixed_cpu_models(out, first.suite_json);
    std::cerr << "merged " << copied << " run files (" << duplicates << " already there) from " << shards.size()
              << " complete shards; " << runs << " runs in " << out << "/summary.csv\n";
    return 0;
}

}  // namespace cb
