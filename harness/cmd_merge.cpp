// `contactbench merge OUT DIR1 DIR2 ...`: joins the shard folders of one suite run.
#include "harness/cli.hpp"
#include "harness/commands.hpp"
#include "harness/provenance.hpp"
#include "harness/results.hpp"
#include "harness/timing_hygiene.hpp"

#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>

namespace cb {

namespace fs = std::filesystem;

namespace {

const char* const kUsage = "contactbench merge OUT DIR1 DIR2 ...";

std::string slurp(const fs::path& p)
{
    std::ifstream in(p, std::ios::binary);
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

} // namespace

int cmd_merge(const Args& args)
{
    const CommandLine cl("merge", args, {}, {});
    if (cl.help()) {
        std::cout << "usage: " << kUsage
                  << "\n\nCopies DIRk/runs/*.json into OUT/runs (the same run in two shards must be\n"
                     "identical apart from timing; the first one is kept), then rewrites OUT/summary.csv.\n";
        return 0;
    }
    cl.expect_positional(2, 100000, kUsage);
    const std::string out = cl.positional()[0];
    fs::create_directories(fs::path(out) / "runs");
    nlohmann::json suite;
    nlohmann::json shards = nlohmann::json::array();
    size_t copied = 0, duplicates = 0;
    for (size_t k = 1; k < cl.positional().size(); ++k) {
        const fs::path dir = cl.positional()[k];
        if (!fs::is_directory(dir / "runs"))
            throw_input_error(dir.string(), "runs/", "missing: not a results folder of `contactbench run`");
        if (suite.is_null() && fs::is_regular_file(dir / "suite.json")) suite = read_json_file((dir / "suite.json").string());
        if (fs::is_regular_file(dir / "provenance.json"))
            shards.push_back({{"dir", dir.string()}, {"provenance", read_json_file((dir / "provenance.json").string())}});
        std::vector<fs::path> files;
        for (const auto& entry : fs::directory_iterator(dir / "runs"))
            if (entry.is_regular_file() && entry.path().extension() == ".json") files.push_back(entry.path());
        std::sort(files.begin(), files.end());
        for (const auto& f : files) {
            const fs::path target = fs::path(out) / "runs" / f.filename();
            if (fs::equivalent(f.parent_path(), target.parent_path())) continue;  // OUT is one of the shards
            if (fs::exists(target)) {
                ++duplicates;
                std::cerr << "merge: " << f.filename().string() << " already in " << out << ", kept the first\n";
                continue;
            }
            read_json_file(f.string());  // refuse to merge a damaged run file
            write_file_atomic(target.string(), slurp(f));
            ++copied;
        }
    }
    const std::string name = suite.is_object() ? suite.value("name", std::string("merged")) : std::string("merged");
    if (suite.is_object()) write_json_atomic((fs::path(out) / "suite.json").string(), suite);
    nlohmann::json prov = provenance();
    prov["merged_from"] = shards;
    write_json_atomic((fs::path(out) / "provenance.json").string(), prov);
    const size_t runs = write_summary(out, name);
    warn_mixed_cpu_models(out, suite);
    std::cerr << "merged " << copied << " run files (" << duplicates << " duplicates skipped); " << runs << " runs in "
              << out << "/summary.csv\n";
    return 0;
}

} // namespace cb
