// The ROS 1 wire format of the two messages umbra reads from bags, parsed
// without ROS: sensor_msgs/PointCloud2 and tf2_msgs/TFMessage (tf/tfMessage
// has the same layout and md5sum).
//
// ROS 1 serialization: fields in declaration order, little-endian, no
// padding; a string or variable-length array is a u32 count followed by its
// elements; time is two u32 (sec, nsec). Every count is checked against the
// bytes left before anything is allocated or read, and the message must use
// its bytes exactly: a count past the end, or bytes left over at the end, is
// a FormatError "NAME: byte K of the N-byte message: what".
//
// The cloud's layout itself (fields within point_step, rows within data) is
// checked by decode_point_cloud2, before any point is read.
//
// Cost: one pass over the message; the cloud's point data is not copied (the
// view borrows it).
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "umbra_ros/point_cloud2.hpp"

namespace umbra::ros_io {

/// md5sums of the message definitions umbra reads (a connection with another md5sum carries another
/// version of the message, which these parsers would misread).
inline constexpr const char* kPointCloud2Md5 = "1158d486dd51d683ce2f1be655c3c181";
inline constexpr const char* kTfMessageMd5 = "94810edda583a504dfda3829e70d7eec";

/// std_msgs/Header.
struct MessageHeader {
  std::uint32_t seq = 0;
  std::uint32_t stamp_sec = 0;
  std::uint32_t stamp_nsec = 0;
  std::string frame_id;
};

/// A sensor_msgs/PointCloud2; cloud.data borrows the message's bytes.
struct SerializedCloud {
  MessageHeader header;
  PointCloud2View cloud;
};

/// One geometry_msgs/TransformStamped.
struct SerializedTransform {
  MessageHeader header;
  std::string child_frame_id;
  std::array<double, 3> translation{};
  std::array<double, 4> rotation{};  ///< x, y, z, w
};

/// Parses a serialized sensor_msgs/PointCloud2; `name` says which message, for errors.
SerializedCloud parse_point_cloud2(std::span<const std::uint8_t> bytes, const std::string& name);

/// Parses a serialized tf2_msgs/TFMessage.
std::vector<SerializedTransform> parse_tf_message(std::span<const std::uint8_t> bytes, const std::string& name);

}  // namespace umbra::ros_io
