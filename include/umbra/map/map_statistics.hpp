// MapStatistics: what `umbra info` reports about a map, in one pass over
// its leaves (cost: O(childless nodes)).
//
// Voxel counts are in finest-depth voxels: an inner leaf at depth d counts
// for the 8^d voxels it covers. Bounds are those of the known (occupied or
// free) space, in metres.
#pragma once

#include <cstdint>

#include "umbra/core/vec3.hpp"
#include "umbra/map/occupancy_map.hpp"
#include "umbra/core/node.hpp"

namespace umbra {

struct MapStatistics {
  double resolution = 0.0;
  int depth_levels = 0;
  NodeCounts nodes;
  std::size_t memory_bytes = 0;
  std::uint64_t occupied_voxels = 0;
  std::uint64_t free_voxels = 0;
  double occupied_volume_m3 = 0.0;
  double free_volume_m3 = 0.0;
  bool has_known_space = false;  ///< false: the bounds below are meaningless
  Vec3d known_min;
  Vec3d known_max;
};

MapStatistics compute_statistics(const OccupancyMap& map);

}  // namespace umbra
