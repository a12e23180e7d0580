// How umbra saves files, and what a program can do about interrupted saves.
//
// Every file umbra writes (.umb, .bt, .ot, .png) goes first to a hidden
// temporary file beside its target, `.NAME.tmp-PID-N-SALT`, which is flushed
// to disk and renamed over the target: the target holds either its old
// contents or the complete new file, never a part. A target that is a
// symbolic link is written through: the file it points to is replaced and
// the link stays a link.
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

#include <filesystem>

namespace umbra {

/// Removes the temporary files of the saves in progress in this process
/// (at most 64 at a time are tracked). Async-signal-safe; the saves fail.
void remove_unfinished_saves() noexcept;

/// Checks, before any work, that a save to `path` can create its temporary
/// file (the folder exists and is writable, `path` is not a folder) by
/// creating one and removing it. Throws std::runtime_error naming the path
/// and the system's reason.
void check_can_save(const std::filesystem::path& path);

}  // namespace umbra
