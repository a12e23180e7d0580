#include "support/test_support.hpp"

#include <atomic>
#include <vector>
#include <unistd.h>

namespace umbra::test {

std::optional<std::filesystem::path> shared_data(const std::string& relative) {
  const std::filesystem::path path = std::filesystem::path(UMBRA_SHARED_DATA_DIR) / relative;
  if (std::filesystem::exists(path)) return path;
  return std::nullopt;
}

namespace {

/// Removes the scratch folders of this test process when it exits.
struct ScratchFolders {
  std::vector<std::filesystem::path> paths;
  ~ScratchFolders() {
    std::error_code ignored;
    for (const auto& path : paths) std::filesystem::remove_all(path, ignored);
  }
};
ScratchFolders g_scratch_folders;

}  // namespace

std::filesystem::path scratch_dir() {
  static std::atomic<int> counter{0};
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  std::string name = info ? std::string(info->test_suite_name()) + "." + info->name() : "umbra";
  for (char& c : name) {
    if (c == '/') c = '_';
  }
  const std::filesystem::path dir = std::filesystem::temp_directory_path() /
                                    ("umbra-test-" + std::to_string(::getpid()) + "-" +
                                     std::to_string(counter++) + "-" + name);
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  g_scratch_folders.paths.push_back(dir);
  return dir;
}

std::filesystem::path source_dir() { return UMBRA_SOURCE_DIR; }

}  // namespace umbra::test
