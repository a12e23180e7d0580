// crop_map: the part of a map inside a box, as a new map.
//
// The voxels of the VoxelBox keep their values (log-odds, float for float)
// and colors (with the count of samples behind them, so that later color
// updates average as they would have); every other voxel becomes unknown.
// A pruned node that the box cuts is split just enough to keep its part.
// The new map has the source's resolution, depth levels, sensor model,
// thresholds, color, insertion box and automatic pruning (on: equal
// siblings the cut leaves are merged, as after any update).
//
// OctoMap's edit_octree does the same with its -bbx option. Cost: one walk
// over the source's nodes that meet the box: O(those nodes) time, and the
// new map holds only what is kept.
#pragma once

#include "umbra/map/occupancy_map.hpp"
#include "umbra/map/voxel_box.hpp"

namespace umbra {

/// The voxels of `keep` from `map`, the rest unknown. The box must lie in
/// the map (voxel_box() gives one that does): std::out_of_range otherwise.
[[nodiscard]] OccupancyMap crop_map(const OccupancyMap& map, const VoxelBox& keep);

}  // namespace umbra
