// VmHWM from /proc/self/status and its reset through /proc/self/clear_refs (Linux >= 4.0).
#include "solvers/core/peak_memory.hpp"

#include <algorithm>
#include <atomic>
#include <fstream>
#include <sstream>
#include <string>

namespace cb {

namespace {

std::atomic<bool> g_reset_worked{false};
std::atomic<long> g_children_peak{0};

long read_vm_hwm_bytes()
{
    std::ifstream status("/proc/self/status");
    std::string line;
    while (std::getline(status, line)) {
        if (line.rfind("VmHWM:", 0) != 0) continue;
        std::istringstream fields(line.substr(6));
        long kib = -1;
        std::string unit;
        if (fields >> kib >> unit && unit == "kB" && kib >= 0) return kib * 1024;
        return -1;
    }
    return -1;
}

}  // namespace

void reset_peak_memory()
{
    std::ofstream clear("/proc/self/clear_refs");
    clear << "5";
    clear.flush();
    g_reset_worked = static_cast<bool>(clear);
    g_children_peak = 0;
}

void note_child_peak_memory(long bytes)
{
    long seen = g_children_peak.load();
    while (bytes > seen && !g_children_peak.compare_exchange_weak(seen, bytes)) {}
}

PeakMemory read_peak_memory()
{
    PeakMemory peak;
    peak.process_bytes = read_vm_hwm_bytes();
    peak.children_bytes = g_children_peak.load();
    peak.reset = g_reset_worked.load();
    return peak;
}

}  // namespace cb
