// OctoMap's map files: read .bt and .ot into an OccupancyMap, write them back.
//
// Two formats, both a text header ("# Octomap OcTree binary file" or
// "# Octomap OcTree file", then `id`, `size`, `res`, `data` lines) followed
// by the tree in depth-first order (docs/octomap-files.md has the details):
//   .bt  maximum likelihood: 2 bits per child (absent, free, occupied, has
//        children), written after converting every leaf to free/occupied
//        and merging equal siblings, exactly as liboctomap's writeBinary.
//        Reading gives every free leaf the clamping minimum and every
//        occupied leaf the clamping maximum, as liboctomap does.
//   .ot  full: every node's float log-odds (+ 3 color bytes in a
//        ColorOcTree) and an 8-bit child mask. Ids read: OcTree,
//        OcTreeStamped (same layout: liboctomap 1.9.7 stores no timestamp),
//        ColorOcTree and the legacy id "1" (= OcTree); anything else, e.g. a
//        CountingOcTree (liboctomap registers it as "OcTreeBase"), is refused
//        with a message naming the id. Written: OcTree, or ColorOcTree when
//        the map has color.
//
// How umbra's maps and OctoMap's trees correspond (both are 16 levels deep;
// other depth levels are refused on writing because OctoMap fixes 16 and
// its keys would not match): an OctoMap node with children is an umbra node
// with children; a child OctoMap does not have is an umbra child with
// log-odds exactly 0, i.e. unknown. Writing, an umbra node whose whole
// subtree is exactly 0 is left out; inner values are the maximum over the
// children OctoMap has (not umbra's maximum over all eight), inner colors
// OctoMap's truncating average of its children whose color is set. In a
// ColorOcTree white (255,255,255) means "no color" both ways, so an umbra
// voxel colored pure white reads back uncolored; color weights read back
// as 1. A loaded file is exact: leaves, float bits and colors as in the file
// (inner values and colors are recomputed by umbra's rules). If the file
// holds eight equal childless siblings that OctoMap did not merge, the map
// comes back with auto-pruning off so that it is written back unchanged.
//
// Tree data (encode_octomap_tree / decode_octomap_tree): the same trees
// without the text header, as liboctomap's writeBinaryData / writeData give
// them and as ROS's octomap_msgs/Octomap carries them in `data`.
//
// Sensor model: OctoMap files store only `res` and `size`. A loaded map has
// OctoMap's defaults (hit 0.7, miss 0.4, clamping 0.1192..0.971, thresholds
// 0.5) or the SensorModel passed in; .bt leaves take that model's clamping
// values. If an .ot file holds log-odds outside the clamping range (a tree
// made with other clamping) the loaded map's clamping range is widened just
// enough to hold them, so no value is changed.
//
// Resolution text: written as liboctomap writes it (6 significant digits)
// when that reads back as the same double, otherwise with the shortest text
// that does (liboctomap reads both), so no resolution is rounded.
//
// Cost model: reading streams the file through a 1 MiB buffer and builds
// the tree in one depth-first pass (recursion at most 17 deep); nothing is
// allocated from the header's `size` — it is checked against the file
// length first and against the nodes found at the end. Writing makes one
// depth-first pass and holds the encoded file in memory (2 bytes per node
// with children for .bt; 5 bytes per node for .ot, 8 with color) before
// writing it to a temporary file that is flushed and renamed over the
// target, so an existing file is never left half-written.
//
// Errors: a malformed file throws FormatError naming the file and the
// header line or byte offset; I/O failures std::runtime_error; writing a
// map that is not 16 levels deep std::invalid_argument (before any file is
// created). Thread safety: independent calls may run concurrently.
#pragma once

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

#include "umbra/core/log_odds.hpp"
#include "umbra/io/format_error.hpp"
#include "umbra/map/occupancy_map.hpp"

namespace umbra {

/// The depth every OctoMap tree has.
inline constexpr int kOctoMapDepthLevels = 16;

enum class OctoMapFormat : unsigned char {
  bt,  ///< binary, maximum likelihood ("# Octomap OcTree binary file")
  ot,  ///< full, with log-odds (and color) per node ("# Octomap OcTree file")
};

/// "bt" or "ot".
const char* to_string(OctoMapFormat format);

/// What an OctoMap file's header says, validated.
struct OctoMapFileInfo {
  OctoMapFormat format = OctoMapFormat::bt;
  std::string tree_type;        ///< the header's id ("1" is reported as "OcTree")
  bool color = false;           ///< a ColorOcTree .ot: 3 color bytes per node
  double resolution = 0.0;      ///< metres
  std::uint64_t nodes = 0;      ///< the header's `size`: nodes in OctoMap's tree
  std::uint64_t data_offset = 0;  ///< where the tree data begins
  std::uint64_t file_bytes = 0;
};

/// Reads a .bt or an .ot file (told apart by their first line, whatever the
/// extension) into a 16-level map; see the file comment for the sensor model.
[[nodiscard]] OccupancyMap load_octomap(const std::filesystem::path& path, const SensorModel& sensor = {});

/// The same from bytes in memory; `name` is used in error messages.
[[nodiscard]] OccupancyMap decode_octomap(std::span<const std::uint8_t> bytes, const std::string& name = "<memory>",
                                          const SensorModel& sensor = {});

/// Reads and validates the header only (its fields, and `size` against the
/// file length); the tree itself is not read.
[[nodiscard]] OctoMapFileInfo read_octomap_info(const std::filesystem::path& path);

/// The file `save_octomap` would write, in memory. Throws
/// std::invalid_argument unless map.depth_levels() == 16.
[[nodiscard]] std::vector<std::uint8_t> encode_octomap(const OccupancyMap& map, OctoMapFormat format);

/// The tree of an OctoMap file without the file's text header: the bytes
/// liboctomap's writeBinaryData (.bt) or writeData (.ot) write, which is
/// what a ROS octomap_msgs/Octomap message carries in `data` (with `id`,
/// `resolution` and `binary` beside it).
struct OctoMapTreeData {
  OctoMapFormat format = OctoMapFormat::bt;
  std::string id;             ///< the tree type: "OcTree", or "ColorOcTree" for an .ot of a map with color
  double resolution = 0.0;    ///< metres
  std::vector<std::uint8_t> data;
};

/// The tree data encode_octomap would write after its header. Throws
/// std::invalid_argument unless map.depth_levels() == 16.
[[nodiscard]] OctoMapTreeData encode_octomap_tree(const OccupancyMap& map, OctoMapFormat format);

/// Reads tree data without a file header (the node count a file's header
/// would give is taken from the data). `id` is checked as a file's header
/// id is; errors name `name` and the byte offset within `data`.
[[nodiscard]] OccupancyMap decode_octomap_tree(OctoMapFormat format, const std::string& id, double resolution,
                                               std::span<const std::uint8_t> data,
                                               const std::string& name = "<memory>", const SensorModel& sensor = {});

/// Writes `map` as a .bt or .ot file, atomically (temporary file, flushed,
/// renamed over `path`). Throws std::invalid_argument for maps that are not
/// 16 levels deep, before any file is created.
void save_octomap(const OccupancyMap& map, const std::filesystem::path& path, OctoMapFormat format);

}  // namespace umbra
