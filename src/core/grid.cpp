#include "umbra/core/grid.hpp"

#include <charconv>
#include <cmath>
#include <string>
#include <stdexcept>

namespace umbra {

void Grid::validate_resolution(double resolution) {
  if (resolution >= kMinResolution && resolution <= kMaxResolution) return;  // NaN fails this
  char text[32];
  const auto written = std::to_chars(text, text + sizeof text, resolution);  // shortest exact form: 1e-300, nan
  throw std::invalid_argument("resolution must be a number of metres in [0.0001, 1000] (0.1 mm to 1 km), got " +
                              std::string(text, written.ptr));
}

Grid::Grid(double resolution, int depth_levels)
    : resolution_(resolution),
      inverse_resolution_(1.0 / resolution),
      depth_levels_(depth_levels),
      key_offset_(0) {
  validate_resolution(resolution);
  if (depth_levels < 1 || depth_levels > kMaxDepthLevels) {
    throw std::invalid_argument("depth_levels must be in [1, " + std::to_string(kMaxDepthLevels) +
                                "], got " + std::to_string(depth_levels));
  }
  key_offset_ = 1u << (depth_levels - 1);
}

namespace {

/// The shortest text that reads back as exactly `value` (-3276.800048828125
/// for the float nearest -3276.8): an error about a value at the map's edge
/// must show the value that was tested, not one rounded back inside.
std::string exact_text(double value) {
  char text[32];
  const auto written = std::to_chars(text, text + sizeof text, value);
  return std::string(text, written.ptr);
}

}  // namespace

Key Grid::key(Vec3d c) const {
  if (auto k = key_checked(c)) return *k;
  std::string message = "coordinate (" + exact_text(c.x) + ", " + exact_text(c.y) + ", " + exact_text(c.z) +
                        ") is outside the map, which spans [" + exact_text(-half_extent()) + ", " +
                        exact_text(half_extent()) + ") on every axis (resolution " + exact_text(resolution_) +
                        ", depth levels " + std::to_string(depth_levels_) + ")";
  // The key is floor(c * (1 / resolution)), as OctoMap computes it: a
  // coordinate a rounding step inside the span can still land outside.
  for (int axis = 0; axis < 3; ++axis) {
    const double v = c[axis];
    if (axis_key(v) || !(v >= -half_extent() && v < half_extent())) continue;
    message += "; " + std::string(1, "xyz"[axis]) + " = " + exact_text(v) +
               " rounds outside: its key, floor(x * (1 / resolution)) as OctoMap computes it, is " +
               exact_text(std::floor(v * inverse_resolution_)) + ", outside [-" + std::to_string(key_offset_) +
               ", " + std::to_string(key_offset_) + ")";
  }
  throw std::out_of_range(message);
}

Vec3d Grid::min_corner(Key key, int depth) const {
  Vec3d corner;
  for (int axis = 0; axis < 3; ++axis) {
    const std::int64_t first = std::int64_t(key[axis] >> depth) << depth;
    corner[axis] = double(first - std::int64_t(key_offset_)) * resolution_;
  }
  return corner;
}

Vec3d Grid::center(Key key, int depth) const {
  // A voxel's centre is OctoMap's keyToCoord to the bit (the corner plus a
  // half voxel can round differently, which decides ties such as a centre
  // exactly max_range from a sensor).
  if (depth == 0) return {axis_center(key.x), axis_center(key.y), axis_center(key.z)};
  const double half = 0.5 * node_size(depth);
  return min_corner(key, depth) + Vec3d{half, half, half};
}

}  // namespace umbra
