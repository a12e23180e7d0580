// libFuzzer target for ROS bags (.bag): the whole scan source, open_rosbag
// (ros/include/umbra_ros/rosbag_source.hpp), in ROS builds: umbra's reader
// of the bag format (records, index, chunks uncompressed, bz2 and lz4), the
// PointCloud2 and TFMessage parsers, tf2 with the bag's transforms, and the
// cloud decoder. Every PointCloud2 topic is read to the end into frame
// "map"; a scan must have as many colors as points, or none, and progress
// stays within 0..1. Seeds: a small valid bag of each compression
// (make_seeds.cpp, with the tests' bag writer).
#include <cstdint>
#include <memory>

#include "fuzz_support.hpp"
#include "umbra_ros/rosbag_source.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static umbra::fuzz::InputFile file(".bag");
  const auto& path = file.hold(data, size);
  umbra::fuzz::expect_only_format_errors([&] {
    const std::unique_ptr<umbra::ros_io::RosbagScanSource> source = umbra::ros_io::open_rosbag(path);
    umbra::Scan scan;
    while (source->next(scan)) {
      umbra::fuzz::require(scan.colors.empty() || scan.colors.size() == scan.points.size(),
                           "one color per point, or none");
      const double progress = source->progress();
      umbra::fuzz::require(progress >= 0.0 && progress <= 1.0, "progress within 0..1");
    }
  });
  return 0;
}
