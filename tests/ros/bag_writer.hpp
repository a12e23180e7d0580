// A writer of small ROS bag files (format 2.0) for the tests and the fuzz
// seeds, without ROS: the layout rosbag itself writes (a 4096-byte bag
// header record, chunks each followed by their index data records,
// connection records both inside the chunks and after index_pos, chunk
// infos at the end), chunks uncompressed, bz2 or lz4 (an LZ4 frame, as
// roslz4 writes). It also reports where every record and header field
// landed in the file (WrittenRecord), so that tests can corrupt exactly one
// length or offset; and it serializes the two message types umbra reads.
//
// librosbag reads what this writes, and umbra's reader reads what librosbag
// writes (tests/ros/rosbag_test.cpp checks both), so the two readings of the
// format are tied to an independent implementation.
#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "umbra/core/vec3.hpp"
#include "umbra_ros/point_cloud2.hpp"

namespace umbra::test {

struct TestConnection {
  std::string topic;
  std::string type;    ///< e.g. "sensor_msgs/PointCloud2"
  std::string md5sum;
  std::string definition = "# (definition left out)\n";
};

struct TestMessage {
  std::uint32_t connection = 0;  ///< index into the connections (also its id)
  std::uint32_t sec = 0;
  std::uint32_t nsec = 0;
  std::vector<std::uint8_t> bytes;  ///< the serialized message
};

/// Where a record of the written file is. Offsets are file offsets; records inside a compressed chunk are not
/// listed (their bytes are not in the file as such).
struct WrittenRecord {
  std::uint64_t byte = 0;  ///< the record's header length
  std::uint8_t op = 0;
  std::map<std::string, std::uint64_t> fields;  ///< file offset of each header field's value
  std::uint64_t data_length_byte = 0;
  std::uint64_t data_byte = 0;
  std::uint32_t data_size = 0;
  bool in_chunk = false;  ///< inside an uncompressed chunk
};

struct WrittenBag {
  std::vector<std::uint8_t> bytes;
  std::vector<WrittenRecord> records;  ///< in file order

  /// The records with this op (top level and inside uncompressed chunks).
  [[nodiscard]] std::vector<WrittenRecord> with_op(std::uint8_t op) const;
};

/// Writes a bag: messages in the given order, a chunk closed once it holds `chunk_bytes` or more.
/// `compression`: "none", "bz2" or "lz4".
WrittenBag write_test_bag(const std::vector<TestConnection>& connections, const std::vector<TestMessage>& messages,
                          const std::string& compression, std::size_t chunk_bytes = 1024);

/// A sensor_msgs/PointCloud2 in the ROS 1 wire format.
struct TestCloud {
  std::string frame_id;
  std::uint32_t sec = 0;
  std::uint32_t nsec = 0;
  ros_io::PointCloud2View layout;  ///< height, width, fields, is_bigendian, point_step, row_step, is_dense
  std::vector<std::uint8_t> data;  ///< used instead of layout.data
};
std::vector<std::uint8_t> serialize_cloud(const TestCloud& cloud);

/// An unorganised cloud of FLOAT32 x, y, z and a FLOAT32 rgb (0x00RRGGBB bits), point_step 16.
TestCloud xyz_rgb_cloud(const std::string& frame_id, std::uint32_t sec, const std::vector<Vec3f>& points);

/// One geometry_msgs/TransformStamped of a tf2_msgs/TFMessage.
struct TestTransform {
  std::string parent;
  std::string child;
  std::uint32_t sec = 0;
  std::uint32_t nsec = 0;
  std::array<double, 3> translation{};
  std::array<double, 4> rotation{0, 0, 0, 1};  ///< x, y, z, w
};
std::vector<std::uint8_t> serialize_tf(const std::vector<TestTransform>& transforms);

/// md5sums of the definitions (as in the message headers ROS generates).
inline constexpr const char* kCloudMd5 = "1158d486dd51d683ce2f1be655c3c181";
inline constexpr const char* kTfMd5 = "94810edda583a504dfda3829e70d7eec";
inline constexpr const char* kStringMd5 = "992ce8a1687cec8c8bd883ec73ca41d1";

/// The bag most tests start from: /tf_static (base_link -> lidar), /tf (map -> base_link at 10, 11, 12 s,
/// translations only), clouds on /points in frame lidar at 10, 11, 12 s (three points each), one cloud on
/// /map_points already in frame map, and std_msgs/String messages on /chatter; chunks of about
/// `chunk_bytes`. The points expected in the map frame are in small_bag_points().
WrittenBag small_bag(const std::string& compression, std::size_t chunk_bytes = 512);

/// The scans small_bag's clouds give in frame map, in time order: name suffix ("on /points"), points.
struct ExpectedScan {
  std::string topic;
  std::vector<Vec3f> points;
};
std::vector<ExpectedScan> small_bag_points();

}  // namespace umbra::test
