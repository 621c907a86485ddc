#pragma once
/// The subcommands of `contactbench`; each lives in its own harness/cmd_<name>.cpp.
/// Each returns the process exit status: 0 ran, 2 bad input (InputError), 1 internal error.
#include <string>
#include <vector>

namespace cb {

using Args = std::vector<std::string>;

int cmd_info(const Args& args);
int cmd_convert(const Args& args);
int cmd_solve(const Args& args);
int cmd_judge(const Args& args);
int cmd_run(const Args& args);
int cmd_merge(const Args& args);
int cmd_simulate(const Args& args);
int cmd_chains(const Args& args);  // issue 25: the price of decoupling along chains
int cmd_stress(const Args& args);
int cmd_report(const Args& args);  // issue 46: the HTML report of a results folder
int cmd_compare(const Args& args);
int cmd_generate(const Args& args);
int cmd_solvers(const Args& args);
int cmd_friction_solve(const Args& args);  // issue 48: FCLIB local problems with friction
int cmd_version(const Args& args);
// Slurm job arrays (issue 19).
int cmd_cluster(const Args& args);

}  // namespace cb
