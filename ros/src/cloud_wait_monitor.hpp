// CloudWaitMonitor: says so when clouds wait for a transform that does not
// come.
//
// tf2's message filter holds each cloud until tf2 can transform its frame
// into the map frame at its stamp. A cloud whose frame TF never names just
// waits: the filter drops it (and umbra_server says so) only when five newer
// clouds push it out of the queue, so a robot that sent one cloud, or whose
// TF tree lacks the sensor's frame, saw nothing at all. The monitor counts
// the clouds that arrive and those the filter hands on or drops; once a
// second it looks, and when clouds have been waiting for more than 5 s and
// tf2 cannot place the latest of them, it warns (at most once every 5 s)
// naming that cloud's frame and stamp, the map frame and the frames tf2
// knows.
//
// Threads: everything runs in the node's ROS callback thread.
#pragma once

#include <ros/ros.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2_ros/buffer.h>

#include <cstddef>
#include <string>

namespace umbra::ros_io {

class CloudWaitMonitor {
 public:
  /// Starts the once-a-second check; `tf` must outlive this.
  CloudWaitMonitor(ros::NodeHandle& node, const tf2_ros::Buffer& tf, std::string map_frame);

  /// A cloud arrived (before the tf2 filter decides about it).
  void arrived(const sensor_msgs::PointCloud2& cloud);
  /// The filter handed a cloud on or dropped it.
  void left();

  /// "frames tf2 knows: 'a', 'b'", or "tf2 has received no transform yet": for log lines about frames.
  [[nodiscard]] std::string known_frames() const;

 private:
  void check(const ros::WallTimerEvent& event);

  const tf2_ros::Buffer& tf_;
  std::string map_frame_;
  ros::WallTimer timer_;
  std::size_t waiting_ = 0;       ///< clouds arrived and not yet handed on or dropped
  ros::WallTime waiting_since_;   ///< when the oldest of them arrived (approximately: see left())
  std::string latest_frame_;      ///< frame_id of the latest cloud
  ros::Time latest_stamp_;        ///< its stamp
  ros::WallTime last_warning_;
};

}  // namespace umbra::ros_io
