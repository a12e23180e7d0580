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

/// Of two offsets equally near a cell (the same S), whether `a` is the one
/// a field keeps: the canonical order that the transform and the update's
/// lowering both follow, so an updated field equals a rebuilt one bit for
/// bit. Per axis the rank of an offset d is 0 for d = 0, then -1, +1, -2,
/// +2, ... (nearer first, the negative first); axes compare z, then y,
/// then x (the order in which the transform's passes decide them last to
/// first: distance_transform.hpp).
inline bool nearer_tie(SiteOffset a, SiteOffset b) {
  const auto rank = [](int d) { return d == 0 ? 0 : 2 * (d < 0 ? -d : d) - (d < 0 ? 1 : 0); };
  if (rank(a.z) != rank(b.z)) return rank(a.z) < rank(b.z);
  if (rank(a.y) != rank(b.y)) return rank(a.y) < rank(b.y);
  return rank(a.x) < rank(b.x);
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
  /// The largest S within the cap.
  [[nodiscard]] std::uint64_t cap_squared() const { return std::uint64_t(std::floor(cap_squared_)); }
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
