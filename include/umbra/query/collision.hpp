// Options and results of collision checks, line checks and ray casts
// (OccupancyMap::is_free, OccupancyMap::cast_ray).
//
// What blocks: occupied voxels, and unknown voxels unless the caller says
// unknown space is free (a planner that must not fly into the unseen keeps
// the default). A region is free when none of its voxels blocks (shapes.hpp
// says which voxels belong to each shape). At depth d > 0 the answer is
// conservative: a depth-d node that meets the shape and holds any blocking
// voxel blocks, so a coarse check never says free where a finer one finds
// an obstacle.
#pragma once

#include <concepts>
#include <optional>

#include "umbra/core/aabb.hpp"
#include "umbra/core/node.hpp"
#include "umbra/core/vec3.hpp"
#include "umbra/query/shapes.hpp"

namespace umbra {

/// The shapes OccupancyMap::is_free checks, one at a time or a span at once.
template <typename Shape>
concept CollisionShape = std::same_as<Shape, Aabb> || std::same_as<Shape, Sphere> ||
                         std::same_as<Shape, OrientedBox> || std::same_as<Shape, Capsule> ||
                         std::same_as<Shape, Segment>;

struct CollisionOptions {
  bool unknown_is_free = false;  ///< count unknown voxels as free space
  int depth = 0;                 ///< check at this depth (0: finest voxels)
};

struct CollisionResult {
  bool free = true;
  /// When not free: one node that blocks, at the check's depth (or a
  /// childless coarser node covering it). For a segment, the first along it.
  std::optional<Node> blocking;
  explicit operator bool() const { return free; }
};

struct RayCastOptions {
  /// Metres along the ray; the ray ends at the first voxel it enters beyond
  /// this distance. <= 0: it runs to the map's edge.
  double max_range = -1.0;
  bool stop_at_unknown = false;  ///< an unknown voxel ends the ray too
  int depth = 0;                 ///< cast through depth-`depth` nodes
};

struct RayHit {
  bool hit = false;      ///< an occupied (or, when asked, unknown) voxel within range
  Node node;             ///< what was hit (when hit)
  double distance = 0.0; ///< from the origin to where the ray enters the node (0 when it starts inside)
  Vec3d point;           ///< origin + direction * distance
  explicit operator bool() const { return hit; }
};

}  // namespace umbra
