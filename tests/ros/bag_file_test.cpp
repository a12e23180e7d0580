// umbra's reader of ROS bags (ros/include/umbra_ros/bag_file.hpp) and of the
// PointCloud2 / TFMessage wire format (serialized_messages.hpp), without ROS.
//
// Valid bags come from the generator in bag_writer.cpp, in every compression
// the reader supports: every message must come back byte for byte, in time
// order. Then the same bags corrupted: every record's lengths, the index
// offsets, the chunk sizes and a message's length set to hostile values, the
// file cut at every length, and every byte flipped. Reading each (the
// structure, every message, and every cloud and transform parsed and
// decoded) must either succeed or throw a FormatError that names the file
// and a byte offset (a MemoryLimitError where a chunk asks for more than the
// limit); a crash or any other exception fails the test. The librosbag
// crashes of issue 21 are among these cases (index offset 0xFFFFFFFF,
// lengths of 0xFFFFFFFF, a message length of 0x7FFFFFFF).
#include <fcntl.h>
#include <unistd.h>

#include <map>
#include <string>

#include "bag_writer.hpp"
#include "support/test_support.hpp"
#include "umbra/core/memory_limit.hpp"
#include "umbra_ros/bag_file.hpp"
#include "umbra_ros/serialized_messages.hpp"

#include <gtest/gtest.h>

namespace umbra::test {
namespace {

namespace fs = std::filesystem;
using ros_io::BagConnection;
using ros_io::BagFile;
using ros_io::BagMessage;

const std::vector<std::string> kCompressions{"none", "bz2", "lz4"};

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

/// Replaces the file's content. Written in place (pwrite, then ftruncate to the new length), never through
/// O_TRUNC: ext4 flushes a file truncated to 0 to disk when it is closed, which for thousands of cases takes
/// seconds.
void write_bytes(const fs::path& path, const std::vector<std::uint8_t>& bytes) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_CLOEXEC, 0600);
  ASSERT_GE(fd, 0) << path;
  ASSERT_EQ(::pwrite(fd, bytes.data(), bytes.size(), 0), static_cast<ssize_t>(bytes.size()));
  ASSERT_EQ(::ftruncate(fd, static_cast<off_t>(bytes.size())), 0);
  ::close(fd);
}

void set_u32(std::vector<std::uint8_t>& bytes, std::uint64_t at, std::uint32_t value) {
  for (int i = 0; i < 4; ++i) bytes[at + i] = static_cast<std::uint8_t>(value >> (8 * i));
}
std::uint32_t get_u32(const std::vector<std::uint8_t>& bytes, std::uint64_t at) {
  std::uint32_t value = 0;
  for (int i = 3; i >= 0; --i) value = (value << 8) | bytes[at + i];
  return value;
}

/// Reads everything umbra would read from the bag: every message, clouds and transforms parsed, clouds
/// decoded. Returns the number of messages; throws what the reader throws.
std::size_t read_everything(const fs::path& path) {
  BagFile bag(path);
  std::size_t count = 0;
  ros_io::DecodedCloud decoded;
  for (const BagMessage& message : bag.messages([](const BagConnection&) { return true; })) {
    const BagConnection& connection = bag.connections()[message.connection];
    const std::span<const std::uint8_t> bytes = bag.read(message);
    try {
      if (connection.md5sum == ros_io::kPointCloud2Md5) {
        const ros_io::SerializedCloud cloud = ros_io::parse_point_cloud2(bytes, "cloud");
        ros_io::decode_point_cloud2(cloud.cloud, {}, true, decoded, "cloud");
      } else if (connection.md5sum == ros_io::kTfMessageMd5) {
        (void)ros_io::parse_tf_message(bytes, "transforms");
      }
    } catch (const FormatError& e) {
      throw bag.error(message, e.what());
    }
    ++count;
  }
  return count;
}

/// What reading a (possibly corrupt) bag gave.
struct Outcome {
  bool read = false;       ///< no exception
  std::string error;       ///< what() of the FormatError or MemoryLimitError
  std::size_t messages = 0;
};

/// Reads `bytes` as a bag; fails the test for anything but success, a FormatError naming the file and a byte
/// offset, or a MemoryLimitError naming the file. `what` says which corruption, for the failure message.
Outcome read_corrupt(const fs::path& path, const std::vector<std::uint8_t>& bytes, const std::string& what) {
  write_bytes(path, bytes);
  Outcome outcome;
  try {
    outcome.messages = read_everything(path);
    outcome.read = true;
  } catch (const FormatError& e) {
    outcome.error = e.what();
    EXPECT_EQ(outcome.error.rfind(path.string() + ": byte ", 0), 0u) << what << ": " << outcome.error;
  } catch (const MemoryLimitError& e) {
    outcome.error = e.what();
    EXPECT_EQ(outcome.error.rfind(path.string() + ": ", 0), 0u) << what << ": " << outcome.error;
  } catch (const std::exception& e) {
    ADD_FAILURE() << what << ": an exception other than FormatError: " << e.what();
  }
  return outcome;
}

TEST(BagFile, ReadsEveryMessageTheWriterWroteInTimeOrder) {
  const auto dir = scratch_dir();
  for (const std::string& compression : kCompressions) {
    SCOPED_TRACE(compression);
    const WrittenBag written = small_bag(compression, 300);
    EXPECT_GE(written.with_op(0x05).size(), 3u);  // several chunks
    write_bytes(dir / "small.bag", written.bytes);
    BagFile bag(dir / "small.bag");
    ASSERT_EQ(bag.connections().size(), 5u);
    EXPECT_EQ(bag.connections()[2].topic, "/points");
    EXPECT_EQ(bag.connections()[2].type, "sensor_msgs/PointCloud2");
    EXPECT_EQ(bag.connections()[2].md5sum, kCloudMd5);
    // Every message record's data, as written, by connection and time.
    std::multimap<std::pair<std::uint32_t, std::uint64_t>, std::vector<std::uint8_t>> expected;
    {
      // Rebuild the messages small_bag wrote from an uncompressed copy: its in-chunk records are listed.
      const WrittenBag plain = small_bag("none", 300);
      for (const WrittenRecord& r : plain.with_op(0x02)) {
        const std::uint32_t conn = get_u32(plain.bytes, r.fields.at("conn"));
        const std::uint64_t time = std::uint64_t{get_u32(plain.bytes, r.fields.at("time"))} << 32 |
                                   get_u32(plain.bytes, r.fields.at("time") + 4);
        expected.emplace(std::pair{conn, time},
                         std::vector<std::uint8_t>(plain.bytes.begin() + static_cast<std::ptrdiff_t>(r.data_byte),
                                                   plain.bytes.begin() + static_cast<std::ptrdiff_t>(r.data_byte + r.data_size)));
      }
    }
    const std::vector<BagMessage> all = bag.messages([](const BagConnection&) { return true; });
    ASSERT_EQ(all.size(), expected.size());
    for (std::size_t i = 0; i < all.size(); ++i) {
      if (i > 0) {
        EXPECT_FALSE(all[i].time < all[i - 1].time) << "message " << i << " out of time order";
      }
      const std::span<const std::uint8_t> bytes = bag.read(all[i]);
      const auto found = expected.find({bag.connections()[all[i].connection].id, all[i].time.packed()});
      ASSERT_NE(found, expected.end()) << "message " << i;
      EXPECT_EQ(std::vector<std::uint8_t>(bytes.begin(), bytes.end()), found->second) << "message " << i;
    }
    // Only the clouds on /points, and their content.
    const std::vector<BagMessage> clouds = bag.messages([](const BagConnection& c) { return c.topic == "/points"; });
    ASSERT_EQ(clouds.size(), 3u);
    const ros_io::SerializedCloud cloud = ros_io::parse_point_cloud2(bag.read(clouds[1]), "cloud");
    EXPECT_EQ(cloud.header.frame_id, "lidar");
    EXPECT_EQ(cloud.header.stamp_sec, 11u);
    EXPECT_EQ(cloud.cloud.width, 3u);
    EXPECT_EQ(cloud.cloud.fields.size(), 4u);
    EXPECT_EQ(cloud.cloud.point_step, 16u);
  }
}

TEST(BagFile, TransformMessagesParse) {
  TestTransform t{"map", "base_link", 7, 5, {1.5, -2.0, 0.25}, {0.0, 0.0, 0.6, 0.8}};
  const std::vector<std::uint8_t> bytes = serialize_tf({t, t});
  const std::vector<ros_io::SerializedTransform> parsed = ros_io::parse_tf_message(bytes, "tf");
  ASSERT_EQ(parsed.size(), 2u);
  EXPECT_EQ(parsed[1].header.frame_id, "map");
  EXPECT_EQ(parsed[1].child_frame_id, "base_link");
  EXPECT_EQ(parsed[1].header.stamp_nsec, 5u);
  EXPECT_EQ(parsed[1].translation, t.translation);
  EXPECT_EQ(parsed[1].rotation, t.rotation);
  // A count past the end, and a byte too many.
  std::vector<std::uint8_t> lying = bytes;
  set_u32(lying, 0, 0x7fffffff);
  try {
    (void)ros_io::parse_tf_message(lying, "tf");
    ADD_FAILURE() << "parsed";
  } catch (const FormatError& e) {
    EXPECT_TRUE(contains(e.what(), "tf: tf2_msgs/TFMessage message of " + std::to_string(bytes.size()) +
                                       " bytes, at byte 0: transforms counts 2147483647 elements"))
        << e.what();
  }
  std::vector<std::uint8_t> longer = bytes;
  longer.push_back(0);
  EXPECT_THROW((void)ros_io::parse_tf_message(longer, "tf"), FormatError);
}

TEST(BagFile, NamedErrorsForTheCrashesOfLibrosbag) {
  const auto dir = scratch_dir();
  const fs::path path = dir / "bad.bag";
  const auto expect_error = [&](const std::vector<std::uint8_t>& bytes, const std::string& part) {
    const Outcome outcome = read_corrupt(path, bytes, part);
    EXPECT_FALSE(outcome.read) << part;
    EXPECT_TRUE(contains(outcome.error, part)) << outcome.error;
  };
  for (const std::string& compression : kCompressions) {
    SCOPED_TRACE(compression);
    const WrittenBag bag = small_bag(compression);
    // An index entry's offset of 0xFFFFFFFF (librosbag: a segfault in readHeaderFromBuffer).
    const WrittenRecord index = bag.with_op(0x04).front();
    std::vector<std::uint8_t> bytes = bag.bytes;
    set_u32(bytes, index.data_byte + 8, 0xffffffffu);
    expect_error(bytes, path.string() + ": byte " + std::to_string(index.data_byte + 8) +
                            ": index entry 0 of connection " + std::to_string(get_u32(bag.bytes, index.fields.at("conn"))) +
                            " points at offset 4294967295, past the end of its chunk");
    // A record's header length of 0xFFFFFFFF (librosbag: Buffer::ensureCapacity asks for 4 GiB).
    const WrittenRecord chunk = bag.with_op(0x05).front();
    bytes = bag.bytes;
    set_u32(bytes, chunk.byte, 0xffffffffu);
    expect_error(bytes, path.string() + ": byte " + std::to_string(chunk.byte) + ": the record's header (4294967295 bytes");
    // Its data length.
    bytes = bag.bytes;
    set_u32(bytes, chunk.data_length_byte, 0xffffffffu);
    expect_error(bytes, path.string() + ": byte " + std::to_string(chunk.byte) + ": the record's data (4294967295 bytes");
    // A chunk declaring 4 GiB decompressed.
    bytes = bag.bytes;
    set_u32(bytes, chunk.fields.at("size"), 0xffffffffu);
    if (compression == "none") {
      expect_error(bytes, "the uncompressed chunk declares 4294967295 bytes but holds " + std::to_string(chunk.data_size));
    } else {
      set_memory_limit(std::uint64_t{64} << 20);
      write_bytes(path, bytes);
      EXPECT_THROW((void)read_everything(path), MemoryLimitError);
      set_memory_limit(std::uint64_t{16} << 30);  // allowed: then only what the data holds is allocated
      expect_error(bytes, "chunk decompresses to " + std::to_string(get_u32(bag.bytes, chunk.fields.at("size"))) +
                              " bytes, but its header declares 4294967295");
      set_memory_limit(0);
    }
  }
  // A message length of 0x7FFFFFFF inside a chunk (librosbag: 2.1 GB allocated, then "Buffer Overrun").
  const WrittenBag bag = small_bag("none");
  const WrittenRecord message = bag.with_op(0x02).front();
  std::vector<std::uint8_t> bytes = bag.bytes;
  set_u32(bytes, message.data_length_byte, 0x7fffffffu);
  set_memory_limit(std::uint64_t{1} << 20);  // nothing of that size may be allocated
  expect_error(bytes, path.string() + ": byte " + std::to_string(message.data_length_byte + 4) +
                          ": the record's data needs 2147483647 bytes, but the chunk has");
  set_memory_limit(0);
  // Two index entries for the same message.
  bytes = bag.bytes;
  const WrittenRecord index = bag.with_op(0x04).front();
  ASSERT_GE(get_u32(bag.bytes, index.fields.at("count")), 1u);
  const WrittenRecord other = bag.with_op(0x04)[1];
  set_u32(bytes, other.data_byte + 8, get_u32(bag.bytes, index.data_byte + 8));
  expect_error(bytes, "two index entries point at the same message");
}

TEST(BagFile, OtherBagsAndFilesAreNamed) {
  const auto dir = scratch_dir();
  const fs::path path = dir / "x.bag";
  const auto error_of = [&](const std::string& text) {
    write_file(path, text);
    try {
      BagFile bag(path);
    } catch (const FormatError& e) {
      return std::string(e.what());
    }
    return std::string("(opened)");
  };
  EXPECT_EQ(error_of("#ROSBAG V1.2\nold"), path.string() + ": byte 0: ROS bag format '1.2' is not read (only format 2.0, "
                                                           "written by ROS since 2010)");
  EXPECT_EQ(error_of("PK\3\4 a zip"), path.string() + ": byte 0: not a ROS bag: the file does not start with '#ROSBAG V2.0'");
  EXPECT_EQ(error_of(""), path.string() + ": byte 0: not a ROS bag: the file does not start with '#ROSBAG V2.0'");
  // An unindexed bag (index_pos 0), and an encrypted one.
  WrittenBag bag = small_bag("none");
  const WrittenRecord header = bag.records.front();
  std::vector<std::uint8_t> bytes = bag.bytes;
  for (int i = 0; i < 8; ++i) bytes[header.fields.at("index_pos") + i] = 0;
  const Outcome unindexed = read_corrupt(path, bytes, "index_pos 0");
  EXPECT_TRUE(contains(unindexed.error, "byte 13: the bag has no index (index_pos 0: its recording was not closed); "
                                        "run 'rosbag reindex' on it first"))
      << unindexed.error;
  EXPECT_THROW(BagFile(dir / "missing.bag"), std::runtime_error);
}

/// Every hostile value in every length field of every record, and in every index offset.
TEST(BagFile, HostileLengthsAndOffsetsGiveFormatErrors) {
  const auto dir = scratch_dir();
  const fs::path path = dir / "mutated.bag";
  std::size_t cases = 0;
  std::size_t refused = 0;
  for (const std::string& compression : kCompressions) {
    const WrittenBag bag = small_bag(compression);
    std::vector<std::pair<std::uint64_t, std::string>> places;  // (file offset of a u32, what it is)
    for (const WrittenRecord& r : bag.records) {
      const std::string name = "record at byte " + std::to_string(r.byte) + " (op " + std::to_string(r.op) + ")";
      places.emplace_back(r.byte, name + " header length");
      places.emplace_back(r.data_length_byte, name + " data length");
      for (const auto& [field, at] : r.fields) {
        if (field == "size" || field == "count" || field == "conn" || field == "ver" || field == "conn_count" ||
            field == "chunk_count" || field == "index_pos" || field == "chunk_pos") {
          places.emplace_back(at, name + " field " + field);
        }
      }
      if (r.op == 0x04) {
        for (std::uint32_t i = 0; i * 12 < r.data_size; ++i) places.emplace_back(r.data_byte + 12 * i + 8, name + " index offset");
      }
    }
    for (const auto& [at, what] : places) {
      const std::uint32_t original = get_u32(bag.bytes, at);
      for (const std::uint32_t value : {0u, 1u, original - 1, original + 1, original + 12, 0x7fffffffu, 0xffffffffu}) {
        if (value == original) continue;
        std::vector<std::uint8_t> bytes = bag.bytes;
        set_u32(bytes, at, value);
        const Outcome outcome = read_corrupt(path, bytes, compression + " " + what + " = " + std::to_string(value));
        ++cases;
        refused += outcome.read ? 0 : 1;
      }
    }
  }
  EXPECT_GT(cases, 500u);
  EXPECT_GT(refused, cases / 2);  // most corruptions are caught (some, such as a count field's, change nothing read)
}

TEST(BagFile, TruncatedAndFlippedBagsGiveFormatErrors) {
  const auto dir = scratch_dir();
  const fs::path path = dir / "cut.bag";
  for (const std::string& compression : kCompressions) {
    SCOPED_TRACE(compression);
    const WrittenBag bag = small_bag(compression);
    write_bytes(path, bag.bytes);
    ASSERT_EQ(read_everything(path), 11u);
    // Cut at every length (inside the bag header's padding, at its first byte only: nothing reads the rest).
    const WrittenRecord& header = bag.records.front();
    for (std::size_t size = 0; size < bag.bytes.size(); ++size) {
      if (size > header.data_byte && size < header.data_byte + header.data_size) continue;
      const Outcome outcome =
          read_corrupt(path, std::vector<std::uint8_t>(bag.bytes.begin(), bag.bytes.begin() + static_cast<std::ptrdiff_t>(size)),
                       compression + " cut to " + std::to_string(size) + " bytes");
      EXPECT_FALSE(outcome.read) << "cut to " << size << " bytes";
    }
    // Every byte flipped (all bits), except the bag header's padding.
    for (std::size_t at = 0; at < bag.bytes.size(); ++at) {
      if (at >= header.data_byte && at < header.data_byte + header.data_size) continue;
      std::vector<std::uint8_t> bytes = bag.bytes;
      bytes[at] ^= 0xff;
      (void)read_corrupt(path, bytes, compression + " byte " + std::to_string(at) + " flipped");
    }
  }
}

}  // namespace
}  // namespace umbra::test
