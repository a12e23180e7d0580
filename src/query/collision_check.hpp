// check_collision: whether a shape is free in a tree (the algorithm behind
// OccupancyMap::is_free; src/query/collision.cpp says how it descends).
// The caller holds the tree for reading.
#pragma once

#include "tree/occupancy_tree.hpp"
#include "umbra/core/aabb.hpp"
#include "umbra/core/grid.hpp"
#include "umbra/query/collision.hpp"
#include "umbra/query/shapes.hpp"

namespace umbra::detail {

/// Whether no voxel of the shape blocks in `tree` (a map with grid `grid`),
/// and if one does, a blocking node; throws as OccupancyMap::is_free.
/// Instantiated for every CollisionShape (collision.cpp).
template <CollisionShape Shape>
CollisionResult check_collision(const OccupancyTree& tree, const Grid& grid, const Shape& shape,
                                const CollisionOptions& options);

}  // namespace umbra::detail
