#pragma once
/// The FCLIB files the tests read (tests/data/fclib, their license in tests/data).
#include <filesystem>

namespace cb::test {

inline const std::filesystem::path FCLIB_DATA = std::filesystem::path(CB_TEST_DATA_DIR) / "fclib";

}  // namespace cb::test
