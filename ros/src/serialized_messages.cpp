// The ROS 1 wire format of PointCloud2 and TFMessage: see serialized_messages.hpp.
#include "umbra_ros/serialized_messages.hpp"

#include <bit>
#include <cstring>

#include "umbra/io/format_error.hpp"

namespace umbra::ros_io {
namespace {

/// Reads the fields of one message in order, checking each against the bytes left.
class WireReader {
 public:
  WireReader(std::span<const std::uint8_t> bytes, const std::string& name, const char* type)
      : bytes_(bytes), name_(name), type_(type) {}

  std::uint8_t u8(const char* what) { return *take(1, what); }
  std::uint32_t u32(const char* what) {
    const std::uint8_t* p = take(4, what);
    return std::uint32_t{p[0]} | std::uint32_t{p[1]} << 8 | std::uint32_t{p[2]} << 16 | std::uint32_t{p[3]} << 24;
  }
  double f64(const char* what) {
    const std::uint8_t* p = take(8, what);
    std::uint64_t bits = 0;
    for (int i = 7; i >= 0; --i) bits = (bits << 8) | p[i];
    return std::bit_cast<double>(bits);
  }
  std::string text(const char* what) {
    const std::uint32_t length = u32(what);
    const std::uint8_t* p = take(length, what);
    return {reinterpret_cast<const char*>(p), length};
  }
  std::span<const std::uint8_t> byte_array(const char* what) {
    const std::uint32_t length = u32(what);
    return {take(length, what), length};
  }
  /// An array's element count, checked against the bytes left: each element takes at least `min_element_bytes`.
  std::uint32_t count(const char* what, std::size_t min_element_bytes) {
    const std::size_t at = at_;
    const std::uint32_t n = u32(what);
    if (std::uint64_t{n} * min_element_bytes > bytes_.size() - at_) {
      throw error(at, std::string(what) + " counts " + std::to_string(n) + " elements of at least " +
                          std::to_string(min_element_bytes) + " bytes, but only " +
                          std::to_string(bytes_.size() - at_) + " bytes are left");
    }
    return n;
  }
  MessageHeader header() {
    MessageHeader h;
    h.seq = u32("header.seq");
    h.stamp_sec = u32("header.stamp.sec");
    h.stamp_nsec = u32("header.stamp.nsec");
    h.frame_id = text("header.frame_id");
    return h;
  }
  void finish() const {
    if (at_ != bytes_.size()) {
      throw error(at_, std::to_string(bytes_.size() - at_) + " bytes follow the end of the " + type_ +
                           " (another version of the message?)");
    }
  }

 private:
  const std::uint8_t* take(std::size_t size, const char* what) {
    if (size > bytes_.size() - at_) {
      throw error(at_, std::string(what) + " needs " + std::to_string(size) + " bytes, but only " +
                           std::to_string(bytes_.size() - at_) + " are left");
    }
    const std::uint8_t* p = bytes_.data() + at_;
    at_ += size;
    return p;
  }
  [[nodiscard]] FormatError error(std::size_t at, const std::string& what) const {
    return FormatError(name_, std::string(type_) + " message of " + std::to_string(bytes_.size()) + " bytes, at byte " +
                                  std::to_string(at) + ": " + what);
  }

  std::span<const std::uint8_t> bytes_;
  const std::string& name_;
  const char* type_;
  std::size_t at_ = 0;
};

}  // namespace

SerializedCloud parse_point_cloud2(std::span<const std::uint8_t> bytes, const std::string& name) {
  WireReader in(bytes, name, "sensor_msgs/PointCloud2");
  SerializedCloud result;
  result.header = in.header();
  PointCloud2View& cloud = result.cloud;
  cloud.height = in.u32("height");
  cloud.width = in.u32("width");
  // A PointField: name (4 + n), offset (4), datatype (1), count (4).
  const std::uint32_t fields = in.count("fields", 13);
  cloud.fields.reserve(fields);
  for (std::uint32_t i = 0; i < fields; ++i) {
    PointField field;
    field.name = in.text("fields[].name");
    field.offset = in.u32("fields[].offset");
    field.datatype = in.u8("fields[].datatype");
    field.count = in.u32("fields[].count");
    cloud.fields.push_back(std::move(field));
  }
  cloud.is_bigendian = in.u8("is_bigendian") != 0;
  cloud.point_step = in.u32("point_step");
  cloud.row_step = in.u32("row_step");
  cloud.data = in.byte_array("data");
  cloud.is_dense = in.u8("is_dense") != 0;
  in.finish();
  return result;
}

std::vector<SerializedTransform> parse_tf_message(std::span<const std::uint8_t> bytes, const std::string& name) {
  WireReader in(bytes, name, "tf2_msgs/TFMessage");
  // A TransformStamped: header (16 + n), child_frame_id (4 + n), 7 doubles.
  const std::uint32_t count = in.count("transforms", 16 + 4 + 56);
  std::vector<SerializedTransform> transforms;
  transforms.reserve(count);
  for (std::uint32_t i = 0; i < count; ++i) {
    SerializedTransform t;
    t.header = in.header();
    t.child_frame_id = in.text("transforms[].child_frame_id");
    for (double& v : t.translation) v = in.f64("transforms[].transform.translation");
    for (double& v : t.rotation) v = in.f64("transforms[].transform.rotation");
    transforms.push_back(std::move(t));
  }
  in.finish();
  return transforms;
}

}  // namespace umbra::ros_io
