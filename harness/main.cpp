// contactbench: parse the subcommand and dispatch. Exit status: 0 ran, 2 bad input, 1 internal error.
#include "harness/blas_threads.hpp"
#include "harness/command_solver.hpp"
#include "harness/commands.hpp"
#include "solvers/core/types.hpp"

#include <csignal>
#include <cstring>
#include <iostream>
#include <map>

namespace {

struct Command {
    int (*run)(const cb::Args&);
    const char* summary;
};

const std::map<std::string, Command>& commands()
{
    static const std::map<std::string, Command> table = {
        {"info", {cb::cmd_info, "info SNAP: header, sizes, contact kinds, content hash"}},
        {"convert", {cb::cmd_convert, "convert IN OUT: .qpsnap <-> Matrix Market folder (by extension)"}},
        {"solve", {cb::cmd_solve, "solve SNAP --solver NAME [--set k=v ...] [--json FILE] [--save-solution DIR]"}},
        {"judge",
         {cb::cmd_judge,
          "judge SNAP SOLUTION [--tol T] [--record RUN.json] [--json FILE]: the accuracy of any answer"}},
        {"run", {cb::cmd_run, "run SUITE.json [--out DIR] [--shard i/N]: a suite of snapshots x solvers"}},
        {"merge", {cb::cmd_merge, "merge OUT DIR...: join the shard folders DIR... of a suite run into OUT"}},
        {"generate", {cb::cmd_generate, "generate FAMILY --out FILE [--seed S ...]: write a synthetic snapshot"}},
        {"simulate",
         {cb::cmd_simulate, "simulate SCENE.json [--frames N] [--out DIR] [--data DIR]: snapshots of a scene"}},
        {"chains",
         {cb::cmd_chains, "chains SCENE.json [--frames N] [--out DIR]: decoupled vs exact chains of a scene"}},
        {"friction-solve",
         {cb::cmd_friction_solve,
          "friction-solve FILE.hdf5 [--solver nsgs|siconos-nsgs|siconos-nsn|...]: an FCLIB problem with friction"}},
        {"solvers",
         {cb::cmd_solvers, "solvers [--json]: every registered solver, one line each, with what it applies to"}},
        {"stress", {cb::cmd_stress, "stress [--out DIR]: the stress suite and its stability table"}},
        {"report",
         {cb::cmd_report, "report OUT: OUT/report/index.html, every run, its histories and profiles (offline)"}},
        {"compare", {cb::cmd_compare, "compare BASE NEW: regression judge between two result sets"}},
        {"cluster",
         {cb::cmd_cluster, "cluster slurm SUITE.json --out DIR --shards N: sbatch files of a job array + merge"}},
    };
    return table;
}

void usage(std::ostream& out)
{
    out << "contactbench: a benchmark harness for contact QP solvers\n"
           "  minimize 1/2 x'Ax - b'x  subject to  Jx >= c\n\nusage: contactbench COMMAND [options]   "
           "(contactbench COMMAND --help for details)\n\ncommands:\n";
    for (const auto& kv : commands()) out << "  " << kv.second.summary << "\n";
    out << "  --version [--json]: commit, build type, compiler and library versions\n"
           "\nexit status: 0 the command ran (whatever a solver's status), 2 bad input, 1 internal error\n";
}

}  // namespace

int main(int argc, char** argv)
{
    cb::limit_blas_threads();      // timed runs on one BLAS thread unless OPENBLAS_NUM_THREADS says otherwise
    cb::install_command_solver();  // `command` lives in harness/ (it writes files); see command_solver.hpp
    if (argc < 2 || !std::strcmp(argv[1], "--help") || !std::strcmp(argv[1], "-h") || !std::strcmp(argv[1], "help")) {
        usage(std::cout);
        return argc < 2 ? 2 : 0;
    }
    const bool version = !std::strcmp(argv[1], "--version") || !std::strcmp(argv[1], "version");
    const auto it = version ? commands().end() : commands().find(argv[1]);
    if (!version && it == commands().end()) {
        std::cerr << "contactbench: unknown command '" << argv[1] << "'\n";
        usage(std::cerr);
        return 2;
    }
    // Past a file-size limit (ulimit -f) a write must fail with EFBIG and a clear error, not kill us.
    std::signal(SIGXFSZ, SIG_IGN);
    const cb::Args args(argv + 2, argv + argc);
    try {
        return version ? cb::cmd_version(args) : it->second.run(args);
    } catch (const cb::InputError& e) {
        std::cerr << "contactbench " << argv[1] << ": error: " << e.what() << "\n";
        return 2;
    } catch (const std::exception& e) {
        std::cerr << "contactbench " << argv[1] << ": internal error: " << e.what() << "\n";
        return 1;
    }
}
