// copy_voxels: a chosen part of a tree copied into a new map (crop_map's
// copy; the moving window's pieces that leave its box). For the map's own code.
#pragma once

#include <cstdint>

#include "tree/occupancy_tree.hpp"
#include "umbra/core/function_ref.hpp"
#include "umbra/map/occupancy_map.hpp"

namespace umbra::detail {

/// How many finest voxels of the depth-`depth` node whose lowest voxel is
/// `corner` are copied: 0, all 8^depth, or some (then its children are asked).
using VoxelsKept = FunctionRef<std::uint64_t(Key corner, int depth)>;

/// Copies into `into` (a new, empty map with from's depth levels) the
/// voxels of `from` that `kept` keeps, values and colors as they are; the
/// rest stays unknown. Nothing is pruned (the caller prunes when it wants).
/// Returns whether some copied voxel was known or colored. The caller holds
/// `from` for reading.
bool copy_voxels(const OccupancyTree& from, OccupancyMap& into, VoxelsKept kept);

}  // namespace umbra::detail
