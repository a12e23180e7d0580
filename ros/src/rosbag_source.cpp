// open_rosbag: see rosbag_source.hpp. BagFile gives the messages of the
// chosen connections in time order; serialized_messages parses them;
// tf2::BufferCore holds every transform of the bag (its cache as long as the
// transforms' time span) and answers the cloud-to-map lookups.
#include "umbra_ros/rosbag_source.hpp"

#include <console_bridge/console.h>
#include <geometry_msgs/TransformStamped.h>
#include <tf2/buffer_core.h>
#include <tf2/exceptions.h>

#include <algorithm>
#include <limits>
#include <set>
#include <stdexcept>

#include "cloud_message.hpp"
#include "umbra/core/memory_limit.hpp"
#include "reader_support.hpp"
#include "umbra_ros/bag_file.hpp"
#include "umbra_ros/serialized_messages.hpp"

namespace umbra::ros_io {
namespace {

constexpr const char* kPointCloud2 = "sensor_msgs/PointCloud2";

std::string join(const std::set<std::string>& names) {
  std::string text;
  for (const std::string& name : names) text += (text.empty() ? "" : ", ") + name;
  return text.empty() ? std::string("none") : text;
}

bool is_tf_topic(const std::string& topic) {
  return topic == "/tf" || topic == "/tf_static" || topic == "tf" || topic == "tf_static";
}

/// A message's stamp as ros::Time; nanoseconds of 10^9 or more (which ros::Time would carry into the
/// seconds, and overflow) are refused.
ros::Time stamp_of(const MessageHeader& header, const std::string& name) {
  if (header.stamp_nsec >= 1000000000u) {
    throw FormatError(name, "header.stamp has " + std::to_string(header.stamp_nsec) +
                                " nanoseconds, not below 10^9");
  }
  return {header.stamp_sec, header.stamp_nsec};
}

/// While it lives, what tf2 logs (through console_bridge: the only place it says why it refuses a transform)
/// is kept here instead of printed.
class Tf2Log final : public console_bridge::OutputHandler {
 public:
  Tf2Log() { console_bridge::useOutputHandler(this); }
  Tf2Log(const Tf2Log&) = delete;
  Tf2Log& operator=(const Tf2Log&) = delete;
  ~Tf2Log() override { console_bridge::restorePreviousOutputHandler(); }
  void log(const std::string& text, console_bridge::LogLevel, const char*, int) override {
    if (first.empty()) first = text.substr(0, 300);
  }
  std::string first;  ///< the first message, cut to 300 characters (tf2 prints doubles with all their digits)
};

class RosbagSource final : public RosbagScanSource {
 public:
  RosbagSource(const std::filesystem::path& path, const RosbagOptions& options)
      : path_(path.string()), frame_(tf2_frame(options.frame)), colors_(options.colors) {
    if (frame_.empty()) throw std::invalid_argument("the map frame for " + path_ + " is empty");
    try {
      bag_ = std::make_unique<BagFile>(path);
    } catch (const FormatError&) {
      throw;
    } catch (const std::runtime_error& e) {  // cannot open: missing, a folder, unreadable
      throw FormatError(path_, std::string("cannot read this ROS bag: ") + e.what());
    }
    choose_topics(options.topics);
    load_transforms();
    clouds_ = bag_->messages([&](const BagConnection& c) {
      return c.type == kPointCloud2 && std::find(topics_.begin(), topics_.end(), c.topic) != topics_.end();
    });
  }

  bool next(Scan& scan) override {
    while (index_ < clouds_.size()) {
      const BagMessage& message = clouds_[index_++];
      const std::string label = "message " + std::to_string(index_) + " on " + bag_->connections()[message.connection].topic;
      const std::span<const std::uint8_t> bytes = bag_->read(message);  // its errors name their byte already
      try {
        const SerializedCloud cloud = parse_point_cloud2(bytes, label);
        RigidTransform to_map;
        const std::string cloud_frame = tf2_frame(cloud.header.frame_id);
        if (cloud_frame != frame_) {
          const ros::Time stamp = stamp_of(cloud.header, label);
          try {
            to_map = to_rigid_transform(buffer_->lookupTransform(frame_, cloud_frame, stamp).transform);
          } catch (const tf2::TransformException& e) {
            if (skipped_++ == 0) first_skip_reason_ = path_ + " " + label + ": " + e.what();
            continue;
          } catch (const std::exception& e) {  // ros::Time arithmetic out of range, a degenerate quaternion
            throw FormatError(label, std::string("no usable transform from frame '") + cloud_frame + "': " + e.what());
          }
        }
        cloud_to_scan(cloud.cloud, to_map, colors_, decoded_, scan, label);
        scan.stamp = stamp_of(cloud.header, label).toSec();
      } catch (const FormatError& e) {
        throw bag_->error(message, e.what());
      } catch (const MemoryLimitError& e) {  // the decoded points: named like the other errors
        throw MemoryLimitError(bag_->error(message, e.what()).what());
      }
      scan.name = path_ + " " + label;
      ++scans_;
      return true;
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
    return clouds_.empty() ? 1.0 : static_cast<double>(index_) / static_cast<double>(clouds_.size());
  }
  [[nodiscard]] std::vector<std::string> warnings() const override { return warnings_; }
  [[nodiscard]] std::size_t skipped_clouds() const override { return skipped_; }
  [[nodiscard]] const std::string& first_skip_reason() const override { return first_skip_reason_; }

 private:
  void choose_topics(const std::vector<std::string>& requested) {
    std::set<std::string> cloud_topics;
    std::set<std::string> all_topics;
    for (const BagConnection& connection : bag_->connections()) {
      all_topics.insert(connection.topic + " (" + connection.type + ")");
      if (connection.type == kPointCloud2) cloud_topics.insert(connection.topic);
    }
    if (requested.empty()) {
      if (cloud_topics.empty()) {
        throw FormatError(path_, "the bag has no sensor_msgs/PointCloud2 topic; its topics: " + join(all_topics));
      }
      topics_.assign(cloud_topics.begin(), cloud_topics.end());
    } else {
      for (const std::string& topic : requested) {
        if (cloud_topics.count(topic) == 0) {
          throw FormatError(path_, "the bag has no sensor_msgs/PointCloud2 topic '" + topic +
                                       "'; its PointCloud2 topics: " + join(cloud_topics));
        }
      }
      topics_ = requested;
    }
    // Another md5sum is another definition of the message: its bytes would be misread.
    for (const BagConnection& connection : bag_->connections()) {
      if (connection.type != kPointCloud2 || connection.md5sum == kPointCloud2Md5 || connection.md5sum == "*") continue;
      if (std::find(topics_.begin(), topics_.end(), connection.topic) == topics_.end()) continue;
      throw FormatError::at_byte(path_, connection.byte,
                                 "connection " + std::to_string(connection.id) + " on " +
                                     detail::quote(connection.topic) + " is sensor_msgs/PointCloud2 with md5sum " +
                                     detail::quote(connection.md5sum) + ", not " + kPointCloud2Md5 +
                                     ": another version of the message, which umbra cannot read");
    }
  }

  void load_transforms() {
    const std::vector<BagMessage> messages = bag_->messages([&](const BagConnection& c) {
      if (!is_tf_topic(c.topic)) return false;
      if (c.md5sum == kTfMessageMd5 || (c.md5sum == "*" && (c.type == "tf2_msgs/TFMessage" || c.type == "tf/tfMessage"))) {
        return true;
      }
      warnings_.push_back(path_ + ": ignoring connection " + std::to_string(c.id) + " on " + c.topic + ": " +
                          detail::quote(c.type) + " with md5sum " + detail::quote(c.md5sum) +
                          " is not a tf2_msgs/TFMessage");
      return false;
    });
    // Parse every transform first: tf2's cache time must cover their span (see cache_time).
    struct Parsed {
      std::vector<SerializedTransform> transforms;
      bool is_static = false;
      std::string label;
      BagMessage message;
    };
    std::vector<Parsed> parsed;
    std::uint32_t first_sec = std::numeric_limits<std::uint32_t>::max();
    std::uint32_t last_sec = 0;
    for (std::size_t i = 0; i < messages.size(); ++i) {
      const BagMessage& message = messages[i];
      const std::string& topic = bag_->connections()[message.connection].topic;
      Parsed p{{}, topic.find("tf_static") != std::string::npos, "transform message " + std::to_string(i + 1) + " on " + topic, message};
      const std::span<const std::uint8_t> bytes = bag_->read(message);
      try {
        p.transforms = parse_tf_message(bytes, p.label);
        for (const SerializedTransform& t : p.transforms) {
          (void)stamp_of(t.header, p.label);
          first_sec = std::min(first_sec, t.header.stamp_sec);
          last_sec = std::max(last_sec, t.header.stamp_sec);
        }
      } catch (const FormatError& e) {
        throw bag_->error(message, e.what());
      }
      parsed.push_back(std::move(p));
    }
    buffer_ = std::make_unique<tf2::BufferCore>(cache_time(first_sec, last_sec));
    std::size_t total = 0;
    std::size_t refused = 0;
    const Tf2Log tf2_log;
    for (const Parsed& p : parsed) {
      for (const SerializedTransform& t : p.transforms) {
        geometry_msgs::TransformStamped transform;
        transform.header.stamp = ros::Time(t.header.stamp_sec, t.header.stamp_nsec);
        transform.header.frame_id = tf2_frame(t.header.frame_id);
        transform.child_frame_id = tf2_frame(t.child_frame_id);
        transform.transform.translation.x = t.translation[0];
        transform.transform.translation.y = t.translation[1];
        transform.transform.translation.z = t.translation[2];
        transform.transform.rotation.x = t.rotation[0];
        transform.transform.rotation.y = t.rotation[1];
        transform.transform.rotation.z = t.rotation[2];
        transform.transform.rotation.w = t.rotation[3];
        try {
          // tf2 refuses (returns false, logs why) NaN, unnormalised quaternions and frames it cannot use.
          ++total;
          if (buffer_->setTransform(transform, "bag", p.is_static)) {
            tf_frames_.insert(transform.header.frame_id);
            tf_frames_.insert(transform.child_frame_id);
          } else {
            ++refused;
          }
        } catch (const std::exception& e) {  // ros::Time arithmetic out of range inside tf2
          throw bag_->error(p.message, p.label + ": tf2 cannot hold the transform " + transform.header.frame_id +
                                           " -> " + transform.child_frame_id + ": " + e.what());
        }
      }
    }
    if (refused > 0) {
      warnings_.push_back(path_ + ": tf2 refused " + std::to_string(refused) + " of the bag's " + std::to_string(total) +
                          " transforms (first: " + tf2_log.first + ")");
    }
  }

  /// tf2 drops transforms older than its cache time behind the newest: the cache spans every transform of the
  /// bag (plus 10 s), within what ros::Duration and ros::Time can hold (stamp + cache time must stay below 2^32 s).
  static ros::Duration cache_time(std::uint32_t first_sec, std::uint32_t last_sec) {
    if (first_sec > last_sec) return ros::Duration(10.0);  // no transforms
    std::uint64_t seconds = std::uint64_t{last_sec} - first_sec + 10;
    seconds = std::min<std::uint64_t>(seconds, std::numeric_limits<std::int32_t>::max() - 1);
    const std::uint64_t headroom = std::uint64_t{std::numeric_limits<std::uint32_t>::max()} - last_sec;
    seconds = std::min<std::uint64_t>(seconds, headroom > 0 ? headroom - 1 : 0);
    return ros::Duration(static_cast<std::int32_t>(seconds), 0);
  }

  std::string path_;
  std::string frame_;
  bool colors_ = true;
  std::unique_ptr<BagFile> bag_;
  std::vector<std::string> topics_;
  std::unique_ptr<tf2::BufferCore> buffer_;
  std::set<std::string> tf_frames_;
  std::vector<BagMessage> clouds_;
  std::size_t index_ = 0;
  std::size_t scans_ = 0;
  std::size_t skipped_ = 0;
  std::string first_skip_reason_;
  std::vector<std::string> warnings_;
  DecodedCloud decoded_;
};

}  // namespace

std::unique_ptr<RosbagScanSource> open_rosbag(const std::filesystem::path& path, const RosbagOptions& options) {
  return std::make_unique<RosbagSource>(path, options);
}

void register_rosbag_format() {
  register_scan_format("rosbag", {".bag"}, [](const std::filesystem::path& path, const ScanSourceOptions& options) {
    return open_rosbag(path, RosbagOptions{options.topics, options.frame});
  });
}

}  // namespace umbra::ros_io
