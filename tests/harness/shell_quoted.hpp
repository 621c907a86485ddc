#pragma once
/// A path in single quotes, as one word of a bash command line (the tests' paths have no quote).
#include <filesystem>
#include <string>

namespace cb::test {

inline std::string shell_quoted(const std::filesystem::path& p) { return "'" + p.string() + "'"; }

}  // namespace cb::test
