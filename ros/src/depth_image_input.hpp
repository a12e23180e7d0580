// DepthImageInput: the depth images umbra_server subscribes to, each handed
// on with its CameraInfo (and its color image) once tf2 can place it.
//
// Topics:
//   depth/image        sensor_msgs/Image, 16UC1 or 32FC1 (image_message.hpp)
//   camera_info beside it (depth/camera_info unless depth/image is
//                      remapped): sensor_msgs/CameraInfo; image_transport's
//                      rule, so that remapping the image alone,
//                      depth/image:=/camera/depth/image_rect_raw, finds
//                      /camera/depth/camera_info as depth_image_proc does
//   rgb/image          sensor_msgs/Image, rgb8 / bgr8 (only with colors on)
// A depth image waits in a tf2 message filter (queue of 5, as the clouds)
// until the transform from its frame to the map frame at its stamp is
// known; then it is matched with the CameraInfo of the same stamp
// (message_filters' ExactTime, as image_transport's CameraSubscriber pairs
// them) or, with colors, with the CameraInfo and the color image nearest
// in time (ApproximateTime, as depth_image_proc's point_cloud_xyzrgb pairs
// color and depth: drivers stamp the two streams separately). An image
// tf2 drops (no frame_id, or no transform while 5 newer images came) and an
// image without a CameraInfo of its stamp (dropped by ExactTime once a newer
// image is matched, or 10 newer ones wait) go to the `dropped` callback
// with the reason; when images come but none finds its partners for 10 s, a
// warning names the topics and what arrived on each (image_transport warns
// likewise).
//
// Threads: everything runs in the node's ROS callback thread.
#pragma once

#include <message_filters/subscriber.h>
#include <message_filters/sync_policies/approximate_time.h>
#include <message_filters/sync_policies/exact_time.h>
#include <message_filters/synchronizer.h>
#include <ros/ros.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/message_filter.h>

#include <cstddef>
#include <functional>
#include <memory>
#include <string>

namespace umbra::ros_io {

class DepthImageInput {
 public:
  /// Receives a depth image, its CameraInfo and its color image (null without colors).
  using Callback = std::function<void(const sensor_msgs::Image::ConstPtr& depth,
                                      const sensor_msgs::CameraInfo::ConstPtr& info,
                                      const sensor_msgs::Image::ConstPtr& color)>;

  /// Why a depth image will not be inserted.
  enum class Drop { no_frame_id, no_transform, no_camera_info };
  /// Receives a depth image that will not be inserted, and why.
  using Dropped = std::function<void(const sensor_msgs::Image::ConstPtr& depth, Drop why)>;

  /// Subscribes (rgb/image only when `colors`); `tf` must outlive this.
  DepthImageInput(ros::NodeHandle& node, tf2_ros::Buffer& tf, const std::string& map_frame, bool colors,
                  Callback callback, Dropped dropped);

  /// The reason in words ("tf2 had no transform from its frame to the map frame at its stamp").
  [[nodiscard]] std::string describe(Drop why) const;

  /// The resolved topics, for the start-up line: "'/depth/image' with '/depth/camera_info'" (and the color images').
  [[nodiscard]] std::string topics() const;

  /// Depth images received since the start.
  [[nodiscard]] std::size_t received() const { return received_; }

 private:
  using ExactPair = message_filters::sync_policies::ExactTime<sensor_msgs::Image, sensor_msgs::CameraInfo>;
  using NearestTriple =
      message_filters::sync_policies::ApproximateTime<sensor_msgs::Image, sensor_msgs::CameraInfo, sensor_msgs::Image>;

  void paired(const sensor_msgs::Image::ConstPtr& depth, const sensor_msgs::CameraInfo::ConstPtr& info);
  /// ExactTime drops a stamp's messages: a depth image among them had no CameraInfo.
  void unpaired(const sensor_msgs::Image::ConstPtr& depth, const sensor_msgs::CameraInfo::ConstPtr& info);
  void matched(const sensor_msgs::Image::ConstPtr& depth, const sensor_msgs::CameraInfo::ConstPtr& info,
               const sensor_msgs::Image::ConstPtr& color);
  /// Every 10 s: warns when images came but none was matched.
  void check_matching(const ros::WallTimerEvent& event);

  Callback callback_;
  Dropped dropped_;
  message_filters::Subscriber<sensor_msgs::Image> depth_subscriber_;
  tf2_ros::MessageFilter<sensor_msgs::Image> depth_filter_;
  message_filters::Subscriber<sensor_msgs::CameraInfo> info_subscriber_;
  message_filters::Subscriber<sensor_msgs::Image> color_subscriber_;
  std::unique_ptr<message_filters::Synchronizer<ExactPair>> exact_;
  std::unique_ptr<message_filters::Synchronizer<NearestTriple>> nearest_;
  ros::WallTimer matching_timer_;
  // Arrivals since the last check_matching (callback thread only).
  std::size_t depth_count_ = 0;
  std::size_t info_count_ = 0;
  std::size_t color_count_ = 0;
  std::size_t matched_count_ = 0;
  std::size_t received_ = 0;  // since the start
};

}  // namespace umbra::ros_io
