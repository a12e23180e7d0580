// Whole-file writes that never leave a half-written file under the real name.
//
// write_file_atomically() writes the bytes to a new hidden file beside the
// target (unique per process, call and clock tick; O_EXCL settles any
// clash), flushes it to disk, gives it the permissions of the file it
// replaces, renames it over the target and flushes the folder (best effort).
// On any failure the temporary file is removed and the target is untouched.
// A target that is a symbolic link is written through (the file it points to
// is replaced). While it is written the temporary file is locked (flock) and
// listed for remove_unfinished_saves() (a signal handler's cleanup), and
// before it is created the stale temporary files of the same target that
// dead processes left are removed (umbra/io/file_saving.hpp).
// Cost: one folder listing, one write per part, two fsyncs. Private to umbra_io.
#pragma once

#include <cstdint>
#include <filesystem>
#include <initializer_list>
#include <span>
#include <string>
#include <string_view>

namespace umbra::detail {

/// `kind` names the contents in errors: std::runtime_error
/// "cannot save KIND to 'PATH': WHAT 'TEMP': REASON".
void write_file_atomically(const std::filesystem::path& path,
                           std::initializer_list<std::span<const std::uint8_t>> parts,
                           std::string_view kind = "map");

}  // namespace umbra::detail
