// Internals of the OctoMap file readers and writers (octomap_files.hpp):
// the text header, the per-format tree codecs and the node names of their
// messages. Both readers stream from common/byte_input.hpp's ByteReader and
// quote with common/message_text.hpp. Private to umbra_io.
//
// Cost model: see byte_input.hpp for the reading; the header parser looks at each header byte
// once and keeps at most 64 bytes of any token.
#pragma once

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "byte_input.hpp"
#include "message_text.hpp"
#include "umbra/io/octomap_files.hpp"

namespace umbra::detail {

using detail::float_text;
using detail::quote_bytes;

/// The byte input both readers stream from (a file or bytes in memory).
using detail::ByteReader;
using detail::InputFile;

/// The header, plus where its fields were (for messages).
struct Header : OctoMapFileInfo {
  std::uint64_t size_line = 0;
};

inline constexpr std::string_view kBtFirstLine = "# Octomap OcTree binary file";
inline constexpr std::string_view kOtFirstLine = "# Octomap OcTree file";

/// Parses the header up to and including the line that holds `data`;
/// `in` is then at the first byte of the tree. Throws FormatError with a line number.
Header parse_header(ByteReader& in, const std::string& name);

/// Why `id` is not a tree type umbra reads (a message), or empty when it is one.
std::string unreadable_tree_type(const std::string& id);

/// The number of nodes in tree data without a file header (what a header's
/// `size` would say): .ot from its length, .bt from its child codes. Throws
/// FormatError when the length cannot be whole nodes.
std::uint64_t count_tree_nodes(const Header& header, std::span<const std::uint8_t> data, const std::string& name);

/// Throws FormatError (at the size line) unless the header's `size` is
/// possible for the number of bytes after the header; nothing is read.
void check_declared_size(const Header& header, const std::string& name);

/// Throws MemoryLimitError (umbra/core/memory_limit.hpp) when building the
/// tree needs more than the memory limit: one group of eight children per
/// node with children (`parents`), 68 bytes each, 32 more with color.
void require_tree_memory(const Header& header, const std::string& name, std::uint64_t parents);
/// What require_tree_memory compares with the limit.
std::uint64_t tree_bytes(const Header& header, std::uint64_t parents);

/// The header liboctomap writes: first line, the comment lines, id, size, res, data.
std::string header_text(OctoMapFormat format, std::string_view id, std::uint64_t size, double resolution);

/// The resolution as liboctomap prints it (6 significant digits) when that
/// reads back as the same double, else the shortest text that does.
std::string resolution_text(double resolution);

/// Trees in the two formats. The decoders read from `in` (positioned at the
/// data) into a new map; the encoders return the tree bytes and its node count.
OccupancyMap decode_bt(ByteReader& in, const Header& header, const std::string& name, const SensorModel& sensor);
OccupancyMap decode_ot(ByteReader& in, const Header& header, const std::string& name, const SensorModel& sensor);

struct EncodedTree {
  std::vector<std::uint8_t> bytes;
  std::uint64_t nodes = 0;
};
EncodedTree encode_bt(const OccupancyMap& map);
EncodedTree encode_ot(const OccupancyMap& map);

/// Throws std::invalid_argument unless the map is 16 levels deep.
void require_octomap_depth(const OccupancyMap& map, const std::string& what);

/// "the node at OctoMap depth D, key (x, y, z)" for a node at umbra depth
/// `depth` (OctoMap counts depths from the root down, umbra from the leaves up).
inline std::string octomap_node(int depth, std::uint64_t code) {
  return "the " + detail::node_text("OctoMap depth", kOctoMapDepthLevels - depth, code);
}

/// The map a decoder fills: resolution from the header, 16 levels, the sensor model, color if asked.
OccupancyMap new_map(const Header& header, const std::string& name, const SensorModel& sensor, bool color);

}  // namespace umbra::detail
