// ROS messages to umbra scans: see cloud_message.hpp.
#include "cloud_message.hpp"

#include <stdexcept>
#include <utility>

namespace umbra::ros_io {

PointCloud2View view_of(const sensor_msgs::PointCloud2& cloud) {
  PointCloud2View view;
  view.height = cloud.height;
  view.width = cloud.width;
  view.fields.reserve(cloud.fields.size());
  for (const sensor_msgs::PointField& field : cloud.fields) {
    view.fields.push_back({field.name, field.offset, field.datatype, field.count});
  }
  view.is_bigendian = cloud.is_bigendian != 0;
  view.point_step = cloud.point_step;
  view.row_step = cloud.row_step;
  view.data = std::span<const std::uint8_t>(cloud.data.data(), cloud.data.size());
  view.is_dense = cloud.is_dense != 0;
  return view;
}

RigidTransform to_rigid_transform(const geometry_msgs::Transform& transform) {
  const auto& t = transform.translation;
  const auto& q = transform.rotation;
  return RigidTransform::from_quaternion({t.x, t.y, t.z}, q.x, q.y, q.z, q.w);
}

std::string tf2_frame(const std::string& frame) {
  const std::size_t start = frame.find_first_not_of('/');
  return start == std::string::npos ? std::string() : frame.substr(start);
}

std::size_t cloud_to_scan(const PointCloud2View& cloud, const RigidTransform& sensor_to_map, bool want_colors,
                          DecodedCloud& decoded, Scan& scan, const std::string& name) {
  decode_point_cloud2(cloud, sensor_to_map, want_colors, decoded, name);
  std::swap(scan.points, decoded.points);
  std::swap(scan.colors, decoded.colors);
  const Vec3d origin = sensor_to_map.translation;
  scan.origin = Vec3f(origin);
  scan.name = name;
  return decoded.non_finite;
}

std::size_t cloud_to_scan(const sensor_msgs::PointCloud2& cloud, const RigidTransform& sensor_to_map,
                          bool want_colors, DecodedCloud& decoded, Scan& scan, const std::string& name) {
  return cloud_to_scan(view_of(cloud), sensor_to_map, want_colors, decoded, scan, name);
}

}  // namespace umbra::ros_io
