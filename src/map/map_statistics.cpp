// compute_statistics: one walk of the tree's childless nodes under one read
// of the map. It works on keys, not metres: per depth the smallest and
// largest first key of a known node on each axis, turned into metres once at
// the end with Grid::min_corner's own arithmetic (rounding is monotonic, so
// the bounds are those of the node-by-node computation to the bit). Going
// through the public for_each_leaf instead (a Node with centre and color
// for every leaf) took 66 ms on the 3DTK map at 5 cm, as long as saving it;
// this takes 18 ms.
#include "umbra/map/map_statistics.hpp"

#include <algorithm>
#include <array>
#include <limits>

#include "map/map_access.hpp"

namespace umbra {
namespace {

/// Smallest and largest first key, on each axis, of the known nodes of one depth.
struct KeyRange {
  std::array<std::uint32_t, 3> low{std::numeric_limits<std::uint32_t>::max(), std::numeric_limits<std::uint32_t>::max(),
                                   std::numeric_limits<std::uint32_t>::max()};
  std::array<std::uint32_t, 3> high{};
  bool any = false;

  void add(const Key& key) {
    for (int axis = 0; axis < 3; ++axis) {
      low[axis] = std::min(low[axis], key[axis]);
      high[axis] = std::max(high[axis], key[axis]);
    }
    any = true;
  }
};

}  // namespace

MapStatistics compute_statistics(const OccupancyMap& map) {
  MapStatistics stats;
  stats.resolution = map.resolution();
  stats.depth_levels = map.depth_levels();
  stats.nodes = map.node_counts();
  stats.memory_bytes = map.memory_bytes();
  std::array<KeyRange, kMaxDepthLevels + 1> ranges;
  detail::MapAccess::read(map, [&](const OccupancyTree& tree) {
    const LogOddsThresholds& thresholds = tree.thresholds();
    tree.for_each_leaf([&](NodeRef node, std::uint64_t code) {
      const OccupancyState state = thresholds.classify(tree.log_odds(node));
      if (state == OccupancyState::unknown) return;
      const std::uint64_t voxels = std::uint64_t{1} << (3 * node.depth);
      (state == OccupancyState::occupied ? stats.occupied_voxels : stats.free_voxels) += voxels;
      ranges[static_cast<std::size_t>(node.depth)].add(morton::decode(code));  // `code` is the node's first voxel
    });
  });
  const Grid& grid = map.grid();
  for (int depth = 0; depth <= kMaxDepthLevels; ++depth) {
    const KeyRange& range = ranges[static_cast<std::size_t>(depth)];
    if (!range.any) continue;
    const Vec3d low = grid.min_corner(Key{range.low[0], range.low[1], range.low[2]}, depth);
    const double size = grid.node_size(depth);
    const Vec3d high = grid.min_corner(Key{range.high[0], range.high[1], range.high[2]}, depth) + Vec3d{size, size, size};
    if (!stats.has_known_space) {
      stats.known_min = low;
      stats.known_max = high;
      stats.has_known_space = true;
      continue;
    }
    for (int axis = 0; axis < 3; ++axis) {
      stats.known_min[axis] = std::min(stats.known_min[axis], low[axis]);
      stats.known_max[axis] = std::max(stats.known_max[axis], high[axis]);
    }
  }
  const double voxel_volume = stats.resolution * stats.resolution * stats.resolution;
  stats.occupied_volume_m3 = static_cast<double>(stats.occupied_voxels) * voxel_volume;
  stats.free_volume_m3 = static_cast<double>(stats.free_voxels) * voxel_volume;
  return stats;
}

}  // namespace umbra
