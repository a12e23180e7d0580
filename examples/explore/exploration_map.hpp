// ExplorationMap: what the explorer asks of an occupancy map, so that one
// planner runs on umbra (umbra_exploration_map.hpp) and on OctoMap
// (bench/explore/octomap_exploration_map.hpp) with identical logic.
//
// Semantics both sides keep (docs/design.md, Semantics): a voxel belongs to a ball when
// its cube is within the radius of the centre; unknown voxels block the
// robot; the gain of a view counts the unknown voxels whose centres lie in
// the frustum and are not hidden behind an occupied voxel. Which threads call
// what: the mapping thread calls insert(), the planning thread the checks and
// the gain, the mapping thread (paused) for_each_free_node(); each
// implementation makes that safe its own way (umbra: its concurrency
// contract; OctoMap: a mutex).
#pragma once

#include <cstdint>
#include <span>
#include <string>

#include "umbra/core/function_ref.hpp"
#include "umbra/core/vec3.hpp"
#include "umbra/query/shapes.hpp"

namespace umbra::explore {

class ExplorationMap {
 public:
  virtual ~ExplorationMap() = default;
  /// "umbra", "octomap": names the map in results and files.
  [[nodiscard]] virtual std::string name() const = 0;
  [[nodiscard]] virtual double resolution() const = 0;

  /// The robot knows the ball it starts in is free: its voxels are set free
  /// (log-odds at the lower clamping bound) before exploring.
  virtual void assume_free(const Sphere& ball) = 0;
  /// One depth image seen from `origin`; points farther than max_range
  /// clear free space up to it and add no obstacle.
  virtual void insert(Vec3f origin, std::span<const Vec3f> points, double max_range) = 0;

  /// Whether no voxel of the ball is occupied or unknown.
  [[nodiscard]] virtual bool is_free(const Sphere& ball) const = 0;
  /// Whether the robot of `path.radius` may fly along the segment: no
  /// occupied or unknown voxel within the radius of it (the implementations
  /// differ in how they sample that volume; see their files).
  [[nodiscard]] virtual bool is_free(const Capsule& path) const = 0;
  /// Volume in m^3 of the unknown space a sensor with this view would see.
  [[nodiscard]] virtual double gain(const Frustum& view) const = 0;

  /// Calls visit(min, max) with the cube of every free leaf (for coverage).
  virtual void for_each_free_node(FunctionRef<void(Vec3d min, Vec3d max)> visit) const = 0;
  /// Bytes the map holds.
  [[nodiscard]] virtual std::size_t memory_bytes() const = 0;
};

}  // namespace umbra::explore
