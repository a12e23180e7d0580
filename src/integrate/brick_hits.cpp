#include "integrate/brick_hits.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdlib>

#include "ray/ray_direction.hpp"
#include "tree/update_batch.hpp"
#include "umbra/core/morton.hpp"
#include "umbra/integrate/insert_options.hpp"

namespace umbra {

namespace {

/// Where all of a brick's voxels lie against max_range.
enum class BrickRange { within, beyond, straddles };

/// Bounds, in double, of the squared length that octomap_norm_exceeds
/// computes in float for any voxel centre of the brick whose lowest key is
/// `first` (4 keys an axis), and where that puts the brick against
/// `max_range`. Each axis' float offset differs from the exact one by the
/// rounding of the centre to float (at most 2^-24 |c|) and of the
/// difference (at most 2^-24 |c - o| <= 2^-24 (|c| + |o|)): slack
/// 2^-22 (|c| + |o|) covers both. The float squares and sums add at most
/// about 5 roundings of 2^-24 relative (the library builds with
/// -ffp-contract=off): 2^-20 covers them. The decision is then
/// octomap_norm_exceeds' own test for every voxel of the brick.
BrickRange brick_range(const Grid& grid, Key first, Vec3f origin, double max_range) {
  double lowest = 0.0;   // squared length, lower bound
  double highest = 0.0;  // upper bound
  const std::uint32_t keys[3] = {first.x, first.y, first.z};
  const double from[3] = {origin.x, origin.y, origin.z};
  for (int axis = 0; axis < 3; ++axis) {
    const double low = grid.axis_center(keys[axis]) - from[axis];
    const double high = grid.axis_center(keys[axis] + 3) - from[axis];
    const double magnitude = std::max(std::abs(grid.axis_center(keys[axis])),
                                      std::abs(grid.axis_center(keys[axis] + 3))) + std::abs(from[axis]);
    const double slack = magnitude * 0x1p-22;
    const double far = std::max(std::abs(low), std::abs(high)) + slack;
    const double near = (low <= 0.0 && high >= 0.0) ? 0.0 : std::max(0.0, std::min(std::abs(low), std::abs(high)) - slack);
    highest += far * far;
    lowest += near * near;
  }
  const double limit = max_range * max_range;
  constexpr double kRounding = 0x1p-20;
  if (highest * (1.0 + kRounding) < limit * (1.0 - 1e-9)) return BrickRange::within;
  if (lowest * (1.0 - kRounding) > limit * (1.0 + 1e-9)) return BrickRange::beyond;
  return BrickRange::straddles;
}

}  // namespace

BrickHits::BrickHits(const Grid& grid, Vec3f origin, double max_range, UpdateBatch& batch, InsertStats& stats)
    : grid_(grid), origin_(origin), max_range_(max_range), batch_(batch), stats_(stats) {}

std::uint64_t BrickHits::in_range(std::uint64_t voxels) const {
  if (max_range_ <= 0.0) return voxels;
  switch (brick_range(grid_, morton::decode(brick_), origin_, max_range_)) {
    case BrickRange::within:
      return voxels;
    case BrickRange::beyond:
      return 0;
    case BrickRange::straddles:
      break;
  }
  std::uint64_t kept = 0;
  for (std::uint64_t rest = voxels; rest != 0; rest &= rest - 1) {
    const auto bit = static_cast<unsigned>(std::countr_zero(rest));
    const Vec3f centre = grid_.center_f(morton::decode(brick_ | bit));
    if (!octomap_norm_exceeds(centre - origin_, max_range_)) kept |= std::uint64_t{1} << bit;
  }
  return kept;
}

void BrickHits::flush() {
  if (voxels_ == 0) return;
  const std::uint64_t voxels = voxels_;
  voxels_ = 0;
  const std::uint64_t kept = in_range(voxels);
  stats_.truncated += static_cast<std::size_t>(std::popcount(voxels & ~kept));
  if (kept != 0) stats_.hits += static_cast<std::size_t>(batch_.add_hits_in_brick(brick_, kept));
}

}  // namespace umbra
