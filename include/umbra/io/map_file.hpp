// umbra's native map file (.umb): save, load, and read the header alone.
//
// The format (docs/map-format.md) is a fixed 124-byte little-endian header
// (magic, version, flags, MapConfig, node counts, stream sizes, header
// CRC-32), two zstd frames (the tree's child masks and the log-odds of every
// childless node, both in depth-first Morton order) and a CRC-32 of
// everything before it. Inner values and indicators are not stored; load_map
// recomputes them. A loaded map is exactly the saved one: same config, same
// tree shape (unpruned equal siblings included), same float bits, same
// auto-pruning setting.
//
// Cost model: save_map and load_map make one depth-first pass over the tree
// and stream both node streams through zstd in 128 KiB chunks, so besides
// the map itself they hold only the compressed file in memory (a few bytes
// per node, typically). read_map_info reads the header bytes and nothing
// else. Nothing is allocated from a size the file declares before that size
// has been checked against the real file size and the node counts.
//
// Errors: malformed files throw FormatError ("FILE: byte OFFSET: what was
// expected, what was found"); I/O failures throw std::runtime_error naming
// the path and the system's reason; save_map throws std::invalid_argument
// (before creating any file) for a map whose values lie outside its sensor
// model's clamping range, since such a file could not be loaded back.
// Thread safety: any number of saves and loads may run concurrently on
// different paths (the test-only fault hook below excepted).
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>

#include "umbra/core/memory_limit.hpp"
#include "umbra/io/format_error.hpp"
#include "umbra/map/insert_options.hpp"  // max_threads()
#include "umbra/map/occupancy_map.hpp"

namespace umbra {

/// The format version this build writes and the only one it reads.
inline constexpr std::uint32_t kMapFileVersion = 1;

/// What a map file's header says, validated (see read_map_info).
struct MapFileInfo {
  std::uint32_t version = kMapFileVersion;
  MapConfig config;
  bool auto_prune = true;                   ///< false: the map was saved with auto-pruning off
  std::uint64_t inner_nodes = 0;            ///< nodes with children
  std::uint64_t childless_nodes = 0;        ///< leaves and inner leaves (= 7 * inner_nodes + 1)
  std::uint64_t structure_bytes = 0;        ///< decompressed size of the child-mask stream
  std::uint64_t structure_compressed_bytes = 0;
  std::uint64_t values_compressed_bytes = 0;
  std::uint64_t colors_compressed_bytes = 0;  ///< 0 unless config.color
  std::uint64_t file_bytes = 0;             ///< total size of the file
};

/// How save_map spends time; the file is the same format whatever they say
/// (and loads back to the same map).
struct MapSaveOptions {
  /// Threads saving may use; 0: all cores; at most max_threads(). With 1 the
  /// calling thread walks the tree and compresses; with 2 or more zstd
  /// compresses on the other threads while the calling thread walks, so the
  /// two overlap (the 3DTK map at 5 cm: 27 ms instead of 42, the same CPU
  /// time, 0.002% more bytes, since each 1 MiB job is compressed apart).
  /// That needs a free core: when none is, 1 is ~10 ms quicker. A libzstd
  /// built without threads compresses on the calling thread.
  unsigned threads = 0;

  /// Throws std::invalid_argument naming the field (threads above max_threads()).
  void validate() const;
};

/// Writes `map` to `path` atomically: a temporary file in the same folder is
/// written, flushed to disk and renamed over `path`, so `path` holds either
/// the old contents or the complete new map, never a partial file.
void save_map(const OccupancyMap& map, const std::filesystem::path& path, const MapSaveOptions& options = {});

/// Reads and fully validates a map file (checksums first, then every field,
/// node and value); throws FormatError saying what is wrong and where.
/// Before allocating, the header's node counts give what the map will take
/// (the file, and 68 bytes per node with children, 32 at the finest depth,
/// 32 more with color); above memory_limit() it throws MemoryLimitError
/// naming the file, that need and the limit (umbra/core/memory_limit.hpp).
[[nodiscard]] OccupancyMap load_map(const std::filesystem::path& path);

/// Reads and validates the header only (its own checksum, every field, the
/// declared sizes against the file size); the body is neither read nor
/// decompressed, so a corrupt body is only detected by load_map.
[[nodiscard]] MapFileInfo read_map_info(const std::filesystem::path& path);

// ---------------------------------------------------------------------------
// TEST-ONLY. Not part of the API; do not use outside tests.
namespace detail {
/// Installs a hook that every file save (.umb, .bt, .ot, .png) calls after
/// the first part (the header; a PNG is one part) has been written to the
/// temporary file and before the rest; if the hook throws, the save removes
/// the temporary file and rethrows, exactly as for a real write error. An
/// empty function removes the hook. Not thread safe: install it only while
/// no save is running.
void set_map_file_fault_for_testing(std::function<void()> hook);
}  // namespace detail
// ---------------------------------------------------------------------------

}  // namespace umbra
