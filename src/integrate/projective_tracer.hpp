// ProjectiveTracer: the misses of one depth image, found from the tree down.
//
// Instead of walking a ray per pixel, the projective integrator walks the
// octree's nodes from the top and asks the image about each node at once
// (ProjectiveFrame's pyramid of the nearest and farthest readings over the
// pixels the node projects onto):
//  - a node that lies wholly in front of the nearest reading under it, with
//    a reading on every pixel it covers, inside the image, the range and the
//    box, is cleared whole (one mark in the batch, however many voxels);
//  - a node behind the farthest reading under it, outside the image, the
//    range or the box, or over pixels without readings, is skipped;
//  - any other node is split into its children; at depth 2 (a brick of 4 x 4
//    x 4 voxels, the batch's unit) the rule is evaluated voxel by voxel.
// The whole-node decisions are sufficient conditions of the voxel rule
// (projective_frame.hpp), computed in double with margins larger than the
// rule's float rounding, so the misses are exactly the rule's, whatever
// nodes the walk happens to decide whole; work grows with the area of the
// borders of free space (the surface, the image's edges, holes), not with
// the number of pixels or the volume.
//
// Known obstacles (the map's occupied voxels) inside a node to be cleared
// whole make it split instead, down to the bricks, where each obstacle the
// rule would clear is cleared only if a ray crosses it
// (ProjectiveRule::ray_crosses).
//
// Any node can be traced on its own into any batch, so the tracing splits
// into independent subtrees for threads (Integrator::trace_image).
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <vector>

#include "integrate/projective_frame.hpp"
#include "tree/occupancy_tree.hpp"
#include "tree/update_batch.hpp"

namespace umbra {

class ProjectiveTracer {
 public:
  enum class Decision : std::uint8_t { none, all, split };

  explicit ProjectiveTracer(const ProjectiveRule& rule);

  /// What the rule does to the voxels of the depth-`depth` node (depth >= 2)
  /// whose first voxel is `code`: clears none, clears all, or only some (or
  /// it cannot tell from the node as a whole).
  [[nodiscard]] Decision classify(std::uint64_t code, int depth) const;

  /// Adds the misses of the depth-`depth` node `code` (depth >= 2, and not
  /// below a node that cells may decide) to `batch`.
  void trace(std::uint64_t code, int depth, UpdateBatch& batch) const {
    trace_node(code, morton::decode(code), depth, batch);
  }

  /// The depth-`depth` nodes (in Morton order) below the node `code` whose
  /// subtrees hold all the rule's work: split nodes are opened down to
  /// `depth`, nodes cleared whole are returned as they are (with their own
  /// depth). Used to hand subtrees to threads.
  struct Task {
    std::uint64_t code;
    int depth;
    Decision decision;  ///< all or split
  };
  void collect(std::uint64_t code, int depth, int task_depth, std::vector<Task>& tasks) const;

 private:
  /// classify() and trace() of a node whose first voxel's key is `first`
  /// (the walk keeps keys, so that nodes are not decoded).
  /// With `all_in_range`: whether every voxel centre of the node lies
  /// within max_range (true without a range), set unless the node lies
  /// outside the box.
  [[nodiscard]] Decision classify_node(Key first, int depth, bool* all_in_range = nullptr) const;
  void trace_node(std::uint64_t code, Key first, int depth, UpdateBatch& batch) const;
  /// A split brick: the voxels it clears, in the box. `in_range`: known to
  /// lie within max_range as a whole (its parent does).
  void trace_brick(std::uint64_t brick, Key first, bool in_range, UpdateBatch& batch) const;
  /// Whether the map holds an obstacle in the depth-`depth` node `code`.
  [[nodiscard]] bool holds_obstacle(std::uint64_t code, int depth) const;

  /// Whether the node whose voxel centres span [lo, lo + span] on each map
  /// axis lies wholly beyond the edge reach outside one side of the image
  /// (no voxel of it is seen); `far`: the farthest centre's distance from
  /// the camera, `pad`: classify_node's.
  [[nodiscard]] bool outside_image_sides(Vec3d lo, double span, double far, double pad) const;

  const ProjectiveRule& rule_;
  /// The image's four sides as planes through the camera in the map frame
  /// (left, right, top, bottom): a point p sees the image's side of plane i
  /// where side_planes_[i] . (p - origin) + edge_reach >= 0.
  std::array<Vec3d, 4> side_planes_;
  double side_planes_scale_ = 0.0;  ///< fx + fy + the four planes' |offsets|: bounds a plane's terms per metre
  // Looks up known obstacles along the walk (a walk is in Morton order, so
  // consecutive lookups share most of their path). One per tracer: a
  // tracer belongs to one thread.
  mutable std::optional<OccupancyTree::Cursor> cursor_;
};

}  // namespace umbra
