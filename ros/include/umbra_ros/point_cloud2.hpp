// PointCloud2 decoding: the bytes of a ROS sensor_msgs/PointCloud2 to umbra points, without ROS.
//
// Layout (the message's own fields, mirrored in PointCloud2View): `height`
// rows of `width` points; the point in row r, column c starts at byte
// r * row_step + c * point_step of `data`; each named field lies at its
// `offset` inside the point and holds `count` values of one datatype
// (INT8 = 1 ... FLOAT64 = 8), all little-endian, or all big-endian when
// `is_bigendian`. Bytes no field names (padding) and fields umbra does not
// use (intensity, ring, time, "_" padding fields) are skipped.
//
// What is read: x, y, z as FLOAT32 or FLOAT64 (the first value when count >
// 1); with colors asked for, the field "rgb" or "rgba" as FLOAT32 holding
// the packed bits (as PCL writes it) or UINT32, 0x00RRGGBB (the top byte,
// alpha, is ignored); a cloud without such a field gives no colors.
// Points with a non-finite coordinate (organised clouds mark missing returns
// with NaN, whatever `is_dense` says) are kept, non-finite, and counted: the
// integrator skips and counts them as for every other input. The rigid
// transform `to_map` (sensor frame to map frame, in double) is applied while
// decoding; the sensor origin is its translation.
//
// Errors throw umbra::FormatError naming the cloud (`name`, e.g. "run.bag
// message 12 on /points") and what is wrong: no x/y/z field, x/y/z of
// another datatype, a field that runs past point_step, point_step 0,
// row_step shorter than a row, data shorter than the rows need. Nothing is
// written to the output before the layout is checked. Points that would
// take more than umbra::memory_limit() throw MemoryLimitError "NAME: ...".
//
// Cost: one pass over the points, no allocation beyond growing the output
// vectors (whose capacity is reused from call to call).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "umbra/core/color.hpp"
#include "umbra/core/vec3.hpp"
#include "umbra/io/format_error.hpp"

namespace umbra::ros_io {

/// sensor_msgs/PointField's datatype constants.
enum class PointFieldType : std::uint8_t {
  int8 = 1,
  uint8 = 2,
  int16 = 3,
  uint16 = 4,
  int32 = 5,
  uint32 = 6,
  float32 = 7,
  float64 = 8,
};

/// "FLOAT32", or "unknown datatype 9".
std::string to_string(PointFieldType type);

/// One sensor_msgs/PointField.
struct PointField {
  std::string name;
  std::uint32_t offset = 0;  ///< bytes from the start of the point
  std::uint8_t datatype = 0;  ///< a PointFieldType value (as in the message, may be anything)
  std::uint32_t count = 1;
};

/// A sensor_msgs/PointCloud2 without its header; `data` is borrowed.
struct PointCloud2View {
  std::uint32_t height = 1;
  std::uint32_t width = 0;
  std::vector<PointField> fields;
  bool is_bigendian = false;
  std::uint32_t point_step = 0;
  std::uint32_t row_step = 0;
  std::span<const std::uint8_t> data;
  bool is_dense = false;  ///< not relied upon: every point is checked
};

/// p_map = rotation * p + translation.
struct RigidTransform {
  std::array<std::array<double, 3>, 3> rotation{{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}};
  Vec3d translation{};

  /// From a translation and a quaternion (x, y, z, w as geometry_msgs has
  /// them), normalised here. Throws std::invalid_argument for a non-finite
  /// value or a quaternion of length 0.
  static RigidTransform from_quaternion(Vec3d translation, double qx, double qy, double qz, double qw);

  [[nodiscard]] Vec3d apply(Vec3d p) const {
    return {rotation[0][0] * p.x + rotation[0][1] * p.y + rotation[0][2] * p.z + translation.x,
            rotation[1][0] * p.x + rotation[1][1] * p.y + rotation[1][2] * p.z + translation.y,
            rotation[2][0] * p.x + rotation[2][1] * p.y + rotation[2][2] * p.z + translation.z};
  }
};

struct DecodedCloud {
  std::vector<Vec3f> points;  ///< map frame, one per point of the cloud (row by row)
  std::vector<Rgb> colors;    ///< one per point, or empty (not asked for, or no rgb field)
  std::size_t non_finite = 0;  ///< points with a NaN or infinite coordinate (kept, as NaN)
};

/// Decodes `cloud` into `out` (cleared first). See the file comment.
void decode_point_cloud2(const PointCloud2View& cloud, const RigidTransform& to_map, bool want_colors,
                         DecodedCloud& out, const std::string& name);

}  // namespace umbra::ros_io
