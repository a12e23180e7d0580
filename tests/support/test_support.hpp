// Helpers shared by the test suites: the shared sensor data, scratch folders,
// whole-file bytes, running the CLI, capping the address space.
#pragma once

#include <sys/resource.h>

#include <cstdint>
#include <filesystem>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "umbra/core/memory_limit.hpp"
#include "umbra/io/scan_source.hpp"

#include <gtest/gtest.h>

namespace umbra::test {

/// ../shared/data/<relative> if it exists (see tests/CMakeLists.txt), else nothing.
std::optional<std::filesystem::path> shared_data(const std::string& relative);

/// A fresh, empty folder for the running test under the system temp folder.
std::filesystem::path scratch_dir();

/// The project's source folder (for README checks and scripts).
std::filesystem::path source_dir();

/// The whole file (empty if it cannot be read).
std::vector<std::uint8_t> read_bytes(const std::filesystem::path& path);

/// Replaces `path` by a new file holding `bytes` (new rather than truncated:
/// ext4 flushes a truncated file to disk on close); a failure fails the test.
void write_bytes(const std::filesystem::path& path, std::span<const std::uint8_t> bytes);

/// Writes `contents` to `path` (replacing it); a failure fails the test.
void write_file(const std::filesystem::path& path, std::string_view contents);

/// Every scan a source yields, in order.
std::vector<Scan> read_all(ScanSource& source);
std::vector<Scan> read_all(const std::filesystem::path& path, const ScanSourceOptions& options = {});

struct CommandResult {
  int exit_code = -1;
  std::string output;  // stdout and stderr together
};

/// Runs `command` through the shell.
CommandResult run_command(const std::string& command);

/// Lowers the soft address-space limit to the current size plus `extra`, so
/// that allocating what a file merely claims fails (bad_alloc) instead of
/// succeeding lazily; restored on destruction. Inactive under
/// AddressSanitizer (which maps terabytes).
class AddressSpaceCap {
 public:
  explicit AddressSpaceCap(std::uint64_t extra);
  ~AddressSpaceCap();
  AddressSpaceCap(const AddressSpaceCap&) = delete;
  AddressSpaceCap& operator=(const AddressSpaceCap&) = delete;
  /// Whether the limit is in force (not under AddressSanitizer, setrlimit worked).
  [[nodiscard]] bool active() const { return active_; }

 private:
  rlimit saved_{};
  bool active_ = false;
};

/// Sets umbra's memory limit (umbra/core/memory_limit.hpp) for a scope and
/// restores the previous one.
class MemoryLimitScope {
 public:
  explicit MemoryLimitScope(std::uint64_t bytes);
  ~MemoryLimitScope();
  MemoryLimitScope(const MemoryLimitScope&) = delete;
  MemoryLimitScope& operator=(const MemoryLimitScope&) = delete;

 private:
  std::uint64_t saved_;
};

}  // namespace umbra::test

/// Declares `variable` as the path of the shared data file `relative`, or
/// skips the test with a message saying what is missing.
#define UMBRA_REQUIRE_SHARED_DATA(variable, relative)                                          \
  const auto variable##_found = test::shared_data(relative);                          \
  if (!variable##_found) {                                                                     \
    GTEST_SKIP() << "shared data file " << (relative)                                         \
                 << " not found (looked in " UMBRA_SHARED_DATA_DIR "); skipping this test";    \
  }                                                                                            \
  const ::std::filesystem::path variable = *variable##_found
