// libFuzzer entry point for the .qpsnap reader (DESIGN.md "Snapshot format"): any byte string
// must either load as a valid QP or be rejected with an InputError; a crash, a sanitizer report,
// a hang or any other exception escaping read_qpsnap is a bug in the reader.
// Build: cmake -DCB_FUZZ=ON with CXX=clang++ (target fuzz_qpsnap), or see tests/fuzz/README.md.
#include "problems/qpsnap.hpp"

#include <cstdint>
#include <cstdio>
#include <string>
#include <unistd.h>

namespace {

/// One temporary file per process, in memory (/dev/shm) when available.
const std::string& scratch_path()
{
    static const std::string path = [] {
        const char* dir = access("/dev/shm", W_OK) == 0 ? "/dev/shm" : "/tmp";
        return std::string(dir) + "/cb_fuzz_qpsnap_" + std::to_string(getpid()) + ".qpsnap";
    }();
    return path;
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
    const std::string& path = scratch_path();
    std::FILE* f = std::fopen(path.c_str(), "wb");
    if (!f) return 0;
    if (size) std::fwrite(data, 1, size, f);
    std::fclose(f);
    try {
        cb::SnapshotExtras extras;
        const cb::Qp qp = cb::read_qpsnap(path, &extras);
        // A returned problem must be whole: the dimensions agree.
        if (qp.b.size() != qp.n() || qp.x0.size() != qp.n() || qp.J.cols() != qp.n() || qp.c.size() != qp.m() ||
            qp.A.cols() != qp.n())
            __builtin_trap();
    } catch (const cb::InputError&) {
        // the expected rejection of a bad file
    }
    return 0;
}
