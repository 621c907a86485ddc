// libFuzzer entry point for judge's solution readers (problems/solution_io.hpp): the first byte
// of an input picks the format (.npy, .mtx or plain text) and the snapshot's n (1..64), the rest
// is the file. read_solution must return x of exactly n finite entries or throw InputError; a
// crash, a sanitizer report, a hang, an out-of-memory (the readers must allocate by n, never by
// a size the file declares) or any other exception is a finding.
#include "problems/solution_io.hpp"

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>
#include <unistd.h>

// NOLINTNEXTLINE(readability-identifier-naming): libFuzzer's fixed entry point
extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
    if (size == 0) return 0;
    static const char* const extensions[3] = {".npy", ".mtx", ".txt"};
    // One scratch file per format and process, removed when libFuzzer exits.
    static const struct Scratch {
        std::string stem = "/dev/shm/cb_fuzz_solution_" + std::to_string(::getpid()) + "_x";
        ~Scratch()
        {
            for (const char* ext : extensions) ::unlink((stem + ext).c_str());
        }
    } scratch;
    const std::string path = scratch.stem + extensions[data[0] % 3];
    const long n = 1 + (data[0] / 3) % 64;
    std::FILE* f = std::fopen(path.c_str(), "wb");
    if (!f) __builtin_trap();
    if (size > 1 && std::fwrite(data + 1, 1, size - 1, f) != size - 1) __builtin_trap();
    std::fclose(f);
    try {
        const cb::SolutionPoint point = cb::read_solution(path, n, 0);
        if (point.x.size() != n || point.lambda.size() != 0) __builtin_trap();
        for (Eigen::Index i = 0; i < n; ++i)
            if (!std::isfinite(point.x[i])) __builtin_trap();
    } catch (const cb::InputError&) {
        // the expected rejection of a bad file
    }
    return 0;
}
