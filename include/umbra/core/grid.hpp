// The voxel grid of a map: resolution, depth levels, coordinate <-> key.
//
// Depth conventions, fixed here once: depth 0 is the finest voxel (edge
// `resolution`); a node at depth d has edge resolution * 2^d; the root is at
// depth `depth_levels` and covers 2^depth_levels voxels per axis, centred on
// the origin. The key of coordinate c is floor(c / resolution) +
// 2^(depth_levels - 1), computed as OctoMap does (c times the reciprocal of
// the resolution, in double) so that keys agree with OctoMap bit for bit.
#pragma once

#include <cmath>
#include <cstdint>
#include <optional>

#include "umbra/core/morton.hpp"
#include "umbra/core/vec3.hpp"

namespace umbra {

/// The voxel edges a map may have, in metres: 0.1 mm to 1 km. Maps, map
/// files and the command line all refuse anything else (and NaN, infinities).
inline constexpr double kMinResolution = 1e-4;
inline constexpr double kMaxResolution = 1e3;

class Grid {
 public:
  /// Throws std::invalid_argument unless resolution is in [kMinResolution,
  /// kMaxResolution] and depth_levels is in [1, 21].
  Grid(double resolution, int depth_levels);

  /// Throws std::invalid_argument "resolution must be ... got X" unless
  /// resolution is in [kMinResolution, kMaxResolution].
  static void validate_resolution(double resolution);

  [[nodiscard]] double resolution() const { return resolution_; }
  /// 1 / resolution: coordinates are multiplied by it to find their keys.
  [[nodiscard]] double inverse_resolution() const { return inverse_resolution_; }
  [[nodiscard]] int depth_levels() const { return depth_levels_; }
  /// Edge length of a node at `depth`.
  [[nodiscard]] double node_size(int depth) const { return resolution_ * double(1u << depth); }
  /// The map spans [-half_extent, half_extent) on every axis.
  [[nodiscard]] double half_extent() const { return resolution_ * double(key_offset_); }

  /// Finest key of a coordinate, or nothing if it is outside the map (or not finite).
  [[nodiscard]] std::optional<Key> key_checked(Vec3d c) const {
    Key key;
    for (int axis = 0; axis < 3; ++axis) {
      const auto k = axis_key(c[axis]);
      if (!k) return std::nullopt;
      key[axis] = *k;
    }
    return key;
  }
  [[nodiscard]] std::optional<Key> key_checked(Vec3f c) const { return key_checked(Vec3d(c)); }

  /// Finest key of a coordinate; throws std::out_of_range naming the
  /// coordinate and the map's extent when it lies outside.
  [[nodiscard]] Key key(Vec3d c) const;

  /// Finest key along one axis, or nothing when outside [0, 2^depth_levels).
  [[nodiscard]] std::optional<std::uint32_t> axis_key(double coordinate) const {
    const double scaled = inverse_resolution_ * coordinate;
    // floor(scaled) without calling libm (no SSE4.1 roundsd on baseline
    // x86-64: a call per coordinate was the largest cost of discretising a
    // Kinect frame). Range first, written so that NaN fails it; then the
    // truncation is exact and one comparison turns it into floor.
    if (!(scaled >= -double(key_offset_) && scaled < double(key_offset_))) return std::nullopt;
    auto whole = static_cast<std::int64_t>(scaled);
    whole -= static_cast<double>(whole) > scaled ? 1 : 0;
    return static_cast<std::uint32_t>(whole + key_offset_);
  }

  /// Centre of the finest voxel with index k along an axis (OctoMap's keyToCoord).
  [[nodiscard]] double axis_center(std::uint32_t k) const {
    return (double(std::int64_t(k) - std::int64_t(key_offset_)) + 0.5) * resolution_;
  }
  /// Centre of the node at `depth` that contains finest key `key`.
  [[nodiscard]] Vec3d center(Key key, int depth = 0) const;
  /// Lower corner of the node at `depth` that contains finest key `key`.
  [[nodiscard]] Vec3d min_corner(Key key, int depth = 0) const;
  /// Centre of a finest voxel rounded to float, as OctoMap's keyToCoord(OcTreeKey).
  [[nodiscard]] Vec3f center_f(Key key) const {
    return {float(axis_center(key.x)), float(axis_center(key.y)), float(axis_center(key.z))};
  }

  /// 2^(depth_levels - 1): the key of coordinate 0.
  [[nodiscard]] std::uint32_t key_offset() const { return key_offset_; }
  /// Finest keys per axis: 2^depth_levels.
  [[nodiscard]] std::uint32_t keys_per_axis() const { return key_offset_ * 2u; }

  friend bool operator==(const Grid& a, const Grid& b) {
    return a.resolution_ == b.resolution_ && a.depth_levels_ == b.depth_levels_;
  }

 private:
  double resolution_;
  double inverse_resolution_;
  int depth_levels_;
  std::uint32_t key_offset_;
};

}  // namespace umbra
