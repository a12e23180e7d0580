// decode_point_cloud2: see point_cloud2.hpp. The layout is checked once
// (fields found, sizes against point_step, rows against the data), then one
// loop reads every point through three field readers chosen up front.
#include "umbra_ros/point_cloud2.hpp"

#include <bit>
#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>

#include "core/memory_budget.hpp"

namespace umbra::ros_io {
namespace {

std::size_t type_bytes(std::uint8_t datatype) {
  switch (static_cast<PointFieldType>(datatype)) {
    case PointFieldType::int8:
    case PointFieldType::uint8:
      return 1;
    case PointFieldType::int16:
    case PointFieldType::uint16:
      return 2;
    case PointFieldType::int32:
    case PointFieldType::uint32:
    case PointFieldType::float32:
      return 4;
    case PointFieldType::float64:
      return 8;
  }
  return 0;
}

/// The unsigned value of `bytes` bytes (1..8) at `p`, in the cloud's byte order.
std::uint64_t load_bits(const std::uint8_t* p, std::size_t bytes, bool big_endian) {
  std::uint64_t bits = 0;
  if (big_endian) {
    for (std::size_t i = 0; i < bytes; ++i) bits = (bits << 8) | p[i];
  } else {
    for (std::size_t i = bytes; i-- > 0;) bits = (bits << 8) | p[i];
  }
  return bits;
}

/// Where a coordinate is and how it is stored.
struct CoordinateReader {
  std::uint32_t offset = 0;
  bool is_double = false;
  bool big_endian = false;

  [[nodiscard]] double read(const std::uint8_t* point) const {
    if (is_double) return std::bit_cast<double>(load_bits(point + offset, 8, big_endian));
    return std::bit_cast<float>(static_cast<std::uint32_t>(load_bits(point + offset, 4, big_endian)));
  }
};

struct Layout {
  std::array<CoordinateReader, 3> xyz;
  std::optional<std::uint32_t> rgb_offset;
  std::uint64_t row_step = 0;
};

/// Throws unless `field` fits inside a point of `point_step` bytes.
void check_fits(const PointField& field, std::uint32_t point_step, const std::string& name) {
  const std::uint64_t end =
      std::uint64_t{field.offset} + type_bytes(field.datatype) * std::uint64_t{field.count == 0 ? 1 : field.count};
  if (end > point_step) {
    throw FormatError(name, "PointCloud2 field '" + field.name + "' (" +
                                to_string(static_cast<PointFieldType>(field.datatype)) + " x" +
                                std::to_string(field.count) + " at offset " + std::to_string(field.offset) +
                                ") ends at byte " + std::to_string(end) + " of the point, past point_step " +
                                std::to_string(point_step));
  }
}

Layout check_layout(const PointCloud2View& cloud, bool want_colors, const std::string& name) {
  Layout layout;
  std::array<const PointField*, 3> xyz{};
  const PointField* rgb = nullptr;
  for (const PointField& field : cloud.fields) {
    const PointField** slot = nullptr;
    if (field.name == "x") slot = &xyz[0];
    if (field.name == "y") slot = &xyz[1];
    if (field.name == "z") slot = &xyz[2];
    if (slot != nullptr) {
      if (*slot != nullptr) throw FormatError(name, "PointCloud2 field '" + field.name + "' appears twice");
      *slot = &field;
    } else if ((field.name == "rgb" || field.name == "rgba") && rgb == nullptr) {
      rgb = &field;
    }
  }
  std::string missing;
  for (std::size_t axis = 0; axis < 3; ++axis) {
    if (xyz[axis] == nullptr) missing += std::string(missing.empty() ? "" : ", ") + "xyz"[axis];
  }
  if (!missing.empty()) {
    std::string present;
    for (const PointField& field : cloud.fields) present += (present.empty() ? "'" : ", '") + field.name + "'";
    throw FormatError(name, "PointCloud2 has no field " + missing + " (fields: " +
                                (present.empty() ? std::string("none") : present) + "); umbra needs x, y and z");
  }
  if (cloud.point_step == 0 && std::uint64_t{cloud.width} * cloud.height > 0) {
    throw FormatError(name, "PointCloud2 point_step is 0 for " + std::to_string(cloud.width) + " x " +
                                std::to_string(cloud.height) + " points");
  }
  for (std::size_t axis = 0; axis < 3; ++axis) {
    const PointField& field = *xyz[axis];
    const auto type = static_cast<PointFieldType>(field.datatype);
    if (type != PointFieldType::float32 && type != PointFieldType::float64) {
      throw FormatError(name, "PointCloud2 field '" + field.name + "' is " + to_string(type) +
                                  "; umbra reads x, y and z as FLOAT32 or FLOAT64");
    }
    check_fits(field, cloud.point_step, name);
    layout.xyz[axis] = {field.offset, type == PointFieldType::float64, cloud.is_bigendian};
  }
  if (want_colors && rgb != nullptr) {
    const auto type = static_cast<PointFieldType>(rgb->datatype);
    if (type == PointFieldType::float32 || type == PointFieldType::uint32 || type == PointFieldType::int32) {
      check_fits(*rgb, cloud.point_step, name);
      layout.rgb_offset = rgb->offset;
    }
  }

  const std::uint64_t row_bytes = std::uint64_t{cloud.width} * cloud.point_step;
  layout.row_step = cloud.height > 1 ? cloud.row_step : row_bytes;  // one row needs no row_step
  if (cloud.height > 1 && layout.row_step < row_bytes) {
    throw FormatError(name, "PointCloud2 row_step " + std::to_string(cloud.row_step) + " is shorter than a row (" +
                                std::to_string(cloud.width) + " points of point_step " +
                                std::to_string(cloud.point_step) + " = " + std::to_string(row_bytes) + " bytes)");
  }
  if (cloud.height > 0 && cloud.width > 0) {
    // Rows 0..height-2 take row_step bytes each, the last one only its points (none of this overflows:
    // every factor is below 2^32, and a product past the data is reported before the sum is formed).
    const std::uint64_t rows_before_last = cloud.height - 1u;
    const bool too_long = rows_before_last > 0 && layout.row_step > (cloud.data.size() / rows_before_last);
    const std::uint64_t needed = too_long ? 0 : rows_before_last * layout.row_step + row_bytes;
    if (too_long || needed > cloud.data.size()) {
      throw FormatError(name, "PointCloud2 data is truncated: " + std::to_string(cloud.height) + " rows of " +
                                  std::to_string(cloud.width) + " points (point_step " +
                                  std::to_string(cloud.point_step) + ", row_step " + std::to_string(layout.row_step) +
                                  ") need " +
                                  (too_long ? std::string("more than ") + std::to_string(cloud.data.size())
                                            : std::to_string(needed)) +
                                  " bytes, but data has " + std::to_string(cloud.data.size()));
    }
  }
  return layout;
}

}  // namespace

std::string to_string(PointFieldType type) {
  switch (type) {
    case PointFieldType::int8:
      return "INT8";
    case PointFieldType::uint8:
      return "UINT8";
    case PointFieldType::int16:
      return "INT16";
    case PointFieldType::uint16:
      return "UINT16";
    case PointFieldType::int32:
      return "INT32";
    case PointFieldType::uint32:
      return "UINT32";
    case PointFieldType::float32:
      return "FLOAT32";
    case PointFieldType::float64:
      return "FLOAT64";
  }
  return "unknown datatype " + std::to_string(static_cast<unsigned>(type));
}

RigidTransform RigidTransform::from_quaternion(Vec3d translation, double qx, double qy, double qz, double qw) {
  const double norm = std::sqrt(qx * qx + qy * qy + qz * qz + qw * qw);
  if (!translation.is_finite() || !std::isfinite(norm) || norm == 0.0) {
    throw std::invalid_argument("a transform needs a finite translation and a finite quaternion of length > 0");
  }
  const double x = qx / norm;
  const double y = qy / norm;
  const double z = qz / norm;
  const double w = qw / norm;
  RigidTransform t;
  t.rotation = {{{1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)},
                 {2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)},
                 {2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)}}};
  t.translation = translation;
  return t;
}

void decode_point_cloud2(const PointCloud2View& cloud, const RigidTransform& to_map, bool want_colors,
                         DecodedCloud& out, const std::string& name) {
  const Layout layout = check_layout(cloud, want_colors, name);
  const std::size_t total = std::size_t{cloud.width} * cloud.height;
  // The points take up to three times the data (12 bytes a point against a point_step of 4 or more).
  detail::require_memory(name, "decoding " + std::to_string(total) + " points",
                         std::uint64_t{total} * (sizeof(Vec3f) + (layout.rgb_offset ? sizeof(Rgb) : 0)));
  out.points.clear();
  out.colors.clear();
  out.non_finite = 0;
  if (total == 0) return;  // width 0 with any height: no row to walk (up to 2^32 - 1 of them)
  out.points.reserve(total);
  if (layout.rgb_offset) out.colors.reserve(total);
  for (std::uint32_t row = 0; row < cloud.height; ++row) {
    const std::uint8_t* point = cloud.data.data() + row * layout.row_step;
    for (std::uint32_t column = 0; column < cloud.width; ++column, point += cloud.point_step) {
      const Vec3d p{layout.xyz[0].read(point), layout.xyz[1].read(point), layout.xyz[2].read(point)};
      if (!p.is_finite()) ++out.non_finite;
      out.points.push_back(Vec3f(to_map.apply(p)));
      if (layout.rgb_offset) {
        const auto packed = static_cast<std::uint32_t>(load_bits(point + *layout.rgb_offset, 4, cloud.is_bigendian));
        out.colors.push_back({static_cast<std::uint8_t>(packed >> 16), static_cast<std::uint8_t>(packed >> 8),
                              static_cast<std::uint8_t>(packed)});
      }
    }
  }
}

}  // namespace umbra::ros_io
