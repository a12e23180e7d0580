// open_rosbag: see rosbag_source.hpp. rosbag::View gives the messages of the
// chosen topics in time order from the bag's index; tf2::BufferCore holds
// every transform of the bag (its cache as long as the bag) and answers the
// cloud-to-map lookups.
#include "umbra_ros/rosbag_source.hpp"

#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2/buffer_core.h>
#include <tf2/exceptions.h>
#include <tf2_msgs/TFMessage.h>

#include <algorithm>
#include <set>
#include <sstream>

#include "cloud_message.hpp"

namespace umbra::ros_io {
namespace {

constexpr const char* kPointCloud2 = "sensor_msgs/PointCloud2";

std::string join(const std::set<std::string>& names) {
  std::string text;
  for (const std::string& name : names) text += (text.empty() ? "" : ", ") + name;
  return text.empty() ? std::string("none") : text;
}

class RosbagSource final : public RosbagScanSource {
 public:
  RosbagSource(const std::filesystem::path& path, const RosbagOptions& options)
      : path_(path.string()), frame_(tf2_frame(options.frame)) {
    if (frame_.empty()) throw std::invalid_argument("the map frame for " + path_ + " is empty");
    ros::Time::init();  // ROS time without a node (rosbag and tf2 only compare stamps)
    try {
      bag_.open(path_, rosbag::bagmode::Read);
    } catch (const rosbag::BagException& e) {
      throw FormatError(path_, std::string("cannot read this ROS bag: ") + e.what());
    }
    choose_topics(options.topics);
    load_transforms();
    try {
      clouds_ = std::make_unique<rosbag::View>(bag_, rosbag::TopicQuery(topics_));
      total_ = clouds_->size();
      next_ = clouds_->begin();
    } catch (const rosbag::BagException& e) {
      throw FormatError(path_, std::string("cannot read this ROS bag: ") + e.what());
    }
  }

  bool next(Scan& scan) override {
    try {
      while (next_ != clouds_->end()) {
        const rosbag::MessageInstance& message = *next_;
        ++index_;
        const std::string name = path_ + " message " + std::to_string(index_) + " on " + message.getTopic();
        const sensor_msgs::PointCloud2::ConstPtr cloud = message.instantiate<sensor_msgs::PointCloud2>();
        ++next_;
        if (!cloud) throw FormatError(name, "not a sensor_msgs/PointCloud2 (" + message.getDataType() + ")");
        RigidTransform to_map;
        const std::string cloud_frame = tf2_frame(cloud->header.frame_id);
        if (cloud_frame != frame_) {
          try {
            to_map = to_rigid_transform(buffer_->lookupTransform(frame_, cloud_frame, cloud->header.stamp).transform);
          } catch (const tf2::TransformException& e) {
            if (skipped_++ == 0) first_skip_reason_ = name + ": " + e.what();
            continue;
          }
        }
        cloud_to_scan(*cloud, to_map, decoded_, scan, name);
        ++scans_;
        return true;
      }
    } catch (const rosbag::BagException& e) {
      throw FormatError(path_, std::string("cannot read this ROS bag: ") + e.what());
    }
    if (scans_ == 0 && skipped_ > 0) {
      throw FormatError(path_, "no cloud could be moved into frame '" + frame_ + "': tf2 found no transform for any of " +
                                   std::to_string(skipped_) + " clouds (first: " + first_skip_reason_ +
                                   "); frames in the bag's TF: " + join(tf_frames_));
    }
    return false;
  }

  [[nodiscard]] std::size_t scan_count() const override { return 0; }  // clouds may be skipped
  [[nodiscard]] double progress() const override {
    return total_ == 0 ? 1.0 : static_cast<double>(index_) / static_cast<double>(total_);
  }
  [[nodiscard]] std::size_t skipped_clouds() const override { return skipped_; }
  [[nodiscard]] const std::string& first_skip_reason() const override { return first_skip_reason_; }

 private:
  void choose_topics(const std::vector<std::string>& requested) {
    std::set<std::string> cloud_topics;
    std::set<std::string> all_topics;
    rosbag::View everything(bag_);
    for (const rosbag::ConnectionInfo* connection : everything.getConnections()) {
      all_topics.insert(connection->topic + " (" + connection->datatype + ")");
      if (connection->datatype == kPointCloud2) cloud_topics.insert(connection->topic);
    }
    if (requested.empty()) {
      if (cloud_topics.empty()) {
        throw FormatError(path_, "the bag has no sensor_msgs/PointCloud2 topic; its topics: " + join(all_topics));
      }
      topics_.assign(cloud_topics.begin(), cloud_topics.end());
      return;
    }
    for (const std::string& topic : requested) {
      if (cloud_topics.count(topic) == 0) {
        throw FormatError(path_, "the bag has no sensor_msgs/PointCloud2 topic '" + topic +
                                     "'; its PointCloud2 topics: " + join(cloud_topics));
      }
    }
    topics_ = requested;
  }

  void load_transforms() {
    rosbag::View everything(bag_);
    const ros::Duration span = everything.size() == 0 ? ros::Duration(0.0) : everything.getEndTime() - everything.getBeginTime();
    // Keep every transform of the bag (tf2 drops those older than the cache time behind the newest).
    buffer_ = std::make_unique<tf2::BufferCore>(span + ros::Duration(10.0));
    rosbag::View transforms(bag_, rosbag::TopicQuery(std::vector<std::string>{"/tf", "/tf_static", "tf", "tf_static"}));
    for (const rosbag::MessageInstance& message : transforms) {
      const tf2_msgs::TFMessage::ConstPtr tf = message.instantiate<tf2_msgs::TFMessage>();
      if (!tf) continue;  // another type on /tf: not a transform
      const bool is_static = message.getTopic().find("tf_static") != std::string::npos;
      for (geometry_msgs::TransformStamped transform : tf->transforms) {
        transform.header.frame_id = tf2_frame(transform.header.frame_id);
        transform.child_frame_id = tf2_frame(transform.child_frame_id);
        buffer_->setTransform(transform, "bag", is_static);
        tf_frames_.insert(transform.header.frame_id);
        tf_frames_.insert(transform.child_frame_id);
      }
    }
  }

  std::string path_;
  std::string frame_;
  rosbag::Bag bag_;
  std::vector<std::string> topics_;
  std::unique_ptr<tf2::BufferCore> buffer_;
  std::set<std::string> tf_frames_;
  std::unique_ptr<rosbag::View> clouds_;
  rosbag::View::iterator next_;
  std::size_t total_ = 0;
  std::size_t index_ = 0;
  std::size_t scans_ = 0;
  std::size_t skipped_ = 0;
  std::string first_skip_reason_;
  DecodedCloud decoded_;
};

}  // namespace

std::unique_ptr<RosbagScanSource> open_rosbag(const std::filesystem::path& path, const RosbagOptions& options) {
  return std::make_unique<RosbagSource>(path, options);
}

}  // namespace umbra::ros_io
