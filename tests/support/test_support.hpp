// Helpers shared by the test suites: the shared sensor data, scratch folders.
#pragma once

#include <filesystem>
#include <optional>
#include <string>

#include <gtest/gtest.h>

namespace umbra::test {

/// ../shared/data/<relative> if it exists (see tests/CMakeLists.txt), else nothing.
std::optional<std::filesystem::path> shared_data(const std::string& relative);

/// A fresh, empty folder for the running test under the system temp folder.
std::filesystem::path scratch_dir();

/// The project's source folder (for README checks and scripts).
std::filesystem::path source_dir();

}  // namespace umbra::test

/// Declares `variable` as the path of the shared data file `relative`, or
/// skips the test with a message saying what is missing.
#define UMBRA_REQUIRE_SHARED_DATA(variable, relative)                                          \
  const auto variable##_found = ::umbra::test::shared_data(relative);                          \
  if (!variable##_found) {                                                                     \
    GTEST_SKIP() << "shared data file " << (relative)                                         \
                 << " not found (looked in " UMBRA_SHARED_DATA_DIR "); skipping this test";    \
  }                                                                                            \
  const ::std::filesystem::path variable = *variable##_found
