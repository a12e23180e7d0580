// PointCloud2 decoding (ros/include/umbra_ros/point_cloud2.hpp), no ROS needed.
//
// Every cloud is written here by a small independent packer from a list of
// points and a layout (field types, offsets, padding, byte order, rows with
// padding, NaN points); decoding must give back the points (rounded to
// float after the transform, computed in double here), their colors, and
// the NaN count. Bad layouts must throw a FormatError that names the cloud
// and the problem.
#include "umbra_ros/point_cloud2.hpp"

#include "umbra/core/memory_limit.hpp"
#include "umbra/io/scan_source.hpp"

#include <bit>
#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

namespace umbra::ros_io {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

struct TestPoint {
  double x = 0;
  double y = 0;
  double z = 0;
  Rgb color;
};

/// How a test cloud is laid out.
struct Layout {
  PointFieldType xyz_type = PointFieldType::float32;
  bool big_endian = false;
  std::uint32_t x_offset = 0;  ///< y and z follow at the type's size (plus xyz_gap bytes between)
  std::uint32_t xyz_gap = 0;
  std::uint32_t padding_after = 0;  ///< bytes after z that no field names
  bool intensity = false;           ///< a float32 field after the padding
  enum class Color { none, rgb_float, rgba_uint32 } color = Color::none;
  std::uint32_t height = 1;
  std::uint32_t row_padding = 0;  ///< bytes at the end of each row
};

/// Writes `bytes` bytes of `bits` in the cloud's byte order.
void put(std::vector<std::uint8_t>& data, std::size_t at, std::uint64_t bits, std::size_t bytes, bool big_endian) {
  for (std::size_t i = 0; i < bytes; ++i) {
    const std::size_t shift = 8 * (big_endian ? bytes - 1 - i : i);
    data[at + i] = static_cast<std::uint8_t>(bits >> shift);
  }
}

struct PackedCloud {
  PointCloud2View view;
  std::vector<std::uint8_t> bytes;  // owns view.data
};

PackedCloud pack(const std::vector<TestPoint>& points, const Layout& layout) {
  PackedCloud cloud;
  PointCloud2View& v = cloud.view;
  const std::uint32_t size = layout.xyz_type == PointFieldType::float64 ? 8 : 4;
  std::uint32_t offset = layout.x_offset;
  for (const char* name : {"x", "y", "z"}) {
    v.fields.push_back({name, offset, static_cast<std::uint8_t>(layout.xyz_type), 1});
    offset += size + layout.xyz_gap;
  }
  offset += layout.padding_after;
  if (layout.intensity) {
    v.fields.push_back({"intensity", offset, static_cast<std::uint8_t>(PointFieldType::float32), 1});
    offset += 4;
  }
  std::uint32_t color_offset = 0;
  if (layout.color != Layout::Color::none) {
    color_offset = offset;
    const bool as_float = layout.color == Layout::Color::rgb_float;
    v.fields.push_back({as_float ? "rgb" : "rgba", offset,
                        static_cast<std::uint8_t>(as_float ? PointFieldType::float32 : PointFieldType::uint32), 1});
    offset += 4;
  }
  if (layout.x_offset > 0) v.fields.push_back({"_", 0, static_cast<std::uint8_t>(PointFieldType::uint8), layout.x_offset});
  v.point_step = offset;
  v.height = layout.height;
  v.width = static_cast<std::uint32_t>(points.size()) / layout.height;
  v.row_step = v.width * v.point_step + layout.row_padding;
  v.is_bigendian = layout.big_endian;
  v.is_dense = false;
  cloud.bytes.assign(std::size_t{v.row_step} * v.height, 0xAB);  // padding bytes hold junk
  for (std::size_t i = 0; i < points.size(); ++i) {
    const std::size_t row = i / v.width;
    const std::size_t column = i % v.width;
    const std::size_t base = row * v.row_step + column * v.point_step;
    const double xyz[3] = {points[i].x, points[i].y, points[i].z};
    for (int axis = 0; axis < 3; ++axis) {
      const std::size_t at = base + v.fields[static_cast<std::size_t>(axis)].offset;
      if (size == 8) {
        put(cloud.bytes, at, std::bit_cast<std::uint64_t>(xyz[axis]), 8, layout.big_endian);
      } else {
        put(cloud.bytes, at, std::bit_cast<std::uint32_t>(static_cast<float>(xyz[axis])), 4, layout.big_endian);
      }
    }
    if (layout.color != Layout::Color::none) {
      const Rgb c = points[i].color;
      const std::uint32_t packed = 0xFF000000u | (std::uint32_t{c.r} << 16) | (std::uint32_t{c.g} << 8) | c.b;
      put(cloud.bytes, base + color_offset, packed, 4, layout.big_endian);
    }
  }
  v.data = cloud.bytes;
  return cloud;
}

std::vector<TestPoint> test_points(std::size_t count, std::uint32_t seed, std::size_t nan_every = 0) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> coordinate(-40.0, 40.0);
  std::uniform_int_distribution<int> byte(0, 255);
  std::vector<TestPoint> points(count);
  for (std::size_t i = 0; i < count; ++i) {
    points[i] = {coordinate(rng), coordinate(rng), coordinate(rng),
                 Rgb{static_cast<std::uint8_t>(byte(rng)), static_cast<std::uint8_t>(byte(rng)),
                     static_cast<std::uint8_t>(byte(rng))}};
    if (nan_every > 0 && i % nan_every == 3) points[i].y = kNaN;
  }
  return points;
}

/// What decoding must give: the stored value (float32 rounds first), transformed in double, rounded to float.
Vec3f expected_point(const TestPoint& p, PointFieldType type, const RigidTransform& transform) {
  auto stored = [&](double v) { return type == PointFieldType::float32 ? double(static_cast<float>(v)) : v; };
  return Vec3f(transform.apply({stored(p.x), stored(p.y), stored(p.z)}));
}

void expect_decodes(const std::vector<TestPoint>& points, const Layout& layout, const RigidTransform& transform = {}) {
  const PackedCloud cloud = pack(points, layout);
  DecodedCloud out;
  out.points.assign(3, Vec3f{1, 2, 3});  // stale contents must go
  decode_point_cloud2(cloud.view, transform, true, out, "test cloud");
  ASSERT_EQ(out.points.size(), points.size());
  const bool colors = layout.color != Layout::Color::none;
  ASSERT_EQ(out.colors.size(), colors ? points.size() : 0u);
  std::size_t nan = 0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (std::isnan(points[i].y)) {
      ++nan;
      EXPECT_FALSE(out.points[i].is_finite()) << "point " << i;
    } else {
      EXPECT_EQ(out.points[i], expected_point(points[i], layout.xyz_type, transform)) << "point " << i;
    }
    if (colors) {
      EXPECT_EQ(out.colors[i], points[i].color) << "point " << i;
    }
  }
  EXPECT_EQ(out.non_finite, nan);
}

TEST(PointCloud2, EveryFieldLayout) {
  const std::vector<TestPoint> points = test_points(240, 7);
  for (const PointFieldType type : {PointFieldType::float32, PointFieldType::float64}) {
    for (const bool big_endian : {false, true}) {
      SCOPED_TRACE(to_string(type) + (big_endian ? " big-endian" : " little-endian"));
      Layout layout;
      layout.xyz_type = type;
      layout.big_endian = big_endian;
      expect_decodes(points, layout);  // packed x y z
      layout.padding_after = 4;         // PCL's PointXYZ: x y z and 4 bytes of padding
      layout.intensity = true;
      expect_decodes(points, layout);
      layout.x_offset = 6;  // a leading padding field, gaps between the coordinates
      layout.xyz_gap = 2;
      expect_decodes(points, layout);
      for (const auto color : {Layout::Color::rgb_float, Layout::Color::rgba_uint32}) {
        layout.color = color;
        expect_decodes(points, layout);
      }
    }
  }
}

TEST(PointCloud2, OrganisedCloudsWithNaNsAndRowPadding) {
  const std::vector<TestPoint> points = test_points(16 * 24, 11, 5);  // every fifth point a missing return
  for (const PointFieldType type : {PointFieldType::float32, PointFieldType::float64}) {
    Layout layout;
    layout.xyz_type = type;
    layout.height = 16;
    layout.padding_after = 4;
    layout.color = Layout::Color::rgb_float;
    expect_decodes(points, layout);
    layout.row_padding = 12;  // rows longer than their points
    layout.big_endian = true;
    expect_decodes(points, layout);
  }
}

TEST(PointCloud2, TransformIsAppliedInDouble) {
  const std::vector<TestPoint> points = test_points(100, 3, 7);
  const double half = 0.6;  // 1.2 rad about the axis (1, 2, 2) / 3
  const RigidTransform transform = RigidTransform::from_quaternion(
      {10.25, -3.5, 1.75}, std::sin(half) / 3.0, 2.0 * std::sin(half) / 3.0, 2.0 * std::sin(half) / 3.0, std::cos(half));
  Layout layout;
  layout.xyz_type = PointFieldType::float64;
  expect_decodes(points, layout, transform);
  // The rotation is a rotation: orthonormal, determinant 1.
  const auto& r = transform.rotation;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      double dot = 0;
      for (int k = 0; k < 3; ++k) dot += r[static_cast<std::size_t>(i)][static_cast<std::size_t>(k)] * r[static_cast<std::size_t>(j)][static_cast<std::size_t>(k)];
      EXPECT_NEAR(dot, i == j ? 1.0 : 0.0, 1e-15);
    }
  }
  // A quaternion of another length gives the same rotation; a zero or NaN one is refused.
  const RigidTransform scaled = RigidTransform::from_quaternion({}, 0.0, 0.0, 2.0 * std::sin(0.5), 2.0 * std::cos(0.5));
  EXPECT_NEAR(scaled.apply({1, 0, 0}).x, std::cos(1.0), 1e-15);
  EXPECT_NEAR(scaled.apply({1, 0, 0}).y, std::sin(1.0), 1e-15);
  EXPECT_THROW((void)RigidTransform::from_quaternion({}, 0, 0, 0, 0), std::invalid_argument);
  EXPECT_THROW((void)RigidTransform::from_quaternion({kNaN, 0, 0}, 0, 0, 0, 1), std::invalid_argument);
}

TEST(PointCloud2, EmptyCloudAndNoColorWanted) {
  DecodedCloud out;
  PackedCloud cloud = pack({}, Layout{});
  decode_point_cloud2(cloud.view, {}, true, out, "empty");
  EXPECT_TRUE(out.points.empty());
  Layout layout;
  layout.color = Layout::Color::rgb_float;
  cloud = pack(test_points(10, 1), layout);
  decode_point_cloud2(cloud.view, {}, false, out, "no color wanted");
  EXPECT_EQ(out.points.size(), 10u);
  EXPECT_TRUE(out.colors.empty());
}

/// The FormatError message decoding gives; a test failure if it decodes.
std::string decode_error(const PointCloud2View& view) {
  DecodedCloud out;
  try {
    decode_point_cloud2(view, {}, true, out, "bag.bag message 4 on /points");
  } catch (const FormatError& e) {
    EXPECT_TRUE(out.points.empty()) << "points were written before the layout was checked";
    return e.what();
  }
  ADD_FAILURE() << "expected a FormatError";
  return "";
}

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

TEST(PointCloud2, BadCloudsAreClearErrors) {
  const std::vector<TestPoint> points = test_points(12, 5);
  Layout layout;
  layout.padding_after = 4;
  layout.height = 3;
  const PackedCloud good = pack(points, layout);

  PointCloud2View v = good.view;
  v.point_step = 10;  // z (offset 8, 4 bytes) no longer fits
  std::string message = decode_error(v);
  EXPECT_TRUE(contains(message, "bag.bag message 4 on /points: ")) << message;
  EXPECT_TRUE(contains(message, "field 'z' (FLOAT32 x1 at offset 8) ends at byte 12 of the point, past point_step 10"))
      << message;

  v = good.view;
  v.point_step = 0;
  EXPECT_TRUE(contains(decode_error(v), "point_step is 0")) << decode_error(v);

  v = good.view;
  v.data = v.data.first(v.data.size() - 1);  // truncated
  message = decode_error(v);
  EXPECT_TRUE(contains(message, "data is truncated: 3 rows of 4 points (point_step 16, row_step 64) need 192 bytes, "
                                "but data has 191"))
      << message;

  v = good.view;
  v.row_step = 60;  // shorter than a row of 4 x 16 bytes
  EXPECT_TRUE(contains(decode_error(v), "row_step 60 is shorter than a row")) << decode_error(v);

  v = good.view;
  v.height = 1u << 31;  // rows far beyond the data; no overflow in the size check
  v.row_step = 1u << 31;
  EXPECT_TRUE(contains(decode_error(v), "data is truncated")) << decode_error(v);

  v = good.view;
  v.fields.erase(v.fields.begin() + 1);  // no y
  message = decode_error(v);
  EXPECT_TRUE(contains(message, "has no field y (fields: 'x', 'z'); umbra needs x, y and z")) << message;
  v.fields.clear();
  EXPECT_TRUE(contains(decode_error(v), "has no field x, y, z (fields: none)")) << decode_error(v);

  v = good.view;
  v.fields[0].datatype = static_cast<std::uint8_t>(PointFieldType::int16);
  EXPECT_TRUE(contains(decode_error(v), "field 'x' is INT16; umbra reads x, y and z as FLOAT32 or FLOAT64"))
      << decode_error(v);
  v.fields[0].datatype = 42;
  EXPECT_TRUE(contains(decode_error(v), "field 'x' is unknown datatype 42")) << decode_error(v);

  v = good.view;
  v.fields.push_back(v.fields[2]);
  EXPECT_TRUE(contains(decode_error(v), "field 'z' appears twice")) << decode_error(v);
}

// The library (umbra_io) knows .bag files but reads them only through the ROS build (ros/src/rosbag_source.cpp,
// used by the umbra program); asked directly it says so.
// The points take 12 bytes each, a point_step can be 4 (x, y and z at one offset): the memory limit is checked
// before the points are allocated.
TEST(PointCloud2, PointsBeyondTheMemoryLimitAreRefused) {
  PointCloud2View cloud;
  const auto f32 = static_cast<std::uint8_t>(PointFieldType::float32);
  cloud.fields = {{"x", 0, f32, 1}, {"y", 0, f32, 1}, {"z", 0, f32, 1}};
  cloud.point_step = 4;
  cloud.width = 1000;
  cloud.row_step = 4000;
  const std::vector<std::uint8_t> data(4000, 0);
  cloud.data = data;
  DecodedCloud out;
  set_memory_limit(8000);
  try {
    decode_point_cloud2(cloud, {}, false, out, "thin cloud");
    ADD_FAILURE() << "decoded";
  } catch (const MemoryLimitError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("thin cloud: decoding 1000 points needs 11.7 KiB (12000 bytes)", 0), 0u)
        << e.what();
  }
  set_memory_limit(0);
  decode_point_cloud2(cloud, {}, false, out, "thin cloud");
  EXPECT_EQ(out.points.size(), 1000u);
}

TEST(RosbagWithoutRos, OpenScanSourceSaysItNeedsTheRosBuild) {
  EXPECT_EQ(scan_format_for("run.bag"), "rosbag");
  EXPECT_EQ(scan_format_for("x.txt", "rosbag"), "rosbag");
  try {
    (void)open_scan_source("run.bag");
    ADD_FAILURE() << "opened";
  } catch (const std::runtime_error& e) {
    EXPECT_TRUE(contains(e.what(), "ROS bag files (.bag) are read only by umbra built with ROS 1")) << e.what();
  }
}

}  // namespace
}  // namespace umbra::ros_io
