#include "support/test_support.hpp"

#include <atomic>
#include <unistd.h>

namespace umbra::test {

std::optional<std::filesystem::path> shared_data(const std::string& relative) {
  const std::filesystem::path path = std::filesystem::path(UMBRA_SHARED_DATA_DIR) / relative;
  if (std::filesystem::exists(path)) return path;
  return std::nullopt;
}

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
  return dir;
}

std::filesystem::path source_dir() { return UMBRA_SOURCE_DIR; }

}  // namespace umbra::test
