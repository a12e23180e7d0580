// VoxelBox: a block of finest voxels, lo <= key <= hi on every axis.
//
// What a box in metres means for the voxels of a map, one rule for every
// tool that takes a box after the map exists (crop_map, compare_maps,
// `umbra crop`, `umbra compare`): the voxels that hold the box's two corners
// and every voxel between them, i.e. every voxel the box meets (a corner on
// a voxel face takes the voxel above it, as OctoMap's coordToKey does). The
// same keys bound insertions under OccupancyMap::set_bounding_box.
#pragma once

#include <cstdint>

#include "umbra/core/aabb.hpp"
#include "umbra/core/grid.hpp"
#include "umbra/core/morton.hpp"

namespace umbra {

struct VoxelBox {
  Key lo;  ///< finest key of the lowest corner voxel
  Key hi;  ///< finest key of the highest corner voxel (inclusive)

  [[nodiscard]] bool contains(Key key) const {
    return key.x >= lo.x && key.x <= hi.x && key.y >= lo.y && key.y <= hi.y && key.z >= lo.z && key.z <= hi.z;
  }
  /// How many finest voxels of the depth-`depth` node whose lowest voxel is
  /// `corner` lie in the box (0 to 8^depth).
  [[nodiscard]] std::uint64_t voxels_inside(Key corner, int depth) const;
  friend bool operator==(const VoxelBox&, const VoxelBox&) = default;
};

/// The voxels of `grid` that `box` meets; a box reaching past the map is cut
/// to it. Throws std::invalid_argument for a bad box (Aabb::validate) and
/// std::out_of_range, naming the box and the map's extent, when the box
/// lies wholly outside the map.
[[nodiscard]] VoxelBox voxel_box(const Grid& grid, const Aabb& box);

}  // namespace umbra
