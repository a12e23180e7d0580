// cast_ray, cast_ray_octomap: ray casts on a tree, voxel for voxel as
// OctoMap's castRay (the algorithms behind OccupancyMap::cast_ray and
// cast_ray_octomap; src/query/ray_cast.cpp says how). The caller holds the
// tree for reading.
#pragma once

#include "tree/occupancy_tree.hpp"
#include "umbra/core/grid.hpp"
#include "umbra/core/vec3.hpp"
#include "umbra/query/collision.hpp"

namespace umbra::detail {

/// OccupancyMap::cast_ray on `tree` (a map with grid `grid`); throws as it does.
RayHit cast_ray(const OccupancyTree& tree, const Grid& grid, Vec3d origin, Vec3d direction,
                const RayCastOptions& options);
/// OccupancyMap::cast_ray_octomap on `tree`; throws as it does.
bool cast_ray_octomap(const OccupancyTree& tree, const Grid& grid, Vec3f origin, Vec3f direction, Vec3f& end,
                      bool ignore_unknown, double max_range);

}  // namespace umbra::detail
