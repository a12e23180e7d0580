// Internals of the OctoMap file readers and writers (octomap_files.hpp):
// the byte input both readers stream from, the text header, the per-format
// tree codecs, and message helpers. Private to umbra_io.
//
// Cost model: ByteInput serves bytes from memory or from a file through a
// 1 MiB buffer (one pread per MiB); get() and read() are inline and only
// call out of line to refill. The header parser looks at each header byte
// once and keeps at most 64 bytes of any token.
#pragma once

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "umbra/io/octomap_files.hpp"

namespace umbra::octomap_io {

/// Sequential bytes from memory or from a file; offset() is the position of the next byte.
class ByteInput {
 public:
  /// Bytes in memory; they must outlive the input.
  explicit ByteInput(std::span<const std::uint8_t> bytes);
  /// A regular file. Throws std::runtime_error naming the path when it cannot be opened or read.
  explicit ByteInput(const std::filesystem::path& path);
  /// A second, independent input over the same bytes (the same open file) from `offset` on.
  ByteInput(const ByteInput& source, std::uint64_t offset);
  ByteInput(const ByteInput&) = delete;
  ByteInput& operator=(const ByteInput&) = delete;
  ~ByteInput();

  /// Total bytes (the file's size when it was opened).
  [[nodiscard]] std::uint64_t size() const { return size_; }
  [[nodiscard]] std::uint64_t offset() const { return window_offset_ + pos_; }
  [[nodiscard]] std::uint64_t remaining() const { return size_ > offset() ? size_ - offset() : 0; }

  /// The next byte, or -1 at the end.
  int get() {
    if (pos_ == end_ && !refill()) return -1;
    return data_[pos_++];
  }
  /// The next byte without consuming it, or -1 at the end.
  int peek() {
    if (pos_ == end_ && !refill()) return -1;
    return data_[pos_];
  }
  /// The next `n` bytes into `out`; false when fewer remain (then the input is at its end).
  bool read(std::uint8_t* out, std::size_t n) {
    if (end_ - pos_ >= n) {
      std::memcpy(out, data_ + pos_, n);
      pos_ += n;
      return true;
    }
    return read_slow(out, n);
  }

 private:
  bool refill();
  bool read_slow(std::uint8_t* out, std::size_t n);

  const std::uint8_t* data_ = nullptr;
  std::size_t pos_ = 0;
  std::size_t end_ = 0;
  std::uint64_t window_offset_ = 0;  // file offset of data_[0]
  std::uint64_t size_ = 0;
  int fd_ = -1;  // -1: memory
  std::filesystem::path path_;
  std::vector<std::uint8_t> buffer_;
};

/// The header, plus where its fields were (for messages).
struct Header : OctoMapFileInfo {
  std::uint64_t size_line = 0;
};

inline constexpr std::string_view kBtFirstLine = "# Octomap OcTree binary file";
inline constexpr std::string_view kOtFirstLine = "# Octomap OcTree file";

/// Parses the header up to and including the line that holds `data`;
/// `in` is then at the first byte of the tree. Throws FormatError with a line number.
Header parse_header(ByteInput& in, const std::string& name);

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
/// node with children (`parents`), 68 bytes each, 32 more with colour.
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
OccupancyMap decode_bt(ByteInput& in, const Header& header, const std::string& name, const SensorModel& sensor);
OccupancyMap decode_ot(ByteInput& in, const Header& header, const std::string& name, const SensorModel& sensor);

struct EncodedTree {
  std::vector<std::uint8_t> bytes;
  std::uint64_t nodes = 0;
};
EncodedTree encode_bt(const OccupancyMap& map);
EncodedTree encode_ot(const OccupancyMap& map);

/// Throws std::invalid_argument unless the map is 16 levels deep.
void require_octomap_depth(const OccupancyMap& map, const std::string& what);

/// "the node at OctoMap depth D (first voxel key (x, y, z))" for a node at umbra depth `depth`.
std::string node_text(int depth, std::uint64_t code);

/// Quoted, with anything not printable ASCII as \xNN, cut after `limit` bytes.
std::string quote_text(std::string_view text, std::size_t limit = 64);

/// A float with enough digits to tell it apart, and its bits.
std::string float_text(float value);

/// The map a decoder fills: resolution from the header, 16 levels, the sensor model, colour if asked.
OccupancyMap new_map(const Header& header, const std::string& name, const SensorModel& sensor, bool color);

}  // namespace umbra::octomap_io
