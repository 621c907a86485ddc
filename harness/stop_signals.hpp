#pragma once
/// SIGINT and SIGTERM as a request to stop at the next whole frame (`simulate`, `chains`): the
/// handler only records the signal, and the loop that checks it leaves a complete, resumable prefix.
#include <csignal>

namespace cb {

/// Installs the handlers (once) and returns the flag they set: 0, or the number of the signal.
const volatile std::sig_atomic_t* catch_stop_signals();

/// The exit status of a command stopped by `signal`: 128 + its number, as the shell reports it.
inline int stopped_exit_status(int signal) { return 128 + signal; }

}  // namespace cb
