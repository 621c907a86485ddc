// `contactbench cluster slurm SUITE --out DIR --shards N [...]`: writes the sbatch files of a
// job array (one shard per task) and of a merge job that depends on it, and prints the two
// `sbatch` commands that submit them. Nothing is submitted here.
#include "harness/cli.hpp"
#include "harness/commands.hpp"
#include "harness/results.hpp"
#include "harness/slurm.hpp"
#include "harness/suite.hpp"

#include <filesystem>
#include <iostream>
#include <unistd.h>

namespace cb {

namespace fs = std::filesystem;

namespace {

const char* const CLUSTER_USAGE =
    "contactbench cluster slurm SUITE.json --out DIR --shards N [--partition P] [--time T] [--mem M]\n"
    "       [--cpus-per-task C] [--exclusive] [--first-index K] [--max-parallel K] [--sbatch-option OPT ...]";

/// The binary that runs this command, so that the jobs run the same build.
std::string this_binary()
{
    std::error_code ec;
    const fs::path self = fs::read_symlink("/proc/self/exe", ec);
    if (ec) throw std::runtime_error("cannot resolve /proc/self/exe: " + ec.message());
    return self.string();
}

}  // namespace

int cmd_cluster(const Args& args)
{
    const CommandLine cl("cluster", args,
                         {"--out", "--shards", "--partition", "--time", "--mem", "--cpus-per-task", "--first-index",
                          "--max-parallel", "--sbatch-option"},
                         {"--exclusive"});
    if (cl.help()) {
        std::cout
            << "usage: " << CLUSTER_USAGE
            << "\n\nWrites DIR/slurm/array.sbatch (a job array: task i runs shard i of N of the suite,\n"
               "pinned to whole cores, and writes DIR/shard-<i>-of-<N>) and DIR/slurm/merge.sbatch (joins\n"
               "the shards into DIR/summary.csv), then prints the sbatch commands that submit them, the\n"
               "merge after the array has succeeded. DIR must be on a file system every node sees.\n"
               "  --partition P, --time T, --mem M   passed to #SBATCH (per array task)\n"
               "  --cpus-per-task C                  cores per task (default: the most `threads` a label asks for, 1)\n"
               "  --exclusive                        whole nodes per task (quietest clock, costs nodes)\n"
               "  --first-index K                    the array runs K..K+N-1 (default 0)\n"
               "  --max-parallel K                   at most K tasks at once (%K)\n"
               "  --sbatch-option OPT                a further #SBATCH option, e.g. --account=abc\n";
        return 0;
    }
    cl.expect_positional(2, 2, CLUSTER_USAGE);
    if (cl.positional()[0] != "slurm")
        throw_input_error("cluster", "scheduler", "expected 'slurm', got '" + cl.positional()[0] + "'");
    if (!cl.has("--out")) throw_input_error("cluster", "--out", "required: the shared results folder");
    if (!cl.has("--shards")) throw_input_error("cluster", "--shards", "required: the number of array tasks");

    const Suite suite = load_suite(cl.positional()[1]);  // refuse a bad suite before anything is queued
    SbatchOptions o;
    o.contactbench = this_binary();
    o.suite = fs::absolute(suite.path).lexically_normal().string();
    o.suite_name = suite.name;
    o.out = fs::absolute(cl.path("--out")).lexically_normal().string();
    while (o.out.size() > 1 && o.out.back() == '/') o.out.pop_back();
    o.shards = cl.integer("--shards", 1);
    o.first_index = cl.integer("--first-index", 0);
    // A task gets the cores its most threaded label uses (the `threads` setting), unless told more.
    const long threads = most_threads(suite);
    o.cpus_per_task = cl.integer("--cpus-per-task", threads);
    if (o.cpus_per_task >= 1 && o.cpus_per_task < threads)
        throw_input_error("cluster", "--cpus-per-task",
                          std::to_string(o.cpus_per_task) + " is fewer than the " + std::to_string(threads) +
                              " threads a label of " + suite.path + " asks for (setting `threads`)");
    o.max_parallel = cl.integer("--max-parallel", 0);
    o.partition = cl.value("--partition");
    o.time = cl.value("--time");
    o.mem = cl.value("--mem");
    o.exclusive = cl.has("--exclusive");
    o.extra = cl.values("--sbatch-option");
    check_sbatch_options(o);  // bounds and safe values before any snapshot is generated or file written

    const size_t jobs = resolve_snapshots(suite).size() * suite.solvers.size();
    if (static_cast<size_t>(o.shards) > jobs)
        std::cerr << "cluster: note: " << o.shards << " shards for " << jobs
                  << " jobs: some tasks will have nothing to do\n";

    const fs::path dir = fs::path(o.out) / "slurm";
    fs::create_directories(dir);
    write_file_atomic((dir / "array.sbatch").string(), sbatch_array_script(o));
    write_file_atomic((dir / "merge.sbatch").string(), sbatch_merge_script(o));
    std::cerr << "cluster: wrote " << (dir / "array.sbatch").string() << " (" << o.shards << " tasks, array "
              << o.first_index << "-" << o.first_index + o.shards - 1 << ") and " << (dir / "merge.sbatch").string()
              << "\n";
    std::cout << "jobid=$(sbatch --parsable " << shell_quote((dir / "array.sbatch").string()) << ")\n"
              << "sbatch --dependency=afterok:$jobid " << shell_quote((dir / "merge.sbatch").string()) << "\n";
    return 0;
}

}  // namespace cb
