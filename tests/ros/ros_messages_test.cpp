// umbra's ROS messages: the generated octomap_msgs types carry octomap_msgs'
// published names and md5sums (so RViz plugins and other nodes accept
// them), the regenerated Debian messages keep theirs, roscpp serialises
// them in C++20 with the wire layout ROS 1 defines (checked byte by byte for
// an Octomap message), and an Octomap message decodes to the map it was
// made from.
#include <octomap_msgs/BoundingBoxQuery.h>
#include <octomap_msgs/GetOctomap.h>
#include <octomap_msgs/Octomap.h>
#include <ros/serialization.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2_msgs/TFMessage.h>
#include <visualization_msgs/MarkerArray.h>

#include <cstring>

#include "map_messages.hpp"
#include "ros_test_support.hpp"

#include <gtest/gtest.h>

namespace umbra::test {
namespace {

namespace mt = ros::message_traits;
namespace st = ros::service_traits;

TEST(RosMessages, NamesAndMd5sumsAsPublished) {
  EXPECT_STREQ(mt::DataType<octomap_msgs::Octomap>::value(), "octomap_msgs/Octomap");
  EXPECT_STREQ(mt::MD5Sum<octomap_msgs::Octomap>::value(), "9a45536b45c5e409cd49f04bb2d9999f");
  EXPECT_STREQ(st::DataType<octomap_msgs::BoundingBoxQuery>::value(), "octomap_msgs/BoundingBoxQuery");
  EXPECT_STREQ(st::MD5Sum<octomap_msgs::BoundingBoxQuery>::value(), "93aa3d73b866f04880927745f4aab303");
  EXPECT_STREQ(st::DataType<octomap_msgs::GetOctomap>::value(), "octomap_msgs/GetOctomap");
  EXPECT_STREQ(st::MD5Sum<octomap_msgs::GetOctomap>::value(), "be9d2869d24fe40d6bc21ac21f6bb2c5");
  // Debian's messages, generated again for C++20, keep their identity.
  EXPECT_STREQ(mt::MD5Sum<sensor_msgs::PointCloud2>::value(), "1158d486dd51d683ce2f1be655c3c181");
  EXPECT_STREQ(mt::MD5Sum<tf2_msgs::TFMessage>::value(), "94810edda583a504dfda3829e70d7eec");
}

template <typename M>
std::vector<std::uint8_t> serialize(const M& message) {
  std::vector<std::uint8_t> bytes(ros::serialization::serializationLength(message));
  ros::serialization::OStream out(bytes.data(), static_cast<std::uint32_t>(bytes.size()));
  ros::serialization::serialize(out, message);
  return bytes;
}

template <typename M>
M deserialize(std::vector<std::uint8_t> bytes) {
  M message;
  ros::serialization::IStream in(bytes.data(), static_cast<std::uint32_t>(bytes.size()));
  ros::serialization::deserialize(in, message);
  return message;
}

void append_u32(std::vector<std::uint8_t>& out, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) out.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
}
void append_string(std::vector<std::uint8_t>& out, const std::string& s) {
  append_u32(out, static_cast<std::uint32_t>(s.size()));
  out.insert(out.end(), s.begin(), s.end());
}

TEST(RosMessages, OctomapWireLayout) {
  octomap_msgs::Octomap message;
  message.header.seq = 7;
  message.header.stamp = ros::Time(12, 345);
  message.header.frame_id = "map";
  message.binary = true;
  message.id = "OcTree";
  message.resolution = 0.25;
  message.data = {1, -2, 3};
  // ROS 1: header (seq, secs, nsecs, frame_id), bool as one byte, strings and arrays with a uint32 length.
  std::vector<std::uint8_t> expected;
  append_u32(expected, 7);
  append_u32(expected, 12);
  append_u32(expected, 345);
  append_string(expected, "map");
  expected.push_back(1);
  append_string(expected, "OcTree");
  const double resolution = 0.25;
  std::uint8_t bits[8];
  std::memcpy(bits, &resolution, 8);
  expected.insert(expected.end(), bits, bits + 8);
  append_u32(expected, 3);
  expected.insert(expected.end(), {1, 0xFE, 3});
  EXPECT_EQ(serialize(message), expected);
  const auto back = deserialize<octomap_msgs::Octomap>(expected);
  EXPECT_EQ(back.header.frame_id, "map");
  EXPECT_EQ(back.id, "OcTree");
  EXPECT_EQ(back.data, message.data);
}

TEST(RosMessages, CloudsMarkersAndTransformsRoundTrip) {
  const std::vector<RosScan> scans = office_scans(1);
  const sensor_msgs::PointCloud2 cloud = to_cloud(scans[0], "lidar", ros::Time(5, 0));
  const auto cloud_back = deserialize<sensor_msgs::PointCloud2>(serialize(cloud));
  EXPECT_EQ(cloud_back.data, cloud.data);
  ASSERT_EQ(cloud_back.fields.size(), cloud.fields.size());
  EXPECT_EQ(cloud_back.fields[3].name, "intensity");
  EXPECT_EQ(cloud_back.row_step, cloud.row_step);

  tf2_msgs::TFMessage tf;
  tf.transforms.push_back(to_transform(scans[0], "map", "lidar", ros::Time(5, 0)));
  const auto tf_back = deserialize<tf2_msgs::TFMessage>(serialize(tf));
  ASSERT_EQ(tf_back.transforms.size(), 1u);
  EXPECT_EQ(tf_back.transforms[0].child_frame_id, "lidar");
  EXPECT_EQ(tf_back.transforms[0].transform.rotation.z, tf.transforms[0].transform.rotation.z);

  const OccupancyMap map = reference_map(scans, 0.2);
  const ros_io::CellMessages cells = ros_io::cell_messages(map, {}, "map", ros::Time(5, 0));
  const auto markers_back = deserialize<visualization_msgs::MarkerArray>(serialize(cells.occupied));
  ASSERT_EQ(markers_back.markers.size(), 17u);
  for (std::size_t i = 0; i < 17; ++i) {
    EXPECT_EQ(markers_back.markers[i].points.size(), cells.occupied.markers[i].points.size());
    EXPECT_EQ(markers_back.markers[i].colors.size(), cells.occupied.markers[i].colors.size());
  }
}

TEST(RosMessages, OctomapMessagesHoldTheMap) {
  const OccupancyMap map = reference_map(office_scans(2), 0.1);
  for (const OctoMapFormat format : {OctoMapFormat::bt, OctoMapFormat::ot}) {
    const octomap_msgs::Octomap message = ros_io::octomap_message(map, format, "map", ros::Time(3, 0));
    EXPECT_EQ(message.binary, format == OctoMapFormat::bt);
    EXPECT_EQ(message.id, "OcTree");
    EXPECT_EQ(message.resolution, 0.1);
    EXPECT_EQ(message.header.frame_id, "map");
    const std::vector<std::uint8_t> data(message.data.begin(), message.data.end());
    EXPECT_EQ(data, tree_bytes(map, format));
    // Back through ROS's own serialisation, then decoded: the same tree.
    const OccupancyMap back = ros_io::map_from_message(deserialize<octomap_msgs::Octomap>(serialize(message)));
    EXPECT_EQ(tree_bytes(back, format), tree_bytes(map, format));
  }
  octomap_msgs::Octomap bad = ros_io::octomap_message(map, OctoMapFormat::ot, "map", ros::Time(3, 0));
  bad.data.pop_back();
  EXPECT_THROW((void)ros_io::map_from_message(bad), FormatError);
}

TEST(RosMessages, CellMarkersListTheOccupiedLeaves) {
  const OccupancyMap map = reference_map(office_scans(2), 0.1);
  ros_io::CellStyle style;
  style.free_cells = true;
  style.min_z = 0.3;
  style.max_z = 2.0;
  const ros_io::CellMessages cells = ros_io::cell_messages(map, style, "map", ros::Time(1, 0));
  std::vector<std::size_t> occupied(17, 0);
  std::vector<std::size_t> free(17, 0);
  map.for_each_leaf([&](const Node& leaf) {
    if (!(leaf.center.z > 0.3 && leaf.center.z < 2.0)) return;
    if (leaf.state == OccupancyState::occupied) ++occupied[static_cast<std::size_t>(16 - leaf.depth)];
    if (leaf.state == OccupancyState::free) ++free[static_cast<std::size_t>(16 - leaf.depth)];
  });
  std::size_t total = 0;
  for (std::size_t i = 0; i < 17; ++i) {
    const auto& marker = cells.occupied.markers[i];
    EXPECT_EQ(marker.points.size(), occupied[i]) << "depth " << i;
    EXPECT_EQ(marker.colors.size(), occupied[i]) << "depth " << i;
    EXPECT_EQ(marker.action, occupied[i] > 0 ? visualization_msgs::Marker::ADD : visualization_msgs::Marker::DELETE);
    EXPECT_DOUBLE_EQ(marker.scale.x, map.grid().node_size(16 - static_cast<int>(i)));
    EXPECT_EQ(cells.free.markers[i].points.size(), free[i]) << "depth " << i;
    for (const auto& p : marker.points) EXPECT_TRUE(p.z > 0.3 && p.z < 2.0);
    total += occupied[i];
  }
  EXPECT_GT(total, 100u);
  EXPECT_GT(free[16], 100u);
  EXPECT_EQ(cells.centers.width, total);
  EXPECT_EQ(cells.centers.data.size(), total * 12);
}

}  // namespace
}  // namespace umbra::test
