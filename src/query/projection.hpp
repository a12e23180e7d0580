// project_tree_to_grid: a tree projected onto a 2D navigation grid (the
// algorithm behind project_to_grid, umbra/query/navigation_grid.hpp;
// src/query/navigation_grid.cpp says how). The caller holds the tree for
// reading.
#pragma once

#include "tree/occupancy_tree.hpp"
#include "umbra/core/grid.hpp"
#include "umbra/query/navigation_grid.hpp"

namespace umbra::detail {

/// project_to_grid on `tree` (a map with grid `grid`); throws as it does.
NavigationGrid project_tree_to_grid(const OccupancyTree& tree, const Grid& grid, const ProjectionOptions& options);

}  // namespace umbra::detail
