#include "support/test_support.hpp"

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <vector>

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

std::vector<std::uint8_t> read_bytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::vector<std::uint8_t>(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

void write_bytes(const std::filesystem::path& path, std::span<const std::uint8_t> bytes) {
  std::filesystem::remove(path);
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  ASSERT_TRUE(out.good()) << path;
}

void write_file(const std::filesystem::path& path, std::string_view contents) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  ASSERT_TRUE(out) << path;
  out.write(contents.data(), static_cast<std::streamsize>(contents.size()));
  ASSERT_TRUE(out) << path;
}

std::vector<Scan> read_all(ScanSource& source) {
  std::vector<Scan> scans;
  Scan scan;
  while (source.next(scan)) scans.push_back(scan);
  return scans;
}

std::vector<Scan> read_all(const std::filesystem::path& path, const ScanSourceOptions& options) {
  const auto source = open_scan_source(path, options);
  return read_all(*source);
}

CommandResult run_command(const std::string& command) {
  CommandResult result;
  std::FILE* pipe = ::popen((command + " 2>&1").c_str(), "r");
  if (pipe == nullptr) return result;
  std::array<char, 4096> buffer{};
  std::size_t n = 0;
  while ((n = std::fread(buffer.data(), 1, buffer.size(), pipe)) > 0) result.output.append(buffer.data(), n);
  const int status = ::pclose(pipe);
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return result;
}

AddressSpaceCap::AddressSpaceCap(std::uint64_t extra) {
#if !defined(__SANITIZE_ADDRESS__)
  ::getrlimit(RLIMIT_AS, &saved_);
  std::ifstream statm("/proc/self/statm");
  std::uint64_t pages = 0;
  statm >> pages;
  rlimit lowered = saved_;
  const std::uint64_t wanted = pages * static_cast<std::uint64_t>(::sysconf(_SC_PAGESIZE)) + extra;
  lowered.rlim_cur = saved_.rlim_max == RLIM_INFINITY ? wanted : std::min<std::uint64_t>(wanted, saved_.rlim_max);
  active_ = pages > 0 && ::setrlimit(RLIMIT_AS, &lowered) == 0;
#else
  (void)extra;
#endif
}

AddressSpaceCap::~AddressSpaceCap() {
  if (active_) ::setrlimit(RLIMIT_AS, &saved_);
}

MemoryLimitScope::MemoryLimitScope(std::uint64_t bytes) : saved_(memory_limit()) { set_memory_limit(bytes); }

MemoryLimitScope::~MemoryLimitScope() { set_memory_limit(saved_); }

}  // namespace umbra::test
