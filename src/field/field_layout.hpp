// FieldLayout: the cells and bricks of a distance field, and its metric in
// integers.
//
// Cells are the depth-`depth` nodes of the map, indexed by key >> depth on
// each axis; bricks are 8^3 cells, indexed by cell >> 3. A site offset
// (dx, dy, dz) in cells gives a distance without rounding: along an axis
// with |d| = n > 0 the gap between the cell's voxel centres and the site's
// cube is (n - 1) E + 1/2 voxels (E = 2^depth voxels per cell edge), so
// twice the gap, 2 (n - 1) E + 1, is an integer, and the squared distance
// in half voxels, S = sum (2 gap)^2, is an integer too (docs/design.md,
// "Distance field"). The distance in metres is sqrt(S) * resolution / 2.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include "umbra/core/morton.hpp"

namespace umbra::detail {

/// The nearest site of a cell, as an offset in cells; x == kNoSite: none
/// within the field's maximum distance.
struct SiteOffset {
  std::int8_t x = kNoSite;
  std::int8_t y = 0;
  std::int8_t z = 0;
  static constexpr std::int8_t kNoSite = -128;
  [[nodiscard]] bool none() const { return x == kNoSite; }
};

struct BrickIndex {
  std::uint32_t x = 0, y = 0, z = 0;
  [[nodiscard]] std::uint64_t packed() const {
    return std::uint64_t{x} | (std::uint64_t{y} << 21) | (std::uint64_t{z} << 42);
  }
  static BrickIndex unpack(std::uint64_t p) {
    return {std::uint32_t(p & 0x1FFFFF), std::uint32_t((p >> 21) & 0x1FFFFF), std::uint32_t(p >> 42)};
  }
  friend bool operator==(BrickIndex, BrickIndex) = default;
};

inline constexpr int kBrickCells = 8;          // per axis
inline constexpr int kBrickVolume = 512;
inline int cell_in_brick(std::uint32_t cx, std::uint32_t cy, std::uint32_t cz) {
  return int(cx & 7u) + 8 * int(cy & 7u) + 64 * int(cz & 7u);
}

class FieldLayout {
 public:
  FieldLayout(double resolution, int depth_levels, int depth, double max_distance)
      : resolution_(resolution), depth_levels_(depth_levels), depth_(depth), max_distance_(max_distance) {
    const double half_voxels = 2.0 * max_distance / resolution;  // the cap in half voxels
    const std::uint32_t e2 = 2u << depth;                         // 2 E
    window_ = half_voxels < 1.0 ? 0 : int(std::floor((half_voxels - 1.0) / double(e2))) + 1;
    cap_squared_ = half_voxels * half_voxels;
    squared_gap_.resize(std::size_t(window_) + 1);
    for (int n = 0; n <= window_; ++n) {
      const std::uint64_t twice_gap = n == 0 ? 0 : std::uint64_t(n - 1) * e2 + 1;
      squared_gap_[std::size_t(n)] = std::uint32_t(twice_gap * twice_gap);
      gap_.push_back(double(twice_gap));
    }
  }

  [[nodiscard]] double resolution() const { return resolution_; }
  [[nodiscard]] int depth() const { return depth_; }
  [[nodiscard]] int depth_levels() const { return depth_levels_; }
  [[nodiscard]] double max_distance() const { return max_distance_; }
  /// Cells per axis of the whole map.
  [[nodiscard]] std::uint32_t cells_per_axis() const { return std::uint32_t{1} << (depth_levels_ - depth_); }
  [[nodiscard]] std::uint32_t bricks_per_axis() const { return cells_per_axis() / kBrickCells; }
  /// The largest |offset| per axis a site within max_distance can have.
  [[nodiscard]] int window() const { return window_; }
  /// Bricks (per axis, either side) within window() cells of a brick.
  [[nodiscard]] int brick_reach() const { return (window_ + kBrickCells - 1) / kBrickCells; }
  /// (2 gap)^2 for an offset of n cells along one axis, n <= window().
  [[nodiscard]] std::uint32_t squared_gap(int n) const { return squared_gap_[std::size_t(n < 0 ? -n : n)]; }
  /// Twice the gap of an offset of n cells, in voxels (see the file comment).
  [[nodiscard]] double gap(int n) const { return gap_[std::size_t(n < 0 ? -n : n)]; }
  /// S of an offset (see the file comment).
  [[nodiscard]] std::uint32_t squared(SiteOffset o) const {
    return squared_gap(o.x) + squared_gap(o.y) + squared_gap(o.z);
  }
  /// S within the cap.
  [[nodiscard]] bool within_cap(std::uint32_t s) const { return double(s) <= cap_squared_; }
  /// Metres of an offset, capped at max_distance.
  [[nodiscard]] double metres(SiteOffset o) const {
    if (o.none()) return max_distance_;
    const double d = std::sqrt(double(squared(o))) * resolution_ * 0.5;
    return d < max_distance_ ? d : max_distance_;
  }

 private:
  double resolution_;
  int depth_levels_;
  int depth_;
  double max_distance_;
  int window_ = 0;
  double cap_squared_ = 0.0;
  std::vector<std::uint32_t> squared_gap_;
  std::vector<double> gap_;
};

}  // namespace umbra::detail
