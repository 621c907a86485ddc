#pragma once
/// Whether a process of this id still exists (a zombie counts): what the leash and timeout tests
/// check after a child was to be killed.
#include <cerrno>
#include <csignal>
#include <sys/types.h>

namespace cb::test {

inline bool process_exists(pid_t pid) { return ::kill(pid, 0) == 0 || errno != ESRCH; }

}  // namespace cb::test
