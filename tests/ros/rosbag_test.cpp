// The .bag scan source (ros/include/umbra_ros/rosbag_source.hpp) and
// `umbra build` on a bag. Most tests write their bag with rosbag itself, in
// each compression: the simulated office's scans as PointCloud2 in a sensor
// frame, the sensor pose on /tf (map -> base_link) and a static mount on
// /tf_static (base_link -> lidar). The map read from the bag must equal, bit
// for bit, the map the library builds from the simulator's points directly.
// umbra's reader and librosbag must see the same messages in the bags of
// both writers (bag_writer.cpp's and rosbag's). Then hostile bags (issue
// 21): a PointCloud2 connection of another md5sum, every byte of a small bag
// flipped, absurd stamps and transforms: a FormatError naming the file and
// byte offset, or scans, never a crash.
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <tf2_msgs/TFMessage.h>

#include <fstream>
#include <set>
#include <string>
#include <tuple>

#include "bag_writer.hpp"
#include "ros_test_support.hpp"
#include "support/test_support.hpp"
#include "umbra/core/memory_limit.hpp"
#include "umbra/io/map_file.hpp"
#include "umbra_ros/bag_file.hpp"
#include "umbra_ros/rosbag_source.hpp"

#include <gtest/gtest.h>

#include <cstring>

namespace umbra::test {
namespace {

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

ros::Time scan_time(std::size_t i) { return ros::Time(100.0 + 0.5 * static_cast<double>(i)); }

namespace fs = std::filesystem;

const std::vector<std::pair<std::string, rosbag::CompressionType>> kCompressions{
    {"none", rosbag::compression::Uncompressed}, {"bz2", rosbag::compression::BZ2}, {"lz4", rosbag::compression::LZ4}};

void write_bytes(const fs::path& path, const std::vector<std::uint8_t>& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
}

/// Writes the scans to `path`; the first `early` clouds come before any transform.
void write_bag(const std::filesystem::path& path, const std::vector<RosScan>& scans, std::size_t early = 0,
               rosbag::CompressionType compression = rosbag::compression::Uncompressed) {
  rosbag::Bag bag(path.string(), rosbag::bagmode::Write);
  bag.setCompression(compression);
  bag.setChunkThreshold(64 * 1024);  // several chunks
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

// Once ros/ registers its reader, open_scan_source reads .bag files with
// ScanSourceOptions::topics and ::frame: the same scans as open_rosbag.
TEST(Rosbag, RegisteredReaderIsWhatOpenScanSourceUses) {
  const std::vector<RosScan> scans = office_scans(2);
  const auto dir = scratch_dir();
  write_bag(dir / "office.bag", scans, 1, kCompressions[0].second);
  ros_io::register_rosbag_format();
  for (const std::string topic : {"/points", "/other_points"}) {
    ScanSourceOptions options;
    options.topics = {topic};
    options.frame = "map";
    const auto registered = open_scan_source(dir / "office.bag", options);
    const auto direct = ros_io::open_rosbag(dir / "office.bag", ros_io::RosbagOptions{{topic}, "map"});
    Scan a;
    Scan b;
    std::size_t count = 0;
    while (direct->next(b)) {
      ASSERT_TRUE(registered->next(a));
      // Bit for bit (the simulated clouds hold NaN points, which == would call different).
      ASSERT_EQ(a.points.size(), b.points.size());
      EXPECT_EQ(std::memcmp(a.points.data(), b.points.data(), a.points.size() * sizeof(Vec3f)), 0);
      EXPECT_EQ(a.origin, b.origin);
      ++count;
    }
    EXPECT_FALSE(registered->next(a));
    EXPECT_GT(count, 0u) << topic;
  }
}

TEST(Rosbag, ScansEqualTheSimulatorsPoints) {
  const std::vector<RosScan> scans = office_scans(4);
  const OccupancyMap reference = reference_map(scans, 0.1);
  for (const auto& [compression_name, compression] : kCompressions) {
    SCOPED_TRACE(compression_name);
    const auto dir = scratch_dir();
    write_bag(dir / "office.bag", scans, 1, compression);
    ros_io::RosbagOptions options;
    options.topics = {"/points"};
    const auto source = ros_io::open_rosbag(dir / "office.bag", options);
    OccupancyMap map(0.1);
    Scan scan;
    std::size_t count = 0;
    while (source->next(scan)) {
      ASSERT_LT(count, scans.size());
      EXPECT_EQ(scan.origin, Vec3f(scans[count].position));
      ASSERT_TRUE(scan.stamp.has_value());  // the cloud's header.stamp, for decay
      EXPECT_DOUBLE_EQ(*scan.stamp, scan_time(count).toSec());
      EXPECT_TRUE(contains(scan.name, "office.bag message " + std::to_string(count + 2) + " on /points")) << scan.name;
      map.insert_point_cloud(scan.origin, scan.points);
      ++count;
    }
    EXPECT_EQ(count, scans.size());
    EXPECT_EQ(source->skipped_clouds(), 1u);  // the cloud before every transform
    EXPECT_TRUE(contains(source->first_skip_reason(), "message 1 on /points")) << source->first_skip_reason();
    EXPECT_DOUBLE_EQ(source->progress(), 1.0);
    EXPECT_EQ(tree_bytes(map, OctoMapFormat::ot), tree_bytes(reference, OctoMapFormat::ot));
  }
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

/// (topic, time, serialized bytes) of every message.
using MessageKey = std::tuple<std::string, std::uint64_t, std::vector<std::uint8_t>>;

std::multiset<MessageKey> librosbag_messages(const fs::path& path) {
  rosbag::Bag bag(path.string(), rosbag::bagmode::Read);
  rosbag::View view(bag);
  std::multiset<MessageKey> messages;
  for (const rosbag::MessageInstance& m : view) {
    std::vector<std::uint8_t> bytes(m.size());
    ros::serialization::OStream stream(bytes.data(), static_cast<std::uint32_t>(bytes.size()));
    m.write(stream);
    messages.insert({m.getTopic(), std::uint64_t{m.getTime().sec} << 32 | m.getTime().nsec, bytes});
  }
  return messages;
}

std::multiset<MessageKey> umbra_messages(const fs::path& path) {
  ros_io::BagFile bag(path);
  std::multiset<MessageKey> messages;
  for (const ros_io::BagMessage& m : bag.messages([](const ros_io::BagConnection&) { return true; })) {
    const std::span<const std::uint8_t> bytes = bag.read(m);
    messages.insert({bag.connections()[m.connection].topic, m.time.packed(), {bytes.begin(), bytes.end()}});
  }
  return messages;
}

TEST(Rosbag, UmbraAndLibrosbagReadTheSameMessages) {
  const auto dir = scratch_dir();
  for (const auto& [name, compression] : kCompressions) {
    SCOPED_TRACE(name);
    // The test generator's bag ...
    write_bytes(dir / "small.bag", small_bag(name).bytes);
    const std::multiset<MessageKey> generated = librosbag_messages(dir / "small.bag");
    EXPECT_EQ(generated.size(), 11u);
    EXPECT_EQ(umbra_messages(dir / "small.bag"), generated);
    // ... and rosbag's.
    write_bag(dir / "office.bag", office_scans(2), 1, compression);
    const std::multiset<MessageKey> written = librosbag_messages(dir / "office.bag");
    EXPECT_EQ(written.size(), 7u);
    EXPECT_EQ(umbra_messages(dir / "office.bag"), written);
  }
}

TEST(Rosbag, GeneratedBagsOfEveryCompressionGiveTheirPoints) {
  const auto dir = scratch_dir();
  const std::vector<ExpectedScan> expected = small_bag_points();
  for (const auto& [name, compression] : kCompressions) {
    SCOPED_TRACE(name);
    write_bytes(dir / "small.bag", small_bag(name).bytes);
    const std::vector<Scan> scans = read_all(*ros_io::open_rosbag(dir / "small.bag"));
    ASSERT_EQ(scans.size(), expected.size());
    for (std::size_t i = 0; i < scans.size(); ++i) {
      EXPECT_TRUE(contains(scans[i].name, "small.bag message " + std::to_string(i + 1) + " on " + expected[i].topic))
          << scans[i].name;
      EXPECT_EQ(scans[i].points, expected[i].points) << "scan " << i;
      ASSERT_EQ(scans[i].colors.size(), scans[i].points.size());
      EXPECT_EQ(scans[i].colors[1], (Rgb{0x10, 0x20, 0x31}));
    }
    // Colors not asked for: none decoded.
    ros_io::RosbagOptions options;
    options.colors = false;
    EXPECT_TRUE(read_all(*ros_io::open_rosbag(dir / "small.bag", options)).front().colors.empty());
  }
}

// Issue 21, item 2: a PointCloud2 connection with another md5sum (another version of the message). librosbag's
// source read a freed MessageInstance here; now it is refused, naming the connection and its byte.
TEST(Rosbag, AnotherVersionOfPointCloud2IsRefused) {
  const auto dir = scratch_dir();
  write_bag(dir / "office.bag", office_scans(2));
  std::vector<std::uint8_t> bytes = read_bytes(dir / "office.bag");
  const std::string from = kCloudMd5;
  const std::string to = "0000d486dd51d683ce2f1be655c3c181";
  std::size_t replaced = 0;
  for (auto at = std::search(bytes.begin(), bytes.end(), from.begin(), from.end()); at != bytes.end();
       at = std::search(at, bytes.end(), from.begin(), from.end())) {
    at = std::copy(to.begin(), to.end(), at);
    ++replaced;
  }
  ASSERT_GE(replaced, 2u);  // in the chunk and in the index
  write_bytes(dir / "md5.bag", bytes);
  std::string error;
  try {
    (void)read_all(*ros_io::open_rosbag(dir / "md5.bag"));
  } catch (const FormatError& e) {
    error = e.what();
  }
  const std::string expected = "is sensor_msgs/PointCloud2 with md5sum '" + to + "', not " + from +
                               ": another version of the message, which umbra cannot read";
  EXPECT_TRUE(contains(error, (dir / "md5.bag").string() + ": byte ")) << error;
  EXPECT_TRUE(contains(error, expected)) << error;
  // The reproduction of the issue: `umbra build md5.bag -o x.umb`.
  const CommandResult result = run_command(std::string(UMBRA_CLI_PATH) + " build " + (dir / "md5.bag").string() +
                                           " -o " + (dir / "x.umb").string() + " 2>&1");
  EXPECT_EQ(result.exit_code, 1) << result.output;
  EXPECT_TRUE(contains(result.output, expected)) << result.output;
}

/// Reads every scan of a possibly corrupt bag: true when it read, false for a FormatError or MemoryLimitError
/// naming the file; anything else fails the test.
bool read_or_refuse(const fs::path& path, const std::string& what, std::string* error = nullptr) {
  try {
    (void)read_all(*ros_io::open_rosbag(path));
    return true;
  } catch (const FormatError& e) {
    EXPECT_EQ(std::string(e.what()).rfind(path.string() + ": ", 0), 0u) << what << ": " << e.what();
    if (error != nullptr) *error = e.what();
  } catch (const MemoryLimitError& e) {
    EXPECT_EQ(std::string(e.what()).rfind(path.string() + ": ", 0), 0u) << what << ": " << e.what();
    if (error != nullptr) *error = e.what();
  } catch (const std::exception& e) {
    ADD_FAILURE() << what << ": an exception other than FormatError: " << e.what();
  }
  return false;
}

// Issue 21, item 3, through the whole scan source (transforms into tf2 included): every byte of a small bag
// flipped, in each compression.
TEST(Rosbag, EveryByteFlippedGivesScansOrAFormatError) {
  const auto dir = scratch_dir();
  std::size_t refused = 0;
  std::size_t cases = 0;
  for (const auto& [name, compression] : kCompressions) {
    const WrittenBag bag = small_bag(name);
    const WrittenRecord& header = bag.records.front();
    for (std::size_t at = 0; at < bag.bytes.size(); ++at) {
      if (at >= header.data_byte && at < header.data_byte + header.data_size) continue;  // padding: not read
      std::vector<std::uint8_t> bytes = bag.bytes;
      bytes[at] ^= 0xff;
      const fs::path path = dir / ("flip-" + name + "-" + std::to_string(at) + ".bag");
      write_bytes(path, bytes);
      refused += read_or_refuse(path, name + " byte " + std::to_string(at) + " flipped") ? 0 : 1;
      ++cases;
      fs::remove(path);
    }
  }
  EXPECT_GT(refused, cases / 2);
}

/// A bag of small_bag's layout with the given transforms (on /tf) and clouds (on /points, frame lidar).
WrittenBag transforms_and_clouds(const std::vector<TestTransform>& transforms, const std::vector<TestCloud>& clouds) {
  const std::vector<TestConnection> connections{{"/tf", "tf2_msgs/TFMessage", kTfMd5},
                                                {"/points", "sensor_msgs/PointCloud2", kCloudMd5}};
  std::vector<TestMessage> messages;
  for (const TestTransform& t : transforms) messages.push_back({0, t.sec, 0, serialize_tf({t})});
  for (const TestCloud& c : clouds) messages.push_back({1, c.sec, 0, serialize_cloud(c)});
  return write_test_bag(connections, messages, "none");
}

TEST(Rosbag, AbsurdStampsAndTransformsGiveScansOrAFormatError) {
  const auto dir = scratch_dir();
  const fs::path path = dir / "stamps.bag";
  const std::vector<Vec3f> points{{1.0f, 2.0f, 0.5f}};
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const auto transform = [](std::uint32_t sec, std::uint32_t nsec, std::array<double, 3> t, std::array<double, 4> q) {
    return TestTransform{"map", "lidar", sec, nsec, t, q};
  };
  const auto cloud = [&](std::uint32_t sec, std::uint32_t nsec) {
    TestCloud c = xyz_rgb_cloud("lidar", sec, points);
    c.nsec = nsec;
    return c;
  };
  std::string error;
  // Nanoseconds of 10^9 or more in the cloud's stamp.
  write_bytes(path, transforms_and_clouds({transform(10, 0, {}, {0, 0, 0, 1})}, {cloud(10, 1500000000)}).bytes);
  EXPECT_FALSE(read_or_refuse(path, "nsec", &error));
  EXPECT_TRUE(contains(error, "message 1 on /points: header.stamp has 1500000000 nanoseconds, not below 10^9")) << error;
  // A NaN translation and a zero quaternion: tf2 refuses them, so no cloud has a transform.
  write_bytes(path, transforms_and_clouds({transform(10, 0, {nan, 0, 0}, {0, 0, 0, 1}), transform(11, 0, {}, {0, 0, 0, 0})},
                                          {cloud(10, 0), cloud(11, 0)})
                        .bytes);
  EXPECT_FALSE(read_or_refuse(path, "NaN", &error));
  EXPECT_TRUE(contains(error, "no cloud could be moved into frame 'map'")) << error;
  const std::vector<std::string> warnings = ros_io::open_rosbag(path)->warnings();
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_TRUE(contains(warnings[0], "tf2 refused 2 of the bag's 2 transforms (first: TF_NAN_INPUT")) << warnings[0];
  // Stamps at both ends of ROS time: the transforms' span does not fit tf2's cache arithmetic.
  const std::uint32_t last = std::numeric_limits<std::uint32_t>::max();
  write_bytes(path, transforms_and_clouds({transform(0, 1, {1, 0, 0}, {0, 0, 0, 1}), transform(last, 999999999, {2, 0, 0}, {0, 0, 0, 1})},
                                          {cloud(0, 1), cloud(last / 2, 0), cloud(last, 999999999)})
                        .bytes);
  (void)read_or_refuse(path, "stamps at the ends of time");
  // The transform exactly at the cloud's stamp, at the last second of ROS time: read.
  write_bytes(path, transforms_and_clouds({transform(last, 0, {1, 0, 0}, {0, 0, 0, 1})}, {cloud(last, 0)}).bytes);
  EXPECT_TRUE(read_or_refuse(path, "the last second"));
}

}  // namespace
}  // namespace umbra::test
