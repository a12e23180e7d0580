// CloudWaitMonitor: see cloud_wait_monitor.hpp.
#include "cloud_wait_monitor.hpp"

#include <utility>
#include <vector>

#include "cloud_message.hpp"

namespace umbra::ros_io {
namespace {

constexpr double kCheckSeconds = 1.0;
/// A cloud is late once it has waited this long; the same bound spaces the warnings.
constexpr double kWaitSeconds = 5.0;

}  // namespace

CloudWaitMonitor::CloudWaitMonitor(ros::NodeHandle& node, const tf2_ros::Buffer& tf, std::string map_frame)
    : tf_(tf), map_frame_(std::move(map_frame)) {
  timer_ = node.createWallTimer(ros::WallDuration(kCheckSeconds), &CloudWaitMonitor::check, this);
}

void CloudWaitMonitor::arrived(const sensor_msgs::PointCloud2& cloud) {
  if (waiting_ == 0) waiting_since_ = ros::WallTime::now();
  ++waiting_;
  latest_frame_ = cloud.header.frame_id;
  latest_stamp_ = cloud.header.stamp;
}

void CloudWaitMonitor::left() {
  if (waiting_ > 0) --waiting_;
  // The filter hands clouds on in order, so the next one waits since about now; taking now keeps the warning
  // for clouds that really wait, at the price of warning up to 5 s later than exact bookkeeping would.
  waiting_since_ = ros::WallTime::now();
}

std::string CloudWaitMonitor::known_frames() const {
  std::vector<std::string> frames;
  tf_._getFrameStrings(frames);
  if (frames.empty()) return "tf2 has received no transform yet";
  std::string text = "frames tf2 knows:";
  for (std::size_t i = 0; i < frames.size(); ++i) text += (i == 0 ? " '" : ", '") + frames[i] + "'";
  return text;
}

void CloudWaitMonitor::check(const ros::WallTimerEvent&) {
  const ros::WallTime now = ros::WallTime::now();
  if (waiting_ == 0 || (now - waiting_since_).toSec() < kWaitSeconds) return;
  if (!last_warning_.isZero() && (now - last_warning_).toSec() < kWaitSeconds) return;
  // A cloud tf2 can place only waits for the callback thread (a long insertion before it): nothing to say.
  // (A cloud without frame_id is dropped by the filter, which says so.)
  if (latest_frame_.empty() || tf_.canTransform(map_frame_, tf2_frame(latest_frame_), latest_stamp_)) return;
  last_warning_ = now;
  ROS_WARN("umbra_server: %zu cloud%s waited %.0f s for a transform from '%s' to the map frame '%s' (the latest at "
           "%f); none is inserted until TF connects the two (%s)",
           waiting_, waiting_ == 1 ? " has" : "s have", (now - waiting_since_).toSec(), latest_frame_.c_str(),
           map_frame_.c_str(), latest_stamp_.toSec(), known_frames().c_str());
}

}  // namespace umbra::ros_io
