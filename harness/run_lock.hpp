#pragma once
/// The lock of an output folder that `run`, `simulate` and `chains` take (DESIGN.md "Runs and
/// chains"): two commands writing into one folder would mix or truncate each other's files.
#include <string>

namespace cb {

/// Creates `out` (and its parents) when missing and holds an exclusive flock on OUT/.lock for
/// the life of the process (the kernel releases it however the process ends). The lock file
/// holds "<pid> <command>" for the message of a second command, which is refused (InputError,
/// exit 2): "OUT: another `contactbench <command>` (pid N) is writing to this folder; ...".
/// A .lock that is not a regular file (a planted symlink) is refused, never followed.
void lock_output_folder(const std::string& out, const std::string& command);

/// Releases the lock this process took with lock_output_folder (no-op without one): for a
/// command whose output is whole before it ends, so that readers that refuse a locked folder
/// (the HTML report of `run`, plots/loader.py) can read it while the command finishes.
void release_output_folder_lock();

}  // namespace cb
