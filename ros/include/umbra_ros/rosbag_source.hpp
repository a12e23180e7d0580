// open_rosbag: a ScanSource over a ROS 1 bag file (.bag), in ROS builds only.
//
// The bag is read by umbra's own reader (bag_file.hpp: format 2.0, chunks
// uncompressed, bz2 or lz4), not librosbag, which trusts the file's lengths
// and offsets. Every sensor_msgs/PointCloud2 message on the chosen topics
// (all PointCloud2 topics when none is named), in the bag's time order, is
// one scan: parsed (serialized_messages.hpp), decoded by decode_point_cloud2
// (its layout checked before any point is read) and moved into the map frame
// with the transform tf2 gives from the cloud's frame to `frame` at the
// cloud's stamp, from every transform on /tf and /tf_static in the bag (tf2
// interpolates between them); the sensor origin is the cloud frame's origin.
// A cloud already in `frame` needs no transform. A cloud for which tf2 has
// no transform (before the first or after the last one on its chain) is
// skipped and counted; if every cloud is skipped, next() throws with tf2's
// reason. Connections on /tf or /tf_static of another message type are
// ignored (warnings() names them).
//
// Cost: opening reads the bag's index and every /tf and /tf_static message
// into a tf2 buffer (memory: all transforms; small beside the clouds); then
// one cloud at a time is read and decoded (its chunk decompressed once).
//
// Errors (umbra::FormatError, each naming the file): a file that is not a
// bag of format 2.0, a corrupt record, chunk or index ("FILE: byte N: what is
// wrong"); a bag without the named topics or without any PointCloud2 topic
// (naming the topics it has); a chosen topic whose PointCloud2 connection
// has another md5sum (another version of the message); a malformed cloud or
// transform message ("FILE: byte N: message K on TOPIC: what is wrong").
// MemoryLimitError when a chunk needs more than umbra::memory_limit().
#pragma once

#include <cstddef>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "umbra/io/scan_source.hpp"

namespace umbra::ros_io {

struct RosbagOptions {
  std::vector<std::string> topics;  ///< PointCloud2 topics; empty: every PointCloud2 topic in the bag
  std::string frame = "map";        ///< the map frame (a leading '/' is ignored)
  bool colors = true;               ///< decode rgb/rgba (a bad rgb field is then an error); false: ignore it
};

class RosbagScanSource : public ScanSource {
 public:
  /// Clouds skipped because tf2 had no transform to the map frame at their time.
  [[nodiscard]] virtual std::size_t skipped_clouds() const = 0;
  /// tf2's reason for the first skipped cloud (empty if none).
  [[nodiscard]] virtual const std::string& first_skip_reason() const = 0;
};

std::unique_ptr<RosbagScanSource> open_rosbag(const std::filesystem::path& path, const RosbagOptions& options = {});

/// Registers open_rosbag as open_scan_source's reader of "rosbag" (.bag),
/// with ScanSourceOptions::topics and ::frame as its options (umbra/io/scan_source.hpp).
void register_rosbag_format();

}  // namespace umbra::ros_io
