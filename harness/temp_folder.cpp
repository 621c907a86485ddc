#include "harness/temp_folder.hpp"

#include <stdlib.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <system_error>

namespace cb {

TempFolder::TempFolder(const std::string& prefix, bool keep) : m_keep(keep)
{
    std::error_code ec;
    const std::filesystem::path base = std::filesystem::temp_directory_path(ec);
    if (ec) throw std::runtime_error("cannot find the temporary folder ($TMPDIR): " + ec.message());
    std::string pattern = (base / (prefix + "-XXXXXX")).string();
    if (::mkdtemp(pattern.data()) == nullptr)
        throw std::runtime_error("cannot create a temporary folder " + pattern + ": " + std::strerror(errno));
    m_path = pattern;
}

TempFolder::~TempFolder()
{
    std::error_code ignored;  // a folder that cannot be removed is left behind, never an exception here
    if (!m_keep) std::filesystem::remove_all(m_path, ignored);
}

}  // namespace cb
