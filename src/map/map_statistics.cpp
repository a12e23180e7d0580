#include "umbra/map/map_statistics.hpp"

#include <algorithm>

namespace umbra {

MapStatistics compute_statistics(const OccupancyMap& map) {
  MapStatistics stats;
  stats.resolution = map.resolution();
  stats.depth_levels = map.depth_levels();
  stats.nodes = map.node_counts();
  stats.memory_bytes = map.memory_bytes();
  const Grid& grid = map.grid();
  map.for_each_leaf([&](const Node& leaf) {
    if (leaf.state == OccupancyState::unknown) return;
    const std::uint64_t voxels = std::uint64_t{1} << (3 * leaf.depth);
    (leaf.state == OccupancyState::occupied ? stats.occupied_voxels : stats.free_voxels) += voxels;
    const Vec3d low = grid.min_corner(leaf.key, leaf.depth);
    const double size = grid.node_size(leaf.depth);
    const Vec3d high = low + Vec3d{size, size, size};
    if (!stats.has_known_space) {
      stats.known_min = low;
      stats.known_max = high;
      stats.has_known_space = true;
      return;
    }
    for (int axis = 0; axis < 3; ++axis) {
      stats.known_min[axis] = std::min(stats.known_min[axis], low[axis]);
      stats.known_max[axis] = std::max(stats.known_max[axis], high[axis]);
    }
  });
  const double voxel_volume = stats.resolution * stats.resolution * stats.resolution;
  stats.occupied_volume_m3 = static_cast<double>(stats.occupied_voxels) * voxel_volume;
  stats.free_volume_m3 = static_cast<double>(stats.free_voxels) * voxel_volume;
  return stats;
}

}  // namespace umbra
