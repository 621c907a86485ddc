// libFuzzer entry point for the .qpsnap reader (DESIGN.md "Snapshot format"): any byte string
// must either load as a valid QP or be rejected with an InputError; a crash, a sanitizer report,
// a hang or any other exception escaping the reader is a bug in the reader.
// Build: cmake -DCB_FUZZ=ON with CXX=clang++ (target fuzz_qpsnap), or see tests/fuzz/README.md.
#include "problems/qpsnap.hpp"

#include <cstdint>
#include <cstring>
#include <memory>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
    // A heap copy of exactly `size` bytes: malloc's alignment gives the reader the aligned fast
    // path (as a mapped file does), and ASan catches a read even one byte past the end.
    std::unique_ptr<unsigned char[]> copy(new unsigned char[size ? size : 1]);
    if (size) std::memcpy(copy.get(), data, size);
    try {
        cb::SnapshotExtras extras;
        const cb::Qp qp = cb::read_qpsnap_bytes("fuzz-input", copy.get(), size, &extras);
        // A returned problem must be whole: the dimensions agree.
        if (qp.b.size() != qp.n() || qp.x0.size() != qp.n() || qp.J.cols() != qp.n() || qp.c.size() != qp.m() ||
            qp.A.cols() != qp.n())
            __builtin_trap();
    } catch (const cb::InputError&) {
        // the expected rejection of a bad file
    }
    return 0;
}
