// MapServer: the umbra_server node, a drop-in for octomap_server.
//
// Subscribes to `cloud_in` (sensor_msgs/PointCloud2); a tf2 message filter
// holds each cloud until the transform from its frame to ~frame_id at its
// stamp is known, then the cloud is decoded, moved into the map frame,
// cut to (pointcloud_min_z, pointcloud_max_z) and inserted with umbra's
// integrator from the sensor frame's origin. Clouds that wait for a
// transform more than 5 s, or that the filter drops, are named in a
// warning with the frames tf2 knows (cloud_wait_monitor.hpp). It also subscribes to depth
// images (`depth/image` with `depth/camera_info`, and `rgb/image` with
// ~image_colors: depth_image_input.hpp): each is placed with the transform
// from its frame (the camera's optical frame) to ~frame_id at its stamp and
// inserted as an image (OccupancyMap::insert_depth_image, ~image_integrator).
// After every cloud or image (and after a reset or a box clearing) it
// publishes, with the cloud's or image's stamp:
//   octomap_binary   octomap_msgs/Octomap, .bt tree data (free/occupied)
//   octomap_full     octomap_msgs/Octomap, .ot tree data (log-odds)
//   occupied_cells_vis_array   visualization_msgs/MarkerArray
//   free_cells_vis_array       (with ~publish_free_space)
//   octomap_point_cloud_centers  sensor_msgs/PointCloud2
//   projected_map    nav_msgs/OccupancyGrid: the band between occupancy_min_z
//                    and occupancy_max_z projected to 2D (projected_map.hpp),
//                    the whole band again after every scan
// latched (~latch, default true) or only while someone subscribes.
// Services: octomap_binary and octomap_full (octomap_msgs/GetOctomap),
// ~reset (std_srvs/Empty: forget everything), ~clear_bbx
// (octomap_msgs/BoundingBoxQuery: every known voxel in the box becomes
// free at the clamping minimum; unknown voxels stay unknown),
// ~check_collision (umbra_msgs/CheckCollision), ~merge (umbra_msgs/MergeMap:
// another map added, log-odds summed voxel by voxel). At start-up it logs the
// map frame and the resolved names of its topics and services.
//
// Threads: ROS callbacks run one at a time (ros::spin); each insertion
// uses ~threads cores inside umbra.
//
// Cost per cloud or image: the insertion, then one pass over the map per published
// message kind (as octomap_server; the projected map walks only the nodes in
// its band, and decides whole blocks of cells from coarse nodes). Clearing a box sets each known voxel in
// it that is not already at the clamping minimum, one by one (boxes of more
// than 2^26 such voxels are refused with an error).
#pragma once

#include <message_filters/subscriber.h>
#include <octomap_msgs/BoundingBoxQuery.h>
#include <octomap_msgs/GetOctomap.h>
#include <ros/ros.h>
#include <sensor_msgs/PointCloud2.h>
#include <std_srvs/Empty.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/message_filter.h>
#include <tf2_ros/transform_listener.h>
#include <umbra_msgs/CheckCollision.h>
#include <umbra_msgs/MergeMap.h>

#include <array>
#include <memory>

#include "cloud_wait_monitor.hpp"
#include "depth_image_input.hpp"
#include "image_message.hpp"
#include "projected_map.hpp"
#include "server_settings.hpp"
#include "umbra/io/scan_source.hpp"
#include "umbra/map/occupancy_map.hpp"
#include "umbra_ros/point_cloud2.hpp"

namespace umbra::ros_io {

class MapServer {
 public:
  /// Advertises and subscribes. `map` is the starting map (empty, or loaded from a file).
  MapServer(ros::NodeHandle& node, ros::NodeHandle& private_node, ServerSettings settings, OccupancyMap map);

  /// Publishes the current map (at start-up, for a loaded map).
  void publish_all(const ros::Time& stamp);

 private:
  void insert_cloud(const sensor_msgs::PointCloud2::ConstPtr& cloud);
  /// Logs a cloud the tf2 filter dropped (no frame_id, or no transform while 5 newer clouds came).
  void drop_cloud(const sensor_msgs::PointCloud2::ConstPtr& cloud,
                  tf2_ros::filter_failure_reasons::FilterFailureReason reason);
  /// The start-up lines: map frame, resolution, integrator, topics and services by their resolved names.
  void log_start() const;
  void insert_image(const sensor_msgs::Image::ConstPtr& depth, const sensor_msgs::CameraInfo::ConstPtr& info,
                    const sensor_msgs::Image::ConstPtr& color);
  /// Logs a depth image that will not be inserted (no transform, no CameraInfo) and counts it.
  void drop_image(const sensor_msgs::Image::ConstPtr& depth, DepthImageInput::Drop why);
  /// "depth images refused so far: N of M" (malformed or dropped, of those received).
  [[nodiscard]] std::string refused_images_text() const;
  /// Publishes the map after the message `name` (stamp `stamp`) was inserted; errors are logged.
  void publish_after(const std::string& name, const ros::Time& stamp);
  /// `options` with the message's stamp when decay is on (the map's clock), else unchanged.
  [[nodiscard]] InsertOptions stamped(const InsertOptions& options, const ros::Time& stamp) const;
  bool reset(std_srvs::Empty::Request& request, std_srvs::Empty::Response& response);
  bool clear_bbx(octomap_msgs::BoundingBoxQuery::Request& request, octomap_msgs::BoundingBoxQuery::Response& response);
  bool get_binary(octomap_msgs::GetOctomap::Request& request, octomap_msgs::GetOctomap::Response& response);
  bool get_full(octomap_msgs::GetOctomap::Request& request, octomap_msgs::GetOctomap::Response& response);
  [[nodiscard]] bool wanted(const ros::Publisher& publisher) const;

  /// ~check_collision (umbra_msgs/CheckCollision): is a sphere, box, capsule or segment free, unknown
  /// space blocking unless the request says otherwise (the query layer's is_free).
  bool check_collision(umbra_msgs::CheckCollision::Request& request, umbra_msgs::CheckCollision::Response& response);

  /// ~merge (umbra_msgs/MergeMap): adds a received map to the node's (OccupancyMap::merge), then publishes.
  bool merge(umbra_msgs::MergeMap::Request& request, umbra_msgs::MergeMap::Response& response);

  ServerSettings settings_;
  OccupancyMap map_;
  tf2_ros::Buffer tf_buffer_;
  tf2_ros::TransformListener tf_listener_;
  message_filters::Subscriber<sensor_msgs::PointCloud2> cloud_subscriber_;
  tf2_ros::MessageFilter<sensor_msgs::PointCloud2> cloud_filter_;
  CloudWaitMonitor cloud_wait_;
  DepthImageInput image_input_;
  ros::Publisher binary_publisher_;
  ros::Publisher full_publisher_;
  ros::Publisher occupied_publisher_;
  ros::Publisher free_publisher_;
  ros::Publisher centers_publisher_;
  ros::Publisher projected_publisher_;
  ros::ServiceServer binary_service_;
  ros::ServiceServer full_service_;
  ros::ServiceServer reset_service_;
  ros::ServiceServer clear_bbx_service_;
  ros::ServiceServer check_collision_service_;
  ros::ServiceServer merge_service_;
  DecodedCloud decoded_;
  Scan scan_;
  DecodedDepthImage decoded_image_;
  std::vector<Rgb> image_colors_;
  std::size_t images_refused_ = 0;  ///< depth images malformed or dropped since the start
  std::size_t clouds_dropped_ = 0;  ///< clouds the tf2 filter dropped since the start
  std::array<ros::WallTime, 3> last_drop_warning_{};  ///< per DepthImageInput::Drop
};

}  // namespace umbra::ros_io
