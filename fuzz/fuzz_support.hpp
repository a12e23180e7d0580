// Shared pieces of the libFuzzer targets: a scratch file that holds the
// current input (the path-based readers need a file name), and the rule for
// exceptions.
//
// The rule: a reader may refuse any input, but only with umbra::FormatError,
// or with umbra::MemoryLimitError when what the input honestly describes
// needs more than the memory limit (set to 256 MiB for the fuzzers, well
// under libFuzzer's 2 GB). Anything else escaping it (another exception
// type, a failed UMBRA_ASSERT, a sanitizer report, an abort) is a bug and is
// turned into a crash so that libFuzzer records the input. Cost: one pwrite and one ftruncate of a tmpfs
// file per input.
#pragma once

#include <fcntl.h>
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <string>

#include "map/map_access.hpp"
#include "umbra/core/memory_limit.hpp"
#include "umbra/io/format_error.hpp"
#include "umbra/map/occupancy_map.hpp"

namespace umbra::fuzz {

/// The memory limit every fuzz target runs under, set when the program starts.
inline constexpr std::uint64_t kMemoryLimit = std::uint64_t{256} << 20;
inline const bool kMemoryLimitSet = (set_memory_limit(kMemoryLimit), true);

/// A file in /dev/shm (or the temp folder) that holds each input in turn.
class InputFile {
 public:
  /// `suffix` is the end of the file name, e.g. ".xyz.bz2" for readers that go by the name.
  explicit InputFile(const std::string& suffix) {
    std::filesystem::path folder = "/dev/shm";
    if (!std::filesystem::is_directory(folder)) folder = std::filesystem::temp_directory_path();
    path_ = folder / ("umbra-fuzz-" + std::to_string(::getpid()) + suffix);
    fd_ = ::open(path_.c_str(), O_RDWR | O_CREAT | O_TRUNC | O_CLOEXEC, 0600);
    if (fd_ < 0) {
      std::perror(path_.c_str());
      std::abort();
    }
  }
  InputFile(const InputFile&) = delete;
  InputFile& operator=(const InputFile&) = delete;
  ~InputFile() {
    ::close(fd_);
    ::unlink(path_.c_str());
  }

  /// Replaces the file's content with the input; returns its path.
  const std::filesystem::path& hold(const std::uint8_t* data, std::size_t size) {
    if (::ftruncate(fd_, 0) != 0) std::abort();
    std::size_t done = 0;
    while (done < size) {
      const ssize_t n = ::pwrite(fd_, data + done, size - done, static_cast<off_t>(done));
      if (n <= 0) std::abort();
      done += static_cast<std::size_t>(n);
    }
    return path_;
  }

 private:
  std::filesystem::path path_;
  int fd_ = -1;
};

/// Runs `read`; FormatError is an accepted answer, anything else a crash.
template <typename Read>
void expect_only_format_errors(Read&& read) {
  try {
    read();
  } catch (const FormatError&) {
    // A refusal, as it should be.
  } catch (const MemoryLimitError&) {
    // An input that needs more than the limit: refused before allocating, as it should be.
  } catch (const std::exception& e) {
    std::fprintf(stderr, "reader threw something other than FormatError: %s\n", e.what());
    std::abort();
  }
}

/// Crashes with a message when `condition` is false (a property of a successful read).
/// Whether every invariant of the map's tree holds.
inline bool invariants_hold(const OccupancyMap& map) {
  return detail::MapAccess::read(map, [](const OccupancyTree& tree) { return tree.check_invariants().empty(); });
}

inline void require(bool condition, const char* what) {
  if (condition) return;
  std::fprintf(stderr, "property violated: %s\n", what);
  std::abort();
}

}  // namespace umbra::fuzz
