// How umbra saves files, and what a program can do about interrupted saves.
//
// Every file umbra writes (.umb, .bt, .ot, .png, ScanGraph .graph, and the
// umbra program's .ply and .html) goes through write_file_atomically() or
// AtomicFileWriter below, which write first to a hidden
// temporary file beside its target, `.NAME.tmp-PID-N-SALT`, which is flushed
// to disk and renamed over the target: the target holds either its old
// contents or the complete new file, never a part. A target that is a
// symbolic link is written through: the file it points to is replaced and
// the link stays a link. Errors are std::runtime_error "cannot save KIND to
// 'PATH': WHAT 'TEMP': REASON", KIND naming the contents ("map", "picture").
// Cost: one write(2) per part or write() call, two fsyncs (the file and its
// folder), one listing of the folder.
//
// A process that dies during a save leaves its temporary file behind. Two
// remedies, both documented in the README ("Errors and limits"):
//  - remove_unfinished_saves() removes the temporary files of the saves
//    running in this process. It is async-signal-safe: call it from a
//    SIGINT / SIGTERM handler (the umbra program does, then dies of the
//    signal as usual).
//  - every save first removes the temporary files of its own target that a
//    dead process left (kill -9, a power cut): a file is removed only when
//    the process its name gives is gone and no process holds its lock.
//    Cost: one listing of the target's folder per save.
#pragma once

#include <cstdint>
#include <filesystem>
#include <initializer_list>
#include <memory>
#include <span>
#include <string_view>

namespace umbra {

/// Saves the bytes of `parts`, one after another, as the file `path`.
void write_file_atomically(const std::filesystem::path& path,
                           std::initializer_list<std::span<const std::uint8_t>> parts, std::string_view kind = "file");

/// A file saved piece by piece, for contents too large to hold in memory at
/// once: the temporary file is created by the constructor, filled by
/// write() and renamed over `path` by commit(); destroyed without commit()
/// (an exception while writing) it is removed and `path` is untouched.
class AtomicFileWriter {
 public:
  explicit AtomicFileWriter(const std::filesystem::path& path, std::string_view kind = "file");
  AtomicFileWriter(const AtomicFileWriter&) = delete;
  AtomicFileWriter& operator=(const AtomicFileWriter&) = delete;
  ~AtomicFileWriter();

  void write(std::span<const std::uint8_t> bytes);
  /// Flushes the file to disk and renames it over the target; write() may not follow.
  void commit();

 private:
  class Temporary;
  std::unique_ptr<Temporary> temporary_;
  std::filesystem::path path_;  // the target, through its symbolic links
};

/// Removes the temporary files of the saves in progress in this process
/// (at most 64 at a time are tracked). Async-signal-safe; the saves fail.
void remove_unfinished_saves() noexcept;

/// Checks, before any work, that a save to `path` can create its temporary
/// file (the folder exists and is writable, `path` is not a folder) by
/// creating one and removing it. Throws std::runtime_error naming the path
/// and the system's reason.
void check_can_save(const std::filesystem::path& path);

}  // namespace umbra
