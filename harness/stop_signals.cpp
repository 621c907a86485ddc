#include "harness/stop_signals.hpp"

namespace cb {

namespace {
volatile std::sig_atomic_t g_stop = 0;

void record_stop(int signal) { g_stop = signal; }
}  // namespace

const volatile std::sig_atomic_t* catch_stop_signals()
{
    struct sigaction action {};
    action.sa_handler = record_stop;
    sigemptyset(&action.sa_mask);
    sigaction(SIGINT, &action, nullptr);
    sigaction(SIGTERM, &action, nullptr);
    return &g_stop;
}

}  // namespace cb
