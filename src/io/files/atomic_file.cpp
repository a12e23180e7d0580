// Atomic saves: write_file_atomically(), AtomicFileWriter and the clean-up
// of interrupted saves (umbra/io/file_saving.hpp).
//
// Temporary files are named `.NAME.tmp-PID-N-SALT` beside their target. A
// fixed table of 64 slots lists the ones being written, so that a signal
// handler can remove them without allocating or locking: a slot is claimed
// with an atomic exchange, filled, then published. Cost: the bytes are
// written once with write(2) (retried on EINTR and short writes), then one
// fsync of the file and one of its folder; one listing of the folder to find
// stale temporary files.
#include "umbra/io/file_saving.hpp"
#include "umbra/io/map_file.hpp"  // set_map_file_fault_for_testing

#include <fcntl.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include "core/assert.hpp"

#include <array>
#include <atomic>
#include <cerrno>
#include <charconv>
#include <chrono>
#include <climits>
#include <cstring>
#include <functional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <system_error>
#include <utility>

namespace umbra::detail {
namespace {

namespace fs = std::filesystem;

// --- the saves in progress, for remove_unfinished_saves() ------------------------

enum SlotState : int { kFree = 0, kFilling = 1, kListed = 2 };

struct Slot {
  std::atomic<int> state{kFree};
  char path[PATH_MAX] = {};
};
static_assert(std::atomic<int>::is_always_lock_free, "a signal handler reads the slots");

std::array<Slot, 64> g_slots;

/// Lists `path`; the slot number, or -1 when all slots are taken (the file is
/// then only cleaned up by a later save, as after kill -9).
int list_temporary(const fs::path& path) {
  const std::string& text = path.native();
  if (text.size() >= PATH_MAX) return -1;
  for (std::size_t i = 0; i < g_slots.size(); ++i) {
    int expected = kFree;
    if (!g_slots[i].state.compare_exchange_strong(expected, kFilling, std::memory_order_acquire)) continue;
    std::memcpy(g_slots[i].path, text.c_str(), text.size() + 1);
    g_slots[i].state.store(kListed, std::memory_order_release);
    return static_cast<int>(i);
  }
  return -1;
}

void unlist_temporary(int slot) {
  if (slot >= 0) g_slots[static_cast<std::size_t>(slot)].state.store(kFree, std::memory_order_release);
}

// --- names ---------------------------------------------------------------------

/// `path`, or the file its chain of symbolic links ends at (which need not exist).
fs::path through_links(const fs::path& path) {
  fs::path current = path;
  for (int hop = 0; hop < 40; ++hop) {
    std::error_code error;
    if (!fs::is_symlink(fs::symlink_status(current, error))) return current;
    const fs::path target = fs::read_symlink(current, error);
    if (error) return current;
    current = target.is_absolute() ? target : current.parent_path() / target;
  }
  throw std::runtime_error("cannot save to '" + path.string() + "': too many levels of symbolic links");
}

fs::path folder_of(const fs::path& path) { return path.has_parent_path() ? path.parent_path() : fs::path("."); }

/// ".NAME.tmp-"
std::string temporary_prefix(const fs::path& target) { return "." + target.filename().string() + ".tmp-"; }

/// Whether process `pid` exists (as far as this process can see).
bool process_exists(long pid) { return pid > 0 && (::kill(static_cast<pid_t>(pid), 0) == 0 || errno == EPERM); }

/// Removes the temporary files of `target` whose process is gone and whose
/// lock is free: what a save killed with SIGKILL (or a power cut) leaves.
void remove_stale_temporaries(const fs::path& target) {
  const std::string prefix = temporary_prefix(target);
  std::error_code error;
  for (fs::directory_iterator it(folder_of(target), error), end; !error && it != end; it.increment(error)) {
    const std::string name = it->path().filename().string();
    if (!name.starts_with(prefix)) continue;
    long pid = 0;
    const char* digits = name.data() + prefix.size();
    const auto [after, status] = std::from_chars(digits, name.data() + name.size(), pid);
    if (status != std::errc() || after == digits || *after != '-' || process_exists(pid)) continue;
    // Its process is gone here; the lock tells whether one in another PID namespace still writes it.
    const int fd = ::open(it->path().c_str(), O_RDONLY | O_NOFOLLOW | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0) continue;
    struct stat info {};
    if (::fstat(fd, &info) == 0 && S_ISREG(info.st_mode) && ::flock(fd, LOCK_EX | LOCK_NB) == 0) {
      ::unlink(it->path().c_str());
    }
    ::close(fd);
  }
}

// --- the temporary file ---------------------------------------------------------------

/// Closes the descriptor and removes the temporary file unless renamed.
class TemporaryFile {
 public:
  TemporaryFile(const fs::path& target, std::string_view kind)
      : target_(target), context_("cannot save " + std::string(kind) + " to '" + target.string() + "': ") {
    static std::atomic<std::uint64_t> counter{0};
    const auto tick = static_cast<std::uint64_t>(std::chrono::steady_clock::now().time_since_epoch().count());
    for (int attempt = 0;; ++attempt) {
      path_ = folder_of(target) / (temporary_prefix(target) + std::to_string(::getpid()) + "-" +
                                   std::to_string(counter++) + "-" + std::to_string(tick % 1000000007u));
      slot_ = list_temporary(path_);  // before it exists, so that no signal can leave it behind
      fd_ = ::open(path_.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
      if (fd_ >= 0) break;
      const int error = errno;
      unlist_temporary(std::exchange(slot_, -1));
      if (error != EEXIST || attempt >= 100) fail("cannot create temporary file", error);
    }
    // Held until the file is renamed or removed: a save in another process sees it as live.
    ::flock(fd_, LOCK_EX | LOCK_NB);
  }
  TemporaryFile(const TemporaryFile&) = delete;
  TemporaryFile& operator=(const TemporaryFile&) = delete;
  ~TemporaryFile() {
    if (!renamed_) ::unlink(path_.c_str());
    if (fd_ >= 0) ::close(fd_);
    unlist_temporary(slot_);
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
  int slot_ = -1;
  bool renamed_ = false;
};

std::function<void()>& fault_hook() {
  static std::function<void()> hook;
  return hook;
}

}  // namespace

void set_map_file_fault_for_testing(std::function<void()> hook) { fault_hook() = std::move(hook); }

}  // namespace umbra::detail

namespace umbra {

class AtomicFileWriter::Temporary : public detail::TemporaryFile {
 public:
  using TemporaryFile::TemporaryFile;
};

AtomicFileWriter::AtomicFileWriter(const std::filesystem::path& path, std::string_view kind)
    : path_(detail::through_links(path)) {
  detail::remove_stale_temporaries(path_);
  temporary_ = std::make_unique<Temporary>(path_, kind);
}

AtomicFileWriter::~AtomicFileWriter() = default;

void AtomicFileWriter::write(std::span<const std::uint8_t> bytes) {
  UMBRA_ASSERT(temporary_ != nullptr);  // write() after commit()
  temporary_->write(bytes);
}

void AtomicFileWriter::commit() {
  UMBRA_ASSERT(temporary_ != nullptr);
  temporary_->commit();
  temporary_.reset();
  // Make the rename itself durable. Best effort: the file is already complete
  // under its name, and some file systems refuse fsync on folders.
  if (const int dir = ::open(detail::folder_of(path_).c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC); dir >= 0) {
    ::fsync(dir);
    ::close(dir);
  }
}

void write_file_atomically(const std::filesystem::path& path,
                           std::initializer_list<std::span<const std::uint8_t>> parts, std::string_view kind) {
  AtomicFileWriter file(path, kind);
  bool first = true;
  for (const auto part : parts) {
    file.write(part);
    if (std::exchange(first, false) && detail::fault_hook()) detail::fault_hook()();
  }
  file.commit();
}

void remove_unfinished_saves() noexcept {
  for (detail::Slot& slot : detail::g_slots) {
    if (slot.state.load(std::memory_order_acquire) == detail::kListed) ::unlink(slot.path);
  }
}

void check_can_save(const std::filesystem::path& path) {
  const std::filesystem::path target = detail::through_links(path);
  std::error_code error;
  if (std::filesystem::is_directory(target, error)) {
    throw std::runtime_error("cannot save to '" + path.string() + "': it is a folder");
  }
  const AtomicFileWriter probe(target, "a file");  // created and removed again
}

}  // namespace umbra
