// A writer of small ROS bags for tests and fuzz seeds: see bag_writer.hpp.
#include "bag_writer.hpp"

#include <bzlib.h>
#include <lz4frame.h>

#include <bit>
#include <cstring>
#include <stdexcept>
#include <utility>

namespace umbra::test {
namespace {

constexpr std::uint64_t kBagHeaderBytes = 4096;  // rosbag pads the bag header record's header and data to this

void put_u32(std::vector<std::uint8_t>& out, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) out.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
}
void put_u64(std::vector<std::uint8_t>& out, std::uint64_t v) {
  for (int i = 0; i < 8; ++i) out.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
}
void put_f64(std::vector<std::uint8_t>& out, double v) { put_u64(out, std::bit_cast<std::uint64_t>(v)); }
void put_text(std::vector<std::uint8_t>& out, const std::string& s) {
  put_u32(out, static_cast<std::uint32_t>(s.size()));
  out.insert(out.end(), s.begin(), s.end());
}
void set_u32(std::vector<std::uint8_t>& out, std::uint64_t at, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) out[at + i] = static_cast<std::uint8_t>(v >> (8 * i));
}
void set_u64(std::vector<std::uint8_t>& out, std::uint64_t at, std::uint64_t v) {
  for (int i = 0; i < 8; ++i) out[at + i] = static_cast<std::uint8_t>(v >> (8 * i));
}

std::string bytes_u32(std::uint32_t v) {
  std::vector<std::uint8_t> b;
  put_u32(b, v);
  return {b.begin(), b.end()};
}
std::string bytes_u64(std::uint64_t v) {
  std::vector<std::uint8_t> b;
  put_u64(b, v);
  return {b.begin(), b.end()};
}
std::string bytes_time(std::uint32_t sec, std::uint32_t nsec) { return bytes_u64(std::uint64_t{nsec} << 32 | sec); }

using Fields = std::vector<std::pair<std::string, std::string>>;

/// Appends a record; returns where its parts landed (offsets relative to `out`'s start, plus `base`).
WrittenRecord put_record(std::vector<std::uint8_t>& out, const Fields& fields, const std::vector<std::uint8_t>& data,
                         std::uint64_t base = 0) {
  WrittenRecord record;
  record.byte = base + out.size();
  record.op = 0;
  std::vector<std::uint8_t> header;
  for (const auto& [name, value] : fields) {
    put_u32(header, static_cast<std::uint32_t>(name.size() + 1 + value.size()));
    header.insert(header.end(), name.begin(), name.end());
    header.push_back('=');
    record.fields[name] = record.byte + 4 + header.size();
    header.insert(header.end(), value.begin(), value.end());
    if (name == "op") record.op = static_cast<std::uint8_t>(value[0]);
  }
  put_u32(out, static_cast<std::uint32_t>(header.size()));
  out.insert(out.end(), header.begin(), header.end());
  record.data_length_byte = base + out.size();
  put_u32(out, static_cast<std::uint32_t>(data.size()));
  record.data_byte = base + out.size();
  record.data_size = static_cast<std::uint32_t>(data.size());
  out.insert(out.end(), data.begin(), data.end());
  return record;
}

std::vector<std::uint8_t> compress(const std::vector<std::uint8_t>& data, const std::string& compression) {
  if (compression == "none") return data;
  if (compression == "bz2") {
    auto capacity = static_cast<unsigned>(data.size() + data.size() / 100 + 600);
    std::vector<std::uint8_t> out(capacity);
    std::vector<std::uint8_t> in = data;  // libbz2 takes a non-const pointer
    if (BZ2_bzBuffToBuffCompress(reinterpret_cast<char*>(out.data()), &capacity, reinterpret_cast<char*>(in.data()),
                                 static_cast<unsigned>(in.size()), 9, 0, 0) != BZ_OK) {
      throw std::runtime_error("bz2 compression failed");
    }
    out.resize(capacity);
    return out;
  }
  if (compression == "lz4") {
    // What roslz4 accepts: independent blocks, no block checksums, a content checksum, no content size.
    LZ4F_preferences_t preferences{};
    preferences.frameInfo.blockSizeID = LZ4F_max64KB;
    preferences.frameInfo.blockMode = LZ4F_blockIndependent;
    preferences.frameInfo.contentChecksumFlag = LZ4F_contentChecksumEnabled;
    std::vector<std::uint8_t> out(LZ4F_compressFrameBound(data.size(), &preferences));
    const std::size_t size = LZ4F_compressFrame(out.data(), out.size(), data.data(), data.size(), &preferences);
    if (LZ4F_isError(size)) throw std::runtime_error("lz4 compression failed");
    out.resize(size);
    return out;
  }
  throw std::invalid_argument("unknown compression " + compression);
}

std::string op(std::uint8_t value) { return std::string(1, static_cast<char>(value)); }

/// The connection header (the data of a connection record).
std::vector<std::uint8_t> connection_header(const TestConnection& c) {
  std::vector<std::uint8_t> out;
  for (const auto& [name, value] : Fields{{"callerid", "/umbra_test"},
                                          {"latching", "0"},
                                          {"md5sum", c.md5sum},
                                          {"message_definition", c.definition},
                                          {"topic", c.topic},
                                          {"type", c.type}}) {
    put_u32(out, static_cast<std::uint32_t>(name.size() + 1 + value.size()));
    out.insert(out.end(), name.begin(), name.end());
    out.push_back('=');
    out.insert(out.end(), value.begin(), value.end());
  }
  return out;
}

struct ChunkInfo {
  std::uint64_t byte = 0;
  std::uint64_t start = UINT64_MAX;  // packed times, for start/end
  std::uint64_t end = 0;
  std::map<std::uint32_t, std::uint32_t> counts;
};

}  // namespace

std::vector<WrittenRecord> WrittenBag::with_op(std::uint8_t op_value) const {
  std::vector<WrittenRecord> result;
  for (const WrittenRecord& r : records) {
    if (r.op == op_value) result.push_back(r);
  }
  return result;
}

WrittenBag write_test_bag(const std::vector<TestConnection>& connections, const std::vector<TestMessage>& messages,
                          const std::string& compression, std::size_t chunk_bytes) {
  WrittenBag bag;
  std::vector<std::uint8_t>& out = bag.bytes;
  const std::string magic = "#ROSBAG V2.0\n";
  out.assign(magic.begin(), magic.end());
  // The bag header, patched at the end.
  WrittenRecord header = put_record(out, {{"chunk_count", bytes_u32(0)}, {"conn_count", bytes_u32(0)},
                                          {"index_pos", bytes_u64(0)}, {"op", op(0x03)}},
                                    {});
  const std::uint64_t header_size = header.data_length_byte - header.byte - 4;
  const std::uint64_t padding = header_size < kBagHeaderBytes ? kBagHeaderBytes - header_size : 0;
  set_u32(out, header.data_length_byte, static_cast<std::uint32_t>(padding));
  out.insert(out.end(), padding, ' ');
  header.data_size = static_cast<std::uint32_t>(padding);
  bag.records.push_back(header);

  std::vector<ChunkInfo> chunk_infos;
  std::vector<std::uint8_t> chunk;          // the open chunk's uncompressed records
  std::vector<WrittenRecord> chunk_records;  // their places, relative to the chunk
  std::map<std::uint32_t, std::vector<std::array<std::uint32_t, 3>>> chunk_index;  // conn -> (sec, nsec, offset)
  std::vector<bool> connection_written(connections.size(), false);
  ChunkInfo info;

  const auto close_chunk = [&] {
    if (chunk.empty()) return;
    info.byte = out.size();
    const std::vector<std::uint8_t> data = compress(chunk, compression);
    const WrittenRecord chunk_record = put_record(
        out, {{"compression", compression}, {"op", op(0x05)}, {"size", bytes_u32(static_cast<std::uint32_t>(chunk.size()))}},
        data);
    bag.records.push_back(chunk_record);
    if (compression == "none") {
      for (WrittenRecord inner : chunk_records) {
        const std::uint64_t shift = chunk_record.data_byte;
        inner.byte += shift;
        inner.data_length_byte += shift;
        inner.data_byte += shift;
        for (auto& [name, at] : inner.fields) at += shift;
        inner.in_chunk = true;
        bag.records.push_back(inner);
      }
    }
    for (const auto& [connection, entries] : chunk_index) {
      std::vector<std::uint8_t> data_bytes;
      for (const auto& [sec, nsec, offset] : entries) {
        put_u32(data_bytes, sec);
        put_u32(data_bytes, nsec);
        put_u32(data_bytes, offset);
      }
      bag.records.push_back(put_record(out,
                                       {{"conn", bytes_u32(connection)},
                                        {"count", bytes_u32(static_cast<std::uint32_t>(entries.size()))},
                                        {"op", op(0x04)},
                                        {"ver", bytes_u32(1)}},
                                       data_bytes));
    }
    chunk_infos.push_back(info);
    info = ChunkInfo{};
    chunk.clear();
    chunk_records.clear();
    chunk_index.clear();
  };

  for (const TestMessage& message : messages) {
    const TestConnection& connection = connections.at(message.connection);
    if (!connection_written[message.connection]) {
      connection_written[message.connection] = true;
      chunk_records.push_back(put_record(chunk,
                                         {{"conn", bytes_u32(message.connection)}, {"op", op(0x07)}, {"topic", connection.topic}},
                                         connection_header(connection)));
    }
    chunk_index[message.connection].push_back({message.sec, message.nsec, static_cast<std::uint32_t>(chunk.size())});
    chunk_records.push_back(put_record(
        chunk, {{"conn", bytes_u32(message.connection)}, {"op", op(0x02)}, {"time", bytes_time(message.sec, message.nsec)}},
        message.bytes));
    const std::uint64_t packed = std::uint64_t{message.sec} << 32 | message.nsec;
    info.start = std::min(info.start, packed);
    info.end = std::max(info.end, packed);
    ++info.counts[message.connection];
    if (chunk.size() >= chunk_bytes) close_chunk();
  }
  close_chunk();

  const std::uint64_t index_byte = out.size();
  for (std::uint32_t id = 0; id < connections.size(); ++id) {
    bag.records.push_back(put_record(out, {{"conn", bytes_u32(id)}, {"op", op(0x07)}, {"topic", connections[id].topic}},
                                     connection_header(connections[id])));
  }
  for (const ChunkInfo& c : chunk_infos) {
    std::vector<std::uint8_t> data;
    for (const auto& [connection, count] : c.counts) {
      put_u32(data, connection);
      put_u32(data, count);
    }
    const auto time_of = [](std::uint64_t packed) {
      return bytes_time(static_cast<std::uint32_t>(packed >> 32), static_cast<std::uint32_t>(packed));
    };
    bag.records.push_back(put_record(out,
                                     {{"chunk_pos", bytes_u64(c.byte)},
                                      {"count", bytes_u32(static_cast<std::uint32_t>(c.counts.size()))},
                                      {"end_time", time_of(c.end)},
                                      {"op", op(0x06)},
                                      {"start_time", time_of(c.start)},
                                      {"ver", bytes_u32(1)}},
                                     data));
  }
  set_u64(out, header.fields.at("index_pos"), index_byte);
  set_u32(out, header.fields.at("conn_count"), static_cast<std::uint32_t>(connections.size()));
  set_u32(out, header.fields.at("chunk_count"), static_cast<std::uint32_t>(chunk_infos.size()));
  return bag;
}

std::vector<std::uint8_t> serialize_cloud(const TestCloud& cloud) {
  std::vector<std::uint8_t> out;
  put_u32(out, 0);  // seq
  put_u32(out, cloud.sec);
  put_u32(out, cloud.nsec);
  put_text(out, cloud.frame_id);
  put_u32(out, cloud.layout.height);
  put_u32(out, cloud.layout.width);
  put_u32(out, static_cast<std::uint32_t>(cloud.layout.fields.size()));
  for (const ros_io::PointField& field : cloud.layout.fields) {
    put_text(out, field.name);
    put_u32(out, field.offset);
    out.push_back(field.datatype);
    put_u32(out, field.count);
  }
  out.push_back(cloud.layout.is_bigendian ? 1 : 0);
  put_u32(out, cloud.layout.point_step);
  put_u32(out, cloud.layout.row_step);
  put_u32(out, static_cast<std::uint32_t>(cloud.data.size()));
  out.insert(out.end(), cloud.data.begin(), cloud.data.end());
  out.push_back(cloud.layout.is_dense ? 1 : 0);
  return out;
}

TestCloud xyz_rgb_cloud(const std::string& frame_id, std::uint32_t sec, const std::vector<Vec3f>& points) {
  TestCloud cloud;
  cloud.frame_id = frame_id;
  cloud.sec = sec;
  constexpr auto f32 = static_cast<std::uint8_t>(ros_io::PointFieldType::float32);
  cloud.layout.height = 1;
  cloud.layout.width = static_cast<std::uint32_t>(points.size());
  cloud.layout.fields = {{"x", 0, f32, 1}, {"y", 4, f32, 1}, {"z", 8, f32, 1}, {"rgb", 12, f32, 1}};
  cloud.layout.point_step = 16;
  cloud.layout.row_step = 16 * cloud.layout.width;
  cloud.layout.is_dense = true;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const std::uint32_t rgb = 0x102030u + static_cast<std::uint32_t>(i);
    for (const std::uint32_t bits :
         {std::bit_cast<std::uint32_t>(points[i].x), std::bit_cast<std::uint32_t>(points[i].y),
          std::bit_cast<std::uint32_t>(points[i].z), rgb}) {
      put_u32(cloud.data, bits);
    }
  }
  return cloud;
}

std::vector<std::uint8_t> serialize_tf(const std::vector<TestTransform>& transforms) {
  std::vector<std::uint8_t> out;
  put_u32(out, static_cast<std::uint32_t>(transforms.size()));
  for (const TestTransform& t : transforms) {
    put_u32(out, 0);  // seq
    put_u32(out, t.sec);
    put_u32(out, t.nsec);
    put_text(out, t.parent);
    put_text(out, t.child);
    for (const double v : t.translation) put_f64(out, v);
    for (const double v : t.rotation) put_f64(out, v);
  }
  return out;
}

namespace {

/// small_bag's clouds in their own frames, and the map -> base_link translations (base_link -> lidar adds
/// kMount).
constexpr std::array<double, 3> kMount{0.25, 0.0, 0.5};
const std::array<std::array<double, 3>, 3> kPoses{{{1.0, 2.0, 0.0}, {1.5, 2.0, 0.0}, {2.0, 2.5, 0.0}}};

std::vector<Vec3f> lidar_points(std::size_t i) {
  const auto s = static_cast<float>(i);
  return {{3.0f + s, 0.5f, 0.25f}, {-2.0f, 1.5f + s, 1.0f}, {0.5f, -4.0f, -0.375f - s}};
}

}  // namespace

WrittenBag small_bag(const std::string& compression, std::size_t chunk_bytes) {
  const std::vector<TestConnection> connections{{"/tf_static", "tf2_msgs/TFMessage", kTfMd5},
                                                {"/tf", "tf2_msgs/TFMessage", kTfMd5},
                                                {"/points", "sensor_msgs/PointCloud2", kCloudMd5},
                                                {"/map_points", "sensor_msgs/PointCloud2", kCloudMd5},
                                                {"/chatter", "std_msgs/String", kStringMd5}};
  std::vector<TestMessage> messages;
  TestTransform mount{"base_link", "lidar", 10, 0, kMount, {0, 0, 0, 1}};
  messages.push_back({0, 10, 0, serialize_tf({mount})});
  for (std::uint32_t i = 0; i < 3; ++i) {
    TestTransform pose{"/map", "base_link", 10 + i, 0, kPoses[i], {0, 0, 0, 1}};
    messages.push_back({1, 10 + i, 0, serialize_tf({pose})});
    messages.push_back({2, 10 + i, 0, serialize_cloud(xyz_rgb_cloud("lidar", 10 + i, lidar_points(i)))});
    std::vector<std::uint8_t> text;
    put_text(text, "hello " + std::to_string(i));
    messages.push_back({4, 10 + i, 500000000, text});
  }
  messages.push_back({3, 11, 0, serialize_cloud(xyz_rgb_cloud("map", 11, {{4.0f, 4.0f, 1.0f}, {5.0f, 4.5f, 0.5f}}))});
  return write_test_bag(connections, messages, compression, chunk_bytes);
}

std::vector<ExpectedScan> small_bag_points() {
  std::vector<ExpectedScan> scans;
  for (std::size_t i = 0; i < 3; ++i) {
    ExpectedScan scan{"/points", {}};
    for (const Vec3f& p : lidar_points(i)) {
      // The decoder's own arithmetic: identity rotation, then the translation, in double.
      scan.points.push_back(Vec3f(Vec3d{static_cast<double>(p.x) + (kPoses[i][0] + kMount[0]),
                                        static_cast<double>(p.y) + (kPoses[i][1] + kMount[1]),
                                        static_cast<double>(p.z) + (kPoses[i][2] + kMount[2])}));
    }
    scans.push_back(scan);
    if (i == 1) scans.push_back({"/map_points", {{4.0f, 4.0f, 1.0f}, {5.0f, 4.5f, 0.5f}}});
  }
  return scans;
}

}  // namespace umbra::test
