// ROS messages to umbra scans: a sensor_msgs/PointCloud2 and the transform
// of its frame into the map frame become a Scan (points in the map frame,
// origin = the sensor frame's origin). Shared by umbra_server and the .bag
// source so that both turn the same message into the same scan.
//
// Cost: one pass over the cloud (decode_point_cloud2); the scan's vectors
// keep their capacity between calls.
#pragma once

#include <geometry_msgs/Transform.h>
#include <sensor_msgs/PointCloud2.h>

#include <string>

#include "umbra/io/scan_source.hpp"
#include "umbra_ros/point_cloud2.hpp"

namespace umbra::ros_io {

/// The message's layout; `data` borrows the message's bytes.
PointCloud2View view_of(const sensor_msgs::PointCloud2& cloud);

/// geometry_msgs/Transform as a RigidTransform; throws std::invalid_argument for NaN or a zero quaternion.
RigidTransform to_rigid_transform(const geometry_msgs::Transform& transform);

/// A frame name as tf2 wants it: without a leading '/' (ROS 1 names such as "/map" still appear in old bags
/// and launch files).
std::string tf2_frame(const std::string& frame);

/// Decodes `cloud` into `scan` (points, and colors when `want_colors` and the cloud has rgb) in the map
/// frame. `decoded` is scratch space kept by the caller; returns the number of NaN/infinite points (kept in
/// the scan: the integrator skips and counts them). Errors: FormatError "NAME: what is wrong".
std::size_t cloud_to_scan(const PointCloud2View& cloud, const RigidTransform& sensor_to_map, bool want_colors,
                          DecodedCloud& decoded, Scan& scan, const std::string& name);

/// The same for a message.
std::size_t cloud_to_scan(const sensor_msgs::PointCloud2& cloud, const RigidTransform& sensor_to_map,
                          bool want_colors, DecodedCloud& decoded, Scan& scan, const std::string& name);

}  // namespace umbra::ros_io
