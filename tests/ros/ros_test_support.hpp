// Helpers of the ROS tests: scans of umbra's simulated office (and of the
// shared 3DTK scans) as the PointCloud2 messages and transforms a robot
// would publish, and the reference map built from the same points with the
// library directly.
//
// A scan's points are the simulator's (map frame, float). The message holds
// them in the sensor frame, p_s = R^T (p - t) in double stored as FLOAT64,
// with the transform map -> sensor (t = the sensor position, R a yaw, and a
// tilt when asked for); moving them back, R p_s + t in double, then rounding
// to float, gives the very same floats (the error, ~1e-15 m, is far below
// half a float step, except at coordinates within ~1e-8 of 0: see
// office_scans), so maps made through ROS can be compared bit for bit with
// maps made from the original points.
#pragma once

#include <geometry_msgs/TransformStamped.h>
#include <sensor_msgs/PointCloud2.h>

#include <string>
#include <vector>

#include "umbra/io/octomap_files.hpp"
#include "umbra/map/occupancy_map.hpp"

namespace umbra::test {

struct RosScan {
  Vec3d position;           ///< sensor origin, map frame
  double yaw = 0.0;         ///< radians about z
  double tilt = 0.0;        ///< radians about the sensor's x axis, after the yaw
  std::vector<Vec3f> points;  ///< map frame
};

/// `count` scans of the simulated office along its demo path, shifted by a few cm (see the .cpp), with a yaw
/// and tilt of their own.
std::vector<RosScan> office_scans(int count);

/// Scans of a file umbra reads (e.g. ../shared/data/3dtk/3dtk_registered.graph), sensor frames unrotated.
std::vector<RosScan> file_scans(const std::string& path);

/// The cloud of `scan` in `sensor_frame`: FLOAT64 x y z, a FLOAT32 intensity,
/// padding, organised in rows of `row_width` points with a last row of NaN points.
sensor_msgs::PointCloud2 to_cloud(const RosScan& scan, const std::string& sensor_frame, const ros::Time& stamp,
                                  std::uint32_t row_width = 64);

/// map_frame -> sensor_frame at `stamp`.
geometry_msgs::TransformStamped to_transform(const RosScan& scan, const std::string& map_frame,
                                             const std::string& sensor_frame, const ros::Time& stamp);

/// The map umbra's library builds from the scans' points directly (16 levels, `sensor`, simple integrator).
OccupancyMap reference_map(const std::vector<RosScan>& scans, double resolution, const SensorModel& sensor = {});

/// Tree data of a map, for bit-for-bit comparisons.
std::vector<std::uint8_t> tree_bytes(const OccupancyMap& map, OctoMapFormat format);

}  // namespace umbra::test
