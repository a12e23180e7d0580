// Helpers of the ROS tests: see ros_test_support.hpp.
#include "ros_test_support.hpp"

#include <cmath>
#include <cstring>
#include <limits>

#include "umbra/io/scan_source.hpp"
#include "umbra/sim/lidar.hpp"
#include "umbra/sim/scene.hpp"

namespace umbra::test {
namespace {

using Matrix = std::array<std::array<double, 3>, 3>;

/// R = Rz(yaw) * Rx(tilt): the sensor's axes in the map frame.
Matrix rotation(const RosScan& scan) {
  const double cy = std::cos(scan.yaw);
  const double sy = std::sin(scan.yaw);
  const double ct = std::cos(scan.tilt);
  const double st = std::sin(scan.tilt);
  return {{{cy, -sy * ct, sy * st}, {sy, cy * ct, -cy * st}, {0.0, st, ct}}};
}

void put_double(std::uint8_t* at, double value) { std::memcpy(at, &value, 8); }

}  // namespace

std::vector<RosScan> office_scans(int count) {
  const sim::Scene scene = sim::make_demo_scene();
  const std::vector<sim::SensorPose> path = sim::demo_path();
  sim::LidarModel lidar;
  lidar.rings = 16;
  lidar.azimuth_steps = 360;
  lidar.max_range = 15.0;
  // The office's floor lies at z = 0 and its walls at whole metres: shifted so that no coordinate is 0, where the
  // round trip through the sensor frame would leave +-1e-16 instead of 0 (another voxel).
  const Vec3f shift{0.37f, -0.21f, 0.13f};
  std::vector<RosScan> scans;
  for (int i = 0; i < count && i < static_cast<int>(path.size()); ++i) {
    const sim::SensorPose& pose = path[static_cast<std::size_t>(i)];
    RosScan scan;
    scan.position = pose.position + Vec3d(shift);
    scan.yaw = pose.yaw + 0.1 * i;
    scan.tilt = 0.05 * (i % 3);
    scan.points = sim::simulate_scan(scene, pose, lidar);
    for (Vec3f& p : scan.points) p = p + shift;
    scans.push_back(std::move(scan));
  }
  return scans;
}

std::vector<RosScan> file_scans(const std::string& path) {
  std::vector<RosScan> scans;
  const auto source = open_scan_source(path);
  Scan scan;
  while (source->next(scan)) {
    RosScan ros_scan;
    ros_scan.position = Vec3d(scan.origin);
    // No rotation: then p - t and back are exact in double even for coordinates at or near 0 (real data
    // cannot be shifted: it is compared with `umbra build` on the file itself).
    ros_scan.points = scan.points;
    scans.push_back(std::move(ros_scan));
  }
  return scans;
}

sensor_msgs::PointCloud2 to_cloud(const RosScan& scan, const std::string& sensor_frame, const ros::Time& stamp,
                                  std::uint32_t row_width) {
  sensor_msgs::PointCloud2 cloud;
  cloud.header.frame_id = sensor_frame;
  cloud.header.stamp = stamp;
  const char* names[4] = {"x", "y", "z", "intensity"};
  const std::uint32_t offsets[4] = {0, 8, 16, 28};  // bytes 24..27 and 32..35: padding
  for (int i = 0; i < 4; ++i) {
    sensor_msgs::PointField field;
    field.name = names[i];
    field.offset = offsets[i];
    field.datatype = i < 3 ? sensor_msgs::PointField::FLOAT64 : sensor_msgs::PointField::FLOAT32;
    field.count = 1;
    cloud.fields.push_back(field);
  }
  cloud.point_step = 36;
  cloud.width = row_width;
  const std::size_t rows = (scan.points.size() + row_width - 1) / row_width + 1;  // + a row of NaN
  cloud.height = static_cast<std::uint32_t>(rows);
  cloud.row_step = cloud.width * cloud.point_step;
  cloud.is_bigendian = false;
  cloud.is_dense = false;
  cloud.data.assign(rows * cloud.row_step, 0);
  const Matrix r = rotation(scan);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (std::size_t i = 0; i < rows * row_width; ++i) {
    double s[3] = {nan, nan, nan};
    if (i < scan.points.size()) {
      const double d[3] = {scan.points[i].x - scan.position.x, scan.points[i].y - scan.position.y,
                           scan.points[i].z - scan.position.z};
      for (std::size_t a = 0; a < 3; ++a) s[a] = r[0][a] * d[0] + r[1][a] * d[1] + r[2][a] * d[2];  // R^T d
    }
    std::uint8_t* point = cloud.data.data() + i * cloud.point_step;
    for (int a = 0; a < 3; ++a) put_double(point + 8 * a, s[a]);
  }
  return cloud;
}

geometry_msgs::TransformStamped to_transform(const RosScan& scan, const std::string& map_frame,
                                             const std::string& sensor_frame, const ros::Time& stamp) {
  geometry_msgs::TransformStamped t;
  t.header.frame_id = map_frame;
  t.header.stamp = stamp;
  t.child_frame_id = sensor_frame;
  t.transform.translation.x = scan.position.x;
  t.transform.translation.y = scan.position.y;
  t.transform.translation.z = scan.position.z;
  // q = q_z(yaw) * q_x(tilt)
  const double cy = std::cos(scan.yaw / 2);
  const double sy = std::sin(scan.yaw / 2);
  const double ct = std::cos(scan.tilt / 2);
  const double st = std::sin(scan.tilt / 2);
  t.transform.rotation.w = cy * ct;
  t.transform.rotation.x = cy * st;
  t.transform.rotation.y = sy * st;
  t.transform.rotation.z = sy * ct;
  return t;
}

OccupancyMap reference_map(const std::vector<RosScan>& scans, double resolution, const SensorModel& sensor) {
  OccupancyMap map(resolution, kOctoMapDepthLevels, sensor);
  for (const RosScan& scan : scans) map.insert_point_cloud(Vec3f(scan.position), scan.points);
  return map;
}

std::vector<std::uint8_t> tree_bytes(const OccupancyMap& map, OctoMapFormat format) {
  return encode_octomap_tree(map, format).data;
}

}  // namespace umbra::test
