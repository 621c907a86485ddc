#pragma once
/// A fresh folder under the system's temporary folder ($TMPDIR, else /tmp), made by mkdtemp and
/// removed with its contents when it goes out of scope, unless kept: the command solver's work
/// folder and the stress suite's simulated cases. (The TAO peers' Open MPI session folder,
/// solvers/peers/tao_common.hpp, is its own: solvers do not depend on the harness.)
#include <filesystem>
#include <string>

namespace cb {

class TempFolder {
public:
    /// @param prefix  the folder's name before mkdtemp's six random characters
    /// @param keep    leave the folder and its contents behind (for inspection)
    /// @throws std::runtime_error naming the folder and the system's reason when it cannot be made
    explicit TempFolder(const std::string& prefix, bool keep = false);
    ~TempFolder();
    TempFolder(const TempFolder&) = delete;
    TempFolder& operator=(const TempFolder&) = delete;
    const std::filesystem::path& path() const { return m_path; }

private:
    std::filesystem::path m_path;
    bool m_keep;
};

}  // namespace cb
