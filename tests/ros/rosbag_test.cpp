// The .bag scan source (ros/include/umbra_ros/rosbag_source.hpp) and
// `umbra build` on a bag. Each test writes its bag with rosbag itself: the
// simulated office's scans as PointCloud2 in a sensor frame, the sensor pose
// on /tf (map -> base_link) and a static mount on /tf_static (base_link ->
// lidar). The map read from the bag must equal, bit for bit, the map the
// library builds from the simulator's points directly.
#include <rosbag/bag.h>
#include <tf2_msgs/TFMessage.h>

#include <string>

#include "ros_test_support.hpp"
#include "support/test_support.hpp"
#include "umbra/io/map_file.hpp"
#include "umbra_ros/rosbag_source.hpp"

#include <gtest/gtest.h>

namespace umbra::test {
namespace {

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

ros::Time scan_time(std::size_t i) { return ros::Time(100.0 + 0.5 * static_cast<double>(i)); }

/// Writes the scans to `path`; the first `early` clouds come before any transform.
void write_bag(const std::filesystem::path& path, const std::vector<RosScan>& scans, std::size_t early = 0) {
  rosbag::Bag bag(path.string(), rosbag::bagmode::Write);
  tf2_msgs::TFMessage mount;
  RosScan identity;  // the lidar sits at base_link's origin
  mount.transforms.push_back(to_transform(identity, "base_link", "lidar", scan_time(0)));
  bag.write("/tf_static", scan_time(0), mount);
  for (std::size_t i = 0; i < early; ++i) {
    bag.write("/points", ros::Time(50.0 + static_cast<double>(i)), to_cloud(scans[i], "lidar", ros::Time(50.0 + static_cast<double>(i))));
  }
  for (std::size_t i = 0; i < scans.size(); ++i) {
    tf2_msgs::TFMessage tf;
    tf.transforms.push_back(to_transform(scans[i], "/map", "base_link", scan_time(i)));  // an old-style "/map"
    bag.write("/tf", scan_time(i), tf);
    bag.write("/points", scan_time(i), to_cloud(scans[i], "lidar", scan_time(i)));
  }
  // Another PointCloud2 topic, already in the map frame: read only when chosen (or when no topic is named).
  RosScan in_map = scans[0];
  in_map.position = {};
  in_map.yaw = 0;
  in_map.tilt = 0;
  bag.write("/other_points", scan_time(0), to_cloud(in_map, "map", scan_time(0)));
  bag.close();
}

TEST(Rosbag, ScansEqualTheSimulatorsPoints) {
  const std::vector<RosScan> scans = office_scans(4);
  const auto dir = scratch_dir();
  write_bag(dir / "office.bag", scans, 1);
  ros_io::RosbagOptions options;
  options.topics = {"/points"};
  const auto source = ros_io::open_rosbag(dir / "office.bag", options);
  OccupancyMap map(0.1);
  Scan scan;
  std::size_t count = 0;
  while (source->next(scan)) {
    ASSERT_LT(count, scans.size());
    EXPECT_EQ(scan.origin, Vec3f(scans[count].position));
    EXPECT_TRUE(contains(scan.name, "office.bag message " + std::to_string(count + 2) + " on /points")) << scan.name;
    map.insert_point_cloud(scan.origin, scan.points);
    ++count;
  }
  EXPECT_EQ(count, scans.size());
  EXPECT_EQ(source->skipped_clouds(), 1u);  // the cloud before every transform
  EXPECT_TRUE(contains(source->first_skip_reason(), "message 1 on /points")) << source->first_skip_reason();
  EXPECT_DOUBLE_EQ(source->progress(), 1.0);
  const OccupancyMap reference = reference_map(scans, 0.1);
  EXPECT_EQ(tree_bytes(map, OctoMapFormat::ot), tree_bytes(reference, OctoMapFormat::ot));
}

TEST(Rosbag, EveryCloudTopicWhenNoneIsNamed) {
  const std::vector<RosScan> scans = office_scans(2);
  const auto dir = scratch_dir();
  write_bag(dir / "two.bag", scans);
  const std::vector<Scan> all = read_all(*ros_io::open_rosbag(dir / "two.bag"));
  ASSERT_EQ(all.size(), 3u);  // two on /points, one on /other_points (at the time of the first)
  std::size_t other = 0;
  for (const Scan& scan : all) other += contains(scan.name, "/other_points") ? 1 : 0;
  EXPECT_EQ(other, 1u);
}

TEST(Rosbag, UmbraBuildReadsBags) {
  const std::vector<RosScan> scans = office_scans(3);
  const auto dir = scratch_dir();
  write_bag(dir / "office.bag", scans);
  const CommandResult result = run_command(std::string(UMBRA_CLI_PATH) + " build " + (dir / "office.bag").string() +
                                           " --topic /points --frame map --res 0.1 --threads 2 -o " +
                                           (dir / "office.umb").string() + " 2>&1");
  ASSERT_EQ(result.exit_code, 0) << result.output;
  EXPECT_TRUE(contains(result.output, "total: 3 scans")) << result.output;
  const OccupancyMap built = load_map(dir / "office.umb");
  EXPECT_EQ(tree_bytes(built, OctoMapFormat::ot), tree_bytes(reference_map(scans, 0.1), OctoMapFormat::ot));
}

TEST(Rosbag, ClearErrors) {
  const auto dir = scratch_dir();
  write_bag(dir / "office.bag", office_scans(1));
  ros_io::RosbagOptions options;
  options.topics = {"/velodyne_points"};
  try {
    (void)ros_io::open_rosbag(dir / "office.bag", options);
    ADD_FAILURE() << "opened";
  } catch (const FormatError& e) {
    EXPECT_TRUE(contains(e.what(), "no sensor_msgs/PointCloud2 topic '/velodyne_points'; its PointCloud2 topics: "
                                   "/other_points, /points"))
        << e.what();
  }
  options.topics = {"/points"};
  options.frame = "odom";
  try {
    (void)read_all(*ros_io::open_rosbag(dir / "office.bag", options));
    ADD_FAILURE() << "read";
  } catch (const FormatError& e) {
    EXPECT_TRUE(contains(e.what(), "no cloud could be moved into frame 'odom'")) << e.what();
    EXPECT_TRUE(contains(e.what(), "frames in the bag's TF: base_link, lidar, map")) << e.what();
  }
  write_file(dir / "not.bag", "#ROSBAG V2.0\nthis is not a bag");
  EXPECT_THROW((void)ros_io::open_rosbag(dir / "not.bag"), FormatError);
  EXPECT_THROW((void)ros_io::open_rosbag(dir / "missing.bag"), FormatError);

  // The CLI names the problem and exits with 1.
  const CommandResult result = run_command(std::string(UMBRA_CLI_PATH) + " build " + (dir / "office.bag").string() +
                                           " --topic /nothing -o " + (dir / "x.umb").string() + " 2>&1");
  EXPECT_EQ(result.exit_code, 1) << result.output;
  EXPECT_TRUE(contains(result.output, "no sensor_msgs/PointCloud2 topic '/nothing'")) << result.output;
}

}  // namespace
}  // namespace umbra::test
