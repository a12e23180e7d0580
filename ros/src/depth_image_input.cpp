// DepthImageInput: see depth_image_input.hpp.
#include "depth_image_input.hpp"

#include <utility>

namespace umbra::ros_io {
namespace {

constexpr std::uint32_t kImageQueue = 5;  // depth images waiting for their transform, as the clouds
/// Messages each synchronizer keeps per topic: CameraInfos and color images arrive while their depth image
/// still waits for its transform.
constexpr std::uint32_t kMatchQueue = 10;
constexpr double kMatchingCheckSeconds = 10.0;

/// The CameraInfo topic of an image topic (resolved): camera_info beside it, image_transport's rule.
std::string camera_info_topic(const std::string& image_topic) {
  return ros::names::append(ros::names::parentNamespace(image_topic), "camera_info");
}

}  // namespace

DepthImageInput::DepthImageInput(ros::NodeHandle& node, tf2_ros::Buffer& tf, const std::string& map_frame,
                                 bool colors, Callback callback, Dropped dropped)
    : callback_(std::move(callback)),
      dropped_(std::move(dropped)),
      depth_subscriber_(node, "depth/image", kImageQueue),
      depth_filter_(depth_subscriber_, tf, map_frame, kImageQueue, node),
      info_subscriber_(node, camera_info_topic(depth_subscriber_.getTopic()), kMatchQueue) {
  depth_filter_.registerFailureCallback(
      [this](const sensor_msgs::Image::ConstPtr& image, tf2_ros::filter_failure_reasons::FilterFailureReason reason) {
        dropped_(image, reason == tf2_ros::filter_failure_reasons::EmptyFrameID ? Drop::no_frame_id : Drop::no_transform);
      });
  depth_subscriber_.registerCallback([this](const sensor_msgs::Image::ConstPtr&) {
    ++depth_count_;
    ++received_;
  });
  info_subscriber_.registerCallback([this](const sensor_msgs::CameraInfo::ConstPtr&) { ++info_count_; });
  if (colors) {
    color_subscriber_.subscribe(node, "rgb/image", kMatchQueue);
    color_subscriber_.registerCallback([this](const sensor_msgs::Image::ConstPtr&) { ++color_count_; });
    nearest_ = std::make_unique<message_filters::Synchronizer<NearestTriple>>(NearestTriple(kMatchQueue), depth_filter_,
                                                                               info_subscriber_, color_subscriber_);
    nearest_->registerCallback(&DepthImageInput::matched, this);
  } else {
    exact_ = std::make_unique<message_filters::Synchronizer<ExactPair>>(ExactPair(kMatchQueue), depth_filter_,
                                                                         info_subscriber_);
    exact_->registerCallback(&DepthImageInput::paired, this);
    exact_->registerDropCallback(&DepthImageInput::unpaired, this);
  }
  matching_timer_ = node.createWallTimer(ros::WallDuration(kMatchingCheckSeconds), &DepthImageInput::check_matching, this);
}

void DepthImageInput::paired(const sensor_msgs::Image::ConstPtr& depth, const sensor_msgs::CameraInfo::ConstPtr& info) {
  matched(depth, info, nullptr);
}

void DepthImageInput::unpaired(const sensor_msgs::Image::ConstPtr& depth, const sensor_msgs::CameraInfo::ConstPtr&) {
  // CameraInfos whose image tf2 dropped, or that came without one, are dropped too: nothing to say about them.
  if (depth) dropped_(depth, Drop::no_camera_info);
}

std::string DepthImageInput::describe(Drop why) const {
  switch (why) {
    case Drop::no_frame_id:
      return "it has no frame_id";
    case Drop::no_transform:
      return "tf2 had no transform from its frame to the map frame at its stamp";
    case Drop::no_camera_info:
      return "no CameraInfo with its stamp came on '" + info_subscriber_.getTopic() + "'";
  }
  return "an unknown reason";
}

std::string DepthImageInput::topics() const {
  std::string text = "'" + depth_subscriber_.getTopic() + "' with '" + info_subscriber_.getTopic() + "'";
  if (nearest_) text += " and colors from '" + color_subscriber_.getTopic() + "'";
  return text;
}

void DepthImageInput::matched(const sensor_msgs::Image::ConstPtr& depth, const sensor_msgs::CameraInfo::ConstPtr& info,
                              const sensor_msgs::Image::ConstPtr& color) {
  ++matched_count_;
  callback_(depth, info, color);
}

void DepthImageInput::check_matching(const ros::WallTimerEvent&) {
  if (depth_count_ > 0 && matched_count_ == 0) {
    const std::string colors = nearest_ ? ", " + std::to_string(color_count_) + " color images on '" +
                                              color_subscriber_.getTopic() + "'"
                                        : std::string();
    ROS_WARN("umbra_server: in the last %.0f s %zu depth images came on '%s', %zu CameraInfo on '%s'%s, but no depth "
             "image could be placed with TF and matched by stamp: none was inserted",
             kMatchingCheckSeconds, depth_count_, depth_subscriber_.getTopic().c_str(), info_count_,
             info_subscriber_.getTopic().c_str(), colors.c_str());
  }
  depth_count_ = 0;
  info_count_ = 0;
  color_count_ = 0;
  matched_count_ = 0;
}

}  // namespace umbra::ros_io
