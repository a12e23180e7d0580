// The 2D navigation grid: a map projected between two heights, the grid a
// ground robot plans on (octomap_server's `projected_map`, map_server's
// PGM + YAML, Nav2's static layer).
//
//   umbra::ProjectionOptions options;
//   options.z_min = 0.1;                    // above the floor
//   options.z_max = 1.8;                    // up to the robot's height
//   const umbra::NavigationGrid grid = umbra::project_to_grid(map, options);
//   if (grid.at(i, j) == umbra::GridCell::occupied) ...
//
// What a cell is (docs/design.md, "The navigation grid"):
//  - A cell is the column of a depth-`depth` node: 2^depth x 2^depth finest
//    voxels in x and y. Its band is the finest voxels of the column whose z
//    key lies between the key of z_min and the key of z_max, both included:
//    every voxel row the interval [z_min, z_max] meets, a bound on a voxel
//    face taking the voxel above it (OctoMap's coordToKey; the rule of
//    voxel_box.hpp). The band is cut to the map.
//  - occupied: some voxel of the band is occupied;
//  - free: rule all_known: every voxel of the band is free;
//          rule any_free (octomap_server's): at least one voxel of the band
//          is free and none is occupied;
//  - unknown otherwise.
// So a coarse grid is the finest grid with its cells merged: occupied if
// any is, free if all are (all_known) or if any is and none is occupied
// (any_free).
//
// Extent: the smallest block of cells holding every cell whose band has a
// known (free or occupied) voxel; a map with nothing known in the band
// gives an empty grid (width = height = 0).
//
// Cost: two walks over the octree nodes that meet the band (the extent,
// then the cells); a node that decides its whole footprint (childless, one
// state throughout, or no wider than a cell and wholly inside the band) is
// written over its cells without looking below it, so known uniform space
// costs one node, not one voxel. Memory: one byte per cell. The map is held
// for reading during the walks.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "umbra/map/occupancy_map.hpp"

namespace umbra {

/// When a cell whose band holds no occupied voxel is free.
enum class ProjectionRule {
  all_known,  ///< every voxel of the band is free
  any_free,   ///< at least one voxel of the band is free (octomap_server's projected_map)
};

/// "all_known" / "any_free".
[[nodiscard]] std::string_view to_string(ProjectionRule rule);
/// The rule of that name; throws std::invalid_argument naming the text and the rules.
[[nodiscard]] ProjectionRule parse_projection_rule(std::string_view name);

/// A cell's value, as nav_msgs/OccupancyGrid writes it.
enum class GridCell : std::int8_t { unknown = -1, free = 0, occupied = 100 };

struct ProjectionOptions {
  double z_min = 0.0;  ///< metres; the band's lower bound
  double z_max = 0.0;  ///< metres; the band's upper bound, > z_min
  int depth = 0;       ///< cells are the columns of depth-`depth` nodes (0: finest voxels)
  ProjectionRule rule = ProjectionRule::all_known;

  /// Throws std::invalid_argument naming the first bad field (a bound that is
  /// not finite, z_min >= z_max, a negative depth).
  void validate() const;
};

/// A 2D grid of cells, row by row from the lowest y, x fastest within a row:
/// the layout of nav_msgs/OccupancyGrid's data.
struct NavigationGrid {
  double resolution = 0.0;  ///< metres, the edge of a cell (the node size at `depth`)
  int depth = 0;            ///< the depth whose node columns are the cells
  double origin_x = 0.0;    ///< metres, the lower-left corner of cell (0, 0)
  double origin_y = 0.0;
  std::uint32_t width = 0;   ///< cells along x
  std::uint32_t height = 0;  ///< cells along y
  std::vector<GridCell> cells;  ///< width * height

  [[nodiscard]] bool empty() const { return cells.empty(); }
  /// The cell in column x (0 .. width - 1) and row y (0 .. height - 1).
  [[nodiscard]] GridCell at(std::uint32_t x, std::uint32_t y) const {
    return cells[std::size_t{y} * width + x];
  }
  friend bool operator==(const NavigationGrid&, const NavigationGrid&) = default;
};

/// The map projected between options.z_min and options.z_max (the rules at
/// the top of this file). Throws std::invalid_argument for bad options or a
/// depth above the map's depth_levels, std::out_of_range when the band lies
/// wholly outside the map (naming both), MemoryLimitError when the grid's two
/// bytes a cell exceed memory_limit() (naming the grid's size).
[[nodiscard]] NavigationGrid project_to_grid(const OccupancyMap& map, const ProjectionOptions& options);

}  // namespace umbra
