// Merging maps: the types of OccupancyMap::merge (occupancy_map.hpp).
//
// map.merge(other) adds other's log-odds to this map's, voxel by voxel, and
// clamps to this map's sensor model, as an update would. Both maps must have
// the same resolution and depth levels. Voxels other never observed (log-odds
// 0) change nothing; a pruned node of other counts for every voxel it covers.
// other is placed in this map by
//  - a VoxelOffset: other's voxel with key k lands on this map's voxel k + offset;
//  - a rigid Pose T (other's frame to this map's): this map's voxel with
//    centre c takes the value of other's voxel that contains T^-1 c (computed
//    in double as R^T (c - t)), if that point lies in other and that voxel is
//    known. Each voxel of this map thus gets at most one of other's voxels.
// docs/design.md ("Merging maps") has the details, the color rule and the costs.
#pragma once

#include <cstdint>

namespace umbra {

/// A shift by whole finest voxels (may be negative).
struct VoxelOffset {
  std::int64_t x = 0;
  std::int64_t y = 0;
  std::int64_t z = 0;
  friend bool operator==(const VoxelOffset&, const VoxelOffset&) = default;
};

/// What a merge did.
struct MergeStats {
  /// Finest voxels of this map that received a value (a pruned node counts
  /// all of its voxels).
  std::uint64_t voxels = 0;
  /// Node additions applied to the tree (fewer than voxels where pruned
  /// blocks land whole on nodes of this map).
  std::uint64_t nodes = 0;
};

}  // namespace umbra
