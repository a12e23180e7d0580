// Reader and writer for OctoMap ScanGraph files (.graph).
//
// Layout (little-endian, as OctoMap writes it): uint32 node count; per node a
// uint32 point count, per point an int32 element count (3) and three doubles
// in the sensor frame, the pose as int32 3 + three doubles (translation) and
// int32 4 + four doubles (quaternion w x y z), and a uint32 id; then a uint32
// edge count and per edge two uint32 node ids, a pose (64 bytes, as above)
// and a double weight. Opening the file walks the node headers (seeking over
// the points) to check every count and pose against the file size, so a
// truncated or hostile file fails up front with the byte offset of the bad
// field and never causes an allocation larger than the file. next() then
// reads one node's points by offset in fixed-size chunks (checking each
// point's count prefix), rounds each coordinate to float (as OctoMap does)
// and maps it into the world frame with the node's pose: world point = R p +
// t (R from the normalised quaternion), sensor origin = t. Edges are only
// checked for size. write_scan_graph() produces files in the same layout.
#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>
#include <system_error>
#include <vector>


#include "reader_support.hpp"
#include "umbra/io/file_saving.hpp"
#include "umbra/io/format_error.hpp"
#include "umbra/io/scan_graph.hpp"
#include "umbra/io/scan_source.hpp"

namespace umbra {
namespace {

using detail::InputFile;
using detail::Pose;

constexpr std::uint64_t kCountBytes = 4;                         // uint32 / int32 fields
constexpr std::uint64_t kPointBytes = 4 + 3 * 8;                 // int32 3 + 3 doubles
constexpr std::uint64_t kPoseBytes = (4 + 3 * 8) + (4 + 4 * 8);  // translation + quaternion
constexpr std::uint64_t kNodeTailBytes = kPoseBytes + 4;         // pose + uint32 id
constexpr std::uint64_t kMinNodeBytes = kCountBytes + kNodeTailBytes;
constexpr std::uint64_t kEdgeBytes = 4 + 4 + kPoseBytes + 8;     // ids, pose, weight
constexpr std::uint32_t kPointsPerChunk = 4096;

// --- little-endian encoding, independent of the host byte order ---

std::uint32_t load_u32(const unsigned char* bytes) {
  return static_cast<std::uint32_t>(detail::load_bits(bytes, 4, false));
}

std::int32_t load_i32(const unsigned char* bytes) { return static_cast<std::int32_t>(load_u32(bytes)); }

double load_f64(const unsigned char* bytes) { return std::bit_cast<double>(detail::load_bits(bytes, 8, false)); }

void append_u32(std::vector<unsigned char>& out, std::uint32_t value) {
  for (int i = 0; i < 4; ++i) out.push_back(static_cast<unsigned char>(value >> (8 * i)));
}

void append_i32(std::vector<unsigned char>& out, std::int32_t value) {
  append_u32(out, static_cast<std::uint32_t>(value));
}

void append_f64(std::vector<unsigned char>& out, double value) {
  const auto bits = std::bit_cast<std::uint64_t>(value);
  for (int i = 0; i < 8; ++i) out.push_back(static_cast<unsigned char>(bits >> (8 * i)));
}

/// Where a node's points are, how many there are, and its pose.
struct NodeEntry {
  std::uint64_t header_offset = 0;  // offset of the point count
  std::uint64_t points_offset = 0;  // offset of the first point
  std::uint64_t end_offset = 0;     // offset just past the id
  std::uint32_t point_count = 0;
  std::uint32_t id = 0;
  // The translation is rounded to float (it is the sensor origin); points are
  // transformed in double and rounded once, so an identity rotation gives
  // exactly float(p) + float(t) as OctoMap computes it, and other rotations
  // are at least as accurate as OctoMap's float quaternion products.
  Pose pose;
};

class ScanGraphReader final : public ScanSource {
 public:
  explicit ScanGraphReader(const std::filesystem::path& path)
      : file_(path, "ScanGraph"), display_name_(path.filename().string()) {
    if (detail::has_bz2_suffix(path)) {
      throw FormatError(file_.name(), "compressed ScanGraph files are not supported; decompress it first (bunzip2)");
    }
    index_nodes();
    chunk_.resize(static_cast<std::size_t>(kPointsPerChunk * kPointBytes));
    // The largest scan decides: scans are read one at a time into the same buffers.
    std::size_t largest = 0;
    for (std::size_t index = 1; index < nodes_.size(); ++index) {
      if (nodes_[index].point_count > nodes_[largest].point_count) largest = index;
    }
    if (!nodes_.empty()) {
      detail::require_point_memory(file_.name(),
                                      "reading scan " + std::to_string(largest) + " (" +
                                          std::to_string(nodes_[largest].point_count) + " points)",
                                      nodes_[largest].point_count, false);
    }
  }

  [[nodiscard]] std::vector<Vec3f> origins() const override {
    std::vector<Vec3f> result;
    result.reserve(nodes_.size());
    for (const NodeEntry& node : nodes_) result.push_back(node.pose.translation());
    return result;
  }

  bool next(Scan& scan) override {
    if (next_node_ >= nodes_.size()) {
      consumed_.store(file_.size(), std::memory_order_relaxed);
      return false;
    }
    const NodeEntry& node = nodes_[next_node_];
    scan.origin = node.pose.translation();
    scan.points.clear();
    scan.colors.clear();
    // Safe: the count was checked against the file size when it was opened.
    scan.points.reserve(node.point_count);
    scan.stamp.reset();  // this format carries no times
    scan.name = display_name_ + " scan " + std::to_string(next_node_);
    if (node.id != next_node_) scan.name += " (id " + std::to_string(node.id) + ")";

    std::uint64_t offset = node.points_offset;
    std::uint32_t points_done = 0;
    while (points_done < node.point_count) {
      const std::uint32_t in_chunk = std::min(kPointsPerChunk, node.point_count - points_done);
      const std::uint64_t chunk_bytes = in_chunk * kPointBytes;
      read_exact(offset, chunk_.data(), chunk_bytes,
                 "the points of scan " + std::to_string(next_node_));
      for (std::uint32_t i = 0; i < in_chunk; ++i) {
        const unsigned char* bytes = chunk_.data() + i * kPointBytes;
        const std::int32_t element_count = load_i32(bytes);
        if (element_count != 3) {
          throw FormatError::at_byte(
              file_.name(), offset + i * kPointBytes,
              "scan " + std::to_string(next_node_) + " point " + std::to_string(points_done + i) +
                  ": expected the element count 3 (int32) before its coordinates, found " +
                  std::to_string(element_count));
        }
        // Round each coordinate to float first, as OctoMap's reader does.
        const Vec3f sensor_point{static_cast<float>(load_f64(bytes + 4)),
                                 static_cast<float>(load_f64(bytes + 12)),
                                 static_cast<float>(load_f64(bytes + 20))};
        scan.points.push_back(node.pose.apply(sensor_point));
      }
      offset += chunk_bytes;
      points_done += in_chunk;
      consumed_.store(offset, std::memory_order_relaxed);
    }
    consumed_.store(node.end_offset, std::memory_order_relaxed);
    ++next_node_;
    return true;
  }

  [[nodiscard]] std::size_t scan_count() const override { return nodes_.size(); }

  [[nodiscard]] double progress() const override {
    if (file_.size() == 0) return 1.0;
    return static_cast<double>(consumed_.load(std::memory_order_relaxed)) /
           static_cast<double>(file_.size());
  }

 private:
  /// Reads `size` bytes at `offset`; a file too short for them is a FormatError
  /// naming `what` was expected there.
  void read_exact(std::uint64_t offset, unsigned char* out, std::uint64_t size, const std::string& what) {
    const std::uint64_t available = offset < file_.size() ? file_.size() - offset : 0;
    if (size > available) {
      throw FormatError::at_byte(file_.name(), offset,
                                 "truncated file: expected " + what + " (" + std::to_string(size) +
                                     " bytes), but only " + std::to_string(available) +
                                     " bytes remain");
    }
    const std::size_t got = file_.read_at(offset, out, static_cast<std::size_t>(size));
    if (got != size) {
      // The file shrank after it was opened.
      throw FormatError::at_byte(file_.name(), offset + got,
                                 "truncated file: expected " + what + ", but the file ends here");
    }
  }

  /// Walks every node header and the edge count, validating the structure
  /// against the file size; fills nodes_.
  void index_nodes() {
    std::array<unsigned char, kNodeTailBytes> buffer{};
    read_exact(0, buffer.data(), kCountBytes, "the scan count (uint32)");
    const std::uint32_t node_count = load_u32(buffer.data());
    const std::uint64_t minimum_size = kCountBytes + node_count * kMinNodeBytes + kCountBytes;
    if (minimum_size > file_.size()) {
      std::string message = "the file declares " + std::to_string(node_count) +
                            " scans, which need at least " + std::to_string(minimum_size) +
                            " bytes, but the file has only " + std::to_string(file_.size()) + " bytes";
      if (std::memcmp(buffer.data(), "BZh", 3) == 0) {
        message += "; it looks bz2-compressed: decompress it first (bunzip2)";
      }
      throw FormatError::at_byte(file_.name(), 0, message);
    }
    nodes_.reserve(node_count);

    std::uint64_t offset = kCountBytes;
    for (std::uint32_t index = 0; index < node_count; ++index) {
      const std::string scan_label = "scan " + std::to_string(index);
      NodeEntry node;
      node.header_offset = offset;
      read_exact(offset, buffer.data(), kCountBytes, "the point count (uint32) of " + scan_label);
      node.point_count = load_u32(buffer.data());
      node.points_offset = offset + kCountBytes;
      const std::uint64_t points_bytes = node.point_count * kPointBytes;
      const std::uint64_t remaining = file_.size() - node.points_offset;
      if (points_bytes + kNodeTailBytes > remaining) {
        throw FormatError::at_byte(
            file_.name(), offset,
            scan_label + " declares " + std::to_string(node.point_count) + " points, which need " +
                std::to_string(points_bytes) + " bytes plus " + std::to_string(kNodeTailBytes) +
                " for its pose and id, but only " + std::to_string(remaining) +
                " bytes remain in the file (truncated file or corrupt point count)");
      }
      const std::uint64_t pose_offset = node.points_offset + points_bytes;
      read_exact(pose_offset, buffer.data(), kNodeTailBytes, "the pose and id of " + scan_label);
      node.pose = parse_pose(buffer.data(), pose_offset, scan_label);
      node.id = load_u32(buffer.data() + kPoseBytes);
      node.end_offset = pose_offset + kNodeTailBytes;
      offset = node.end_offset;
      nodes_.push_back(node);
    }

    read_exact(offset, buffer.data(), kCountBytes, "the edge count (uint32) after the last scan");
    const std::uint32_t edge_count = load_u32(buffer.data());
    const std::uint64_t edge_bytes = edge_count * kEdgeBytes;
    const std::uint64_t after_count = file_.size() - offset - kCountBytes;
    if (edge_bytes != after_count) {
      throw FormatError::at_byte(
          file_.name(), offset,
          "the file declares " + std::to_string(edge_count) + " edges, which need " +
              std::to_string(edge_bytes) + " bytes after the edge count, but " +
              std::to_string(after_count) + " bytes follow" +
              (edge_bytes > after_count ? " (truncated file)" : " (unexpected trailing data)"));
    }
  }

  /// Checks and converts a pose (translation, quaternion) starting at `offset`.
  Pose parse_pose(const unsigned char* bytes, std::uint64_t offset, const std::string& scan_label) const {
    const std::int32_t translation_count = load_i32(bytes);
    if (translation_count != 3) {
      throw FormatError::at_byte(file_.name(), offset,
                                 scan_label + " pose: expected the translation's element count 3 (int32), found " +
                                     std::to_string(translation_count));
    }
    const std::uint64_t quaternion_offset = offset + 4 + 3 * 8;
    const std::int32_t quaternion_count = load_i32(bytes + 4 + 3 * 8);
    if (quaternion_count != 4) {
      throw FormatError::at_byte(file_.name(), quaternion_offset,
                                 scan_label + " pose: expected the quaternion's element count 4 (int32), found " +
                                     std::to_string(quaternion_count));
    }

    static constexpr std::array<const char*, 3> kAxisNames{"x", "y", "z"};
    std::array<double, 3> translation{};
    for (std::size_t axis = 0; axis < 3; ++axis) {
      const std::uint64_t value_offset = offset + 4 + axis * 8;
      const double value = load_f64(bytes + 4 + axis * 8);
      const auto rounded = static_cast<float>(value);
      if (!std::isfinite(value) || !std::isfinite(rounded)) {
        throw FormatError::at_byte(file_.name(), value_offset,
                                   scan_label + " pose: translation " + kAxisNames[axis] + " is " +
                                       std::to_string(value) + ", not a finite float");
      }
      translation[axis] = rounded;
    }

    static constexpr std::array<const char*, 4> kQuaternionNames{"w", "x", "y", "z"};
    std::array<double, 4> q{};
    for (std::size_t i = 0; i < 4; ++i) {
      q[i] = load_f64(bytes + 4 + 3 * 8 + 4 + i * 8);
      if (!std::isfinite(q[i])) {
        throw FormatError::at_byte(file_.name(), quaternion_offset + 4 + i * 8,
                                   scan_label + " pose: quaternion " + kQuaternionNames[i] + " is " +
                                       std::to_string(q[i]) + ", not finite");
      }
    }
    try {
      return Pose::from_translation_quaternion(translation[0], translation[1], translation[2], q[0], q[1], q[2],
                                               q[3]);
    } catch (const std::invalid_argument& error) {  // all finite (checked above): a zero quaternion
      throw FormatError::at_byte(file_.name(), quaternion_offset, scan_label + " pose: " + error.what());
    }
  }

  InputFile file_;
  std::string display_name_;  // file name only, for Scan::name
  std::vector<NodeEntry> nodes_;
  std::size_t next_node_ = 0;
  std::vector<unsigned char> chunk_;
  std::atomic<std::uint64_t> consumed_{0};
};

}  // namespace

std::unique_ptr<ScanSource> open_scan_graph(const std::filesystem::path& path) {
  detail::reject_directory(path);  // before opening, so an unreadable folder is named as a folder
  return detail::naming_bad_alloc(path, [&] { return std::make_unique<ScanGraphReader>(path); });
}

void write_scan_graph(const std::filesystem::path& path, const std::vector<Scan>& scans) {
  if (scans.size() > std::numeric_limits<std::uint32_t>::max()) {
    throw std::invalid_argument("write_scan_graph: too many scans for a ScanGraph (" +
                                std::to_string(scans.size()) + ")");
  }
  for (std::size_t index = 0; index < scans.size(); ++index) {
    if (!scans[index].origin.is_finite()) {
      throw std::invalid_argument("write_scan_graph: scan " + std::to_string(index) +
                                  " has a non-finite origin");
    }
    if (scans[index].points.size() > std::numeric_limits<std::uint32_t>::max()) {
      throw std::invalid_argument("write_scan_graph: scan " + std::to_string(index) + " has " +
                                  std::to_string(scans[index].points.size()) +
                                  " points, more than a ScanGraph can hold");
    }
  }

  // Streamed in 1 MiB pieces through one atomic save (umbra/io/file_saving.hpp).
  AtomicFileWriter out(path, "ScanGraph");
  std::vector<unsigned char> buffer;
  constexpr std::size_t kFlushBytes = 1 << 20;
  buffer.reserve(kFlushBytes + kPointBytes + kNodeTailBytes + 16);
  const auto flush = [&] {
    out.write(buffer);
    buffer.clear();
  };

  append_u32(buffer, static_cast<std::uint32_t>(scans.size()));
  for (std::size_t index = 0; index < scans.size(); ++index) {
    const Scan& scan = scans[index];
    append_u32(buffer, static_cast<std::uint32_t>(scan.points.size()));
    for (const Vec3f& point : scan.points) {
      append_i32(buffer, 3);
      for (std::size_t axis = 0; axis < 3; ++axis) {
        append_f64(buffer, static_cast<double>(point[axis]) - static_cast<double>(scan.origin[axis]));
      }
      if (buffer.size() >= kFlushBytes) flush();
    }
    append_i32(buffer, 3);
    for (std::size_t axis = 0; axis < 3; ++axis) append_f64(buffer, scan.origin[axis]);
    append_i32(buffer, 4);
    for (const double element : {1.0, 0.0, 0.0, 0.0}) append_f64(buffer, element);
    append_u32(buffer, static_cast<std::uint32_t>(index));
  }
  append_u32(buffer, 0);  // no edges
  flush();

  out.commit();
}

}  // namespace umbra
