#pragma once
/// A test program's scratch folder removed when its tests have run, as one line:
///   const auto* const CLEAN_UP = ::testing::AddGlobalTestEnvironment(new test::RemoveAtEnd(work_dir));
#include <gtest/gtest.h>

#include <filesystem>

namespace cb::test {

/// Removes the folder `folder()` names when the test program's tests have run (a GoogleTest global
/// environment).
class RemoveAtEnd : public ::testing::Environment {
public:
    explicit RemoveAtEnd(const std::filesystem::path& (*folder)()) : m_folder(folder) {}
    void TearDown() override { std::filesystem::remove_all(m_folder()); }

private:
    const std::filesystem::path& (*m_folder)();
};

}  // namespace cb::test
