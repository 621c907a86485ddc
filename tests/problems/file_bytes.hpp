#pragma once
/// A file's whole content as bytes (what the writers' tests compare).
#include <fstream>
#include <iterator>
#include <string>

namespace cb::test {

inline std::string file_bytes(const std::string& path)
{
    std::ifstream in(path, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
}

}  // namespace cb::test
