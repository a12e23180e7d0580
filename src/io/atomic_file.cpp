// write_file_atomically(): temporary file, fsync, rename (see atomic_file.hpp).
//
// Cost: the bytes are written once with write(2) (retried on EINTR and short
// writes), then one fsync of the file and one of its folder.
#include "atomic_file.hpp"

#include "umbra/io/map_file.hpp"  // set_map_file_fault_for_testing

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <chrono>
#include <functional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <system_error>
#include <utility>

namespace umbra::detail {
namespace {

namespace fs = std::filesystem;

/// Closes the descriptor and removes the temporary file unless released.
class TemporaryFile {
 public:
  TemporaryFile(const fs::path& target, std::string_view kind)
      : target_(target), context_("cannot save " + std::string(kind) + " to '" + target.string() + "': ") {
    static std::atomic<std::uint64_t> counter{0};
    const fs::path folder = target.has_parent_path() ? target.parent_path() : fs::path(".");
    const auto tick = static_cast<std::uint64_t>(std::chrono::steady_clock::now().time_since_epoch().count());
    for (int attempt = 0;; ++attempt) {
      path_ = folder / ("." + target.filename().string() + ".tmp-" + std::to_string(::getpid()) + "-" +
                        std::to_string(counter++) + "-" + std::to_string(tick % 1000000007u));
      fd_ = ::open(path_.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
      if (fd_ >= 0) return;
      if (errno != EEXIST || attempt >= 100) fail("cannot create temporary file", errno);
    }
  }
  TemporaryFile(const TemporaryFile&) = delete;
  TemporaryFile& operator=(const TemporaryFile&) = delete;
  ~TemporaryFile() {
    if (fd_ >= 0) ::close(fd_);
    if (!renamed_) ::unlink(path_.c_str());
  }

  void write(std::span<const std::uint8_t> bytes) {
    std::size_t done = 0;
    while (done < bytes.size()) {
      const ssize_t n = ::write(fd_, bytes.data() + done, bytes.size() - done);
      if (n < 0) {
        if (errno == EINTR) continue;
        fail("cannot write temporary file", errno);
      }
      done += static_cast<std::size_t>(n);
    }
  }

  void commit() {
    // Keep the permissions of the file being replaced (umask applies to new files).
    struct stat old {};
    if (::stat(target_.c_str(), &old) == 0 && S_ISREG(old.st_mode)) ::fchmod(fd_, old.st_mode & 07777);
    if (::fsync(fd_) != 0) fail("cannot flush temporary file", errno);
    const int fd = std::exchange(fd_, -1);
    if (::close(fd) != 0) fail("cannot close temporary file", errno);
    if (::rename(path_.c_str(), target_.c_str()) != 0) {
      throw std::runtime_error(context_ + "cannot rename temporary file '" + path_.string() +
                               "' to it: " + std::generic_category().message(errno));
    }
    renamed_ = true;
  }

 private:
  /// "cannot save KIND to 'TARGET': WHAT 'TEMP': REASON"
  [[noreturn]] void fail(const std::string& what, int error) const {
    throw std::runtime_error(context_ + what + " '" + path_.string() + "': " + std::generic_category().message(error));
  }

  fs::path target_;
  std::string context_;
  fs::path path_;
  int fd_ = -1;
  bool renamed_ = false;
};

std::function<void()>& fault_hook() {
  static std::function<void()> hook;
  return hook;
}

}  // namespace

void set_map_file_fault_for_testing(std::function<void()> hook) { fault_hook() = std::move(hook); }

void write_file_atomically(const fs::path& path, std::initializer_list<std::span<const std::uint8_t>> parts,
                           std::string_view kind) {
  {
    TemporaryFile temp(path, kind);
    bool first = true;
    for (const auto part : parts) {
      temp.write(part);
      if (std::exchange(first, false) && fault_hook()) fault_hook()();
    }
    temp.commit();
  }
  // Make the rename itself durable. Best effort: the file is already complete
  // under its name, and some file systems refuse fsync on folders.
  const fs::path folder = path.has_parent_path() ? path.parent_path() : fs::path(".");
  if (const int dir = ::open(folder.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC); dir >= 0) {
    ::fsync(dir);
    ::close(dir);
  }
}

}  // namespace umbra::detail
