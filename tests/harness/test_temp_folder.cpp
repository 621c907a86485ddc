// harness/temp_folder: a fresh folder under $TMPDIR, removed with its contents unless kept, and a
// clear error (not a crash) when the temporary folder is unusable.
#include "harness/temp_folder.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <optional>
#include <stdexcept>
#include <string>

namespace fs = std::filesystem;
using cb::TempFolder;

namespace {

/// Sets TMPDIR for one test and puts the old value back.
class TmpdirOverride {
public:
    explicit TmpdirOverride(const std::string& value)
    {
        if (const char* old = std::getenv("TMPDIR")) m_old = old;
        ::setenv("TMPDIR", value.c_str(), 1);
    }
    ~TmpdirOverride()
    {
        if (m_old)
            ::setenv("TMPDIR", m_old->c_str(), 1);
        else
            ::unsetenv("TMPDIR");
    }

private:
    std::optional<std::string> m_old;
};

}  // namespace

TEST(TempFolder, IsAFreshFolderRemovedWithItsContents)
{
    fs::path path, other;
    {
        const TempFolder folder("cb-test-temp-folder");
        const TempFolder second("cb-test-temp-folder");
        path = folder.path();
        other = second.path();
        EXPECT_TRUE(fs::is_directory(path));
        EXPECT_NE(path, other);
        EXPECT_EQ(path.parent_path(), fs::temp_directory_path());
        EXPECT_EQ(path.filename().string().rfind("cb-test-temp-folder-", 0), 0u);
        fs::create_directories(path / "snapshots");
        std::ofstream(path / "snapshots" / "a.qpsnap") << "x";
    }
    EXPECT_FALSE(fs::exists(path));
    EXPECT_FALSE(fs::exists(other));
}

TEST(TempFolder, KeptFolderStays)
{
    fs::path path;
    {
        const TempFolder folder("cb-test-temp-folder-kept", true);
        path = folder.path();
    }
    EXPECT_TRUE(fs::is_directory(path));
    fs::remove_all(path);
}

TEST(TempFolder, AnUnusableTmpdirIsAnErrorNamingIt)
{
    const TmpdirOverride bad("/nonexistent/cb-test-no-such-folder");
    try {
        const TempFolder folder("cb-test-temp-folder");
        FAIL() << "made " << folder.path();
    } catch (const std::runtime_error& e) {
        EXPECT_NE(std::string(e.what()).find("temporary folder"), std::string::npos) << e.what();
    }
}
