// libFuzzer entry point for the suite reader (harness/suite.hpp): any byte string given as a
// suite file must either parse into a valid Suite or be rejected with an InputError. A crash, a
// sanitizer report, a hang (deep nesting) or any other exception is a bug in the reader.
// Build: cmake -DCB_FUZZ=ON with CXX=clang++ (target fuzz_suite), see tests/fuzz/README.md.
#include "harness/suite.hpp"
#include "problems/io_util.hpp"
#include "solvers/core/types.hpp"

#include <cstdint>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
    // The bytes as read_json_file sees them: depth check, then nlohmann, then the validation.
    const std::string text(reinterpret_cast<const char*>(data), size);
    try {
        const cb::Suite suite = cb::parse_suite(cb::parse_json_text(text, "fuzz-suite.json"), "fuzz-suite.json");
        // A returned suite is whole: a name and at least one solver, labels unique.
        if (suite.name.empty() || suite.solvers.empty()) __builtin_trap();
        if (suite.snapshots.empty() && suite.generate.empty()) __builtin_trap();
    } catch (const cb::InputError&) {
        // the expected rejection of a bad suite
    }
    return 0;
}
