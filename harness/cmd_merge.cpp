// `contactbench merge OUT DIR1 DIR2 ...`: joins the shard folders of one suite run.
#include "harness/cli.hpp"
#include "harness/commands.hpp"
#include "harness/provenance.hpp"
#include "harness/results.hpp"
#include "harness/timing_hygiene.hpp"

#include <filesystem>
#include <fstream>
#include <iostream>
#include <set>
#include <sstream>

namespace cb {

namespace fs = std::filesystem;

namespace {

const char* const kUsage = "contactbench merge OUT DIR1 DIR2 ...";

std::string slurp(const fs::path& p)
{
    std::ifstream in(p, std::ios::binary);  // a run file checked by read_json_file first
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
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
        std::cout << "usage: " << kUsage
                  << "\n\nChecks that DIR1 DIR2 ... are the complete shards i/N (every i once) of one suite,\n"
                     "each finished (DIRk/jobs.json lists every job, each has its run file), then copies\n"
                     "DIRk/runs/*.json into OUT/runs and rewrites OUT/summary.csv.\n";
        return 0;
    }
    cl.expect_positional(2, 100000, kUsage);
    const std::string out = cl.positional()[0];
    // Check every shard before anything is written.
    nlohmann::json suite, first_jobs;
    std::string first_dir;
    std::set<long> indices;
    std::set<std::string> all_files;
    for (size_t k = 1; k < cl.positional().size(); ++k) {
        const fs::path dir = cl.positional()[k];
        if (!fs::is_directory(dir / "runs"))
            throw_input_error(dir.string(), "runs/", "missing: not a results folder of `contactbench run`");
        const fs::path jobs_path = dir / "jobs.json";
        if (!fs::exists(jobs_path))
            throw_input_error(jobs_path.string(), "",
                              "missing: the shard's `contactbench run` did not finish (run it again)");
        const nlohmann::json jobs = read_json_file(jobs_path.string());
        if (!jobs.is_object() || !jobs.contains("suite_hash") || !jobs.contains("shard") ||
            !jobs["shard"].is_object() || !jobs["shard"].value("index", nlohmann::json()).is_number_integer() ||
            !jobs["shard"].value("count", nlohmann::json()).is_number_integer() || !jobs.contains("jobs") ||
            !jobs["jobs"].is_array() || !jobs.value("all_jobs", nlohmann::json()).is_number_integer())
            throw_input_error(jobs_path.string(), "", "not a jobs file of `contactbench run`");
        if (!fs::exists(dir / "suite.json"))
            throw_input_error((dir / "suite.json").string(), "",
                              "missing: the shard's `contactbench run` did not finish");
        if (first_jobs.is_null()) {
            first_jobs = jobs;
            first_dir = dir.string();
            suite = read_json_file((dir / "suite.json").string());
        } else if (jobs["suite_hash"] != first_jobs["suite_hash"] || jobs["suite"] != first_jobs["suite"]) {
            throw_input_error(jobs_path.string(), "suite",
                              "shard of suite " + jobs["suite"].dump() + " (hash " + jobs["suite_hash"].dump() +
                                  "), but " + first_dir + " is of suite " + first_jobs["suite"].dump() + " (hash " +
                                  first_jobs["suite_hash"].dump() + "): not one suite");
        } else if (jobs["shard"]["count"] != first_jobs["shard"]["count"]) {
            throw_input_error(jobs_path.string(), "shard",
                              "of " + jobs["shard"]["count"].dump() + " shards, but " + first_dir + " is of " +
                                  first_jobs["shard"]["count"].dump());
        }
        const long index = jobs["shard"].value("index", 0L);
        if (!indices.insert(index).second)
            throw_input_error(jobs_path.string(), "shard", "shard " + std::to_string(index) + " given twice");
        for (const auto& f : jobs["jobs"]) {
            if (!f.is_string() || fs::path(f.get<std::string>()).filename() != f.get<std::string>())
                throw_input_error(jobs_path.string(), "jobs", "expected run file names, got " + f.dump());
            const std::string name = f.get<std::string>();
            if (!fs::is_regular_file(dir / "runs" / name))
                throw_input_error((dir / "runs" / name).string(), "",
                                  "missing: shard " + std::to_string(index) + " is incomplete (run it again)");
            all_files.insert(name);
        }
    }
    const long count = first_jobs["shard"].value("count", 1L);
    std::string missing;
    for (long i = 1; i <= count; ++i)
        if (!indices.count(i))
            missing += (missing.empty() ? "" : ", ") + std::to_string(i) + "/" + std::to_string(count);
    if (!missing.empty())
        throw_input_error("merge", "shards", "missing shard(s) " + missing + " of suite " + first_jobs["suite"].dump());
    if (all_files.size() != first_jobs.value("all_jobs", size_t(0)))
        throw_input_error("merge", "shards",
                          "the shards hold " + std::to_string(all_files.size()) + " jobs, the suite has " +
                              first_jobs["all_jobs"].dump());

    std::error_code ec;
    fs::create_directories(fs::path(out) / "runs", ec);
    if (ec) throw_input_error(out, "", "cannot create the folder: " + ec.message());
    nlohmann::json shards = nlohmann::json::array();
    size_t copied = 0, duplicates = 0;
    for (size_t k = 1; k < cl.positional().size(); ++k) {
        const fs::path dir = cl.positional()[k];
        if (fs::is_regular_file(dir / "provenance.json"))
            shards.push_back(
                {{"dir", dir.string()}, {"provenance", read_json_file((dir / "provenance.json").string())}});
        const nlohmann::json jobs = read_json_file((dir / "jobs.json").string());
        for (const auto& f : jobs["jobs"]) {
            const fs::path source = dir / "runs" / f.get<std::string>();
            const fs::path target = fs::path(out) / "runs" / source.filename();
            if (fs::equivalent(source.parent_path(), target.parent_path())) continue;  // OUT is one of the shards
            if (fs::exists(target) && slurp(target) == slurp(source)) {
                ++duplicates;
                continue;
            }
            read_json_file(source.string());  // refuse to merge a damaged run file
            write_file_atomic(target.string(), slurp(source));
            ++copied;
        }
    }
    const std::string name = suite.is_object() ? suite.value("name", std::string("merged")) : std::string("merged");
    nlohmann::json merged_jobs = first_jobs;
    merged_jobs["shard"] = {{"index", 1}, {"count", 1}};
    merged_jobs["jobs"] = all_files;
    merged_jobs["complete"] = true;
    write_json_atomic((fs::path(out) / "jobs.json").string(), merged_jobs);
    if (suite.is_object()) write_json_atomic((fs::path(out) / "suite.json").string(), suite);
    nlohmann::json prov = provenance();
    prov["merged_from"] = shards;
    write_json_atomic((fs::path(out) / "provenance.json").string(), prov);
    const size_t runs = write_summary(out, name);
    warn_mixed_cpu_models(out, suite);
    std::cerr << "merged " << copied << " run files (" << duplicates << " already there) from " << indices.size()
              << " complete shards; " << runs << " runs in " << out << "/summary.csv\n";
    return 0;
}

}  // namespace cb
