// RayTracer: one worker's share of a scan, traced into its own UpdateBatch.
//
// The integrator splits a scan's rays over workers; each worker owns a
// RayTracer (its batch and scratch buffers), so tracing needs no locks, and
// the batches are merged before the tree is updated. What every tracer of a
// scan shares is the read-only ScanContext.
//
// Per ray (see integrator.hpp for the rules):
//  - the ray to a point beyond max_range is cut there and gives no hit;
//  - with a bounding box the ray is clipped to it (begin and end move
//    inwards; a clipped end gives a miss instead of a hit) and only voxels
//    in the box are updated;
//  - simple / discrete: every voxel before the end voxel gets a miss
//    (OctoMap's walk), collected a brick (4x4x4 voxels) at a time;
//  - fast: the rays (one per end voxel, to its first point) are grouped by
//    the depth-`clear_depth` node their end lies in. The group's middle ray,
//    the guide, walks the coarse nodes and clears whole every node the
//    group's rays may cross along it (its node widened by the spread of the
//    group) until one of them may not be cleared: a node the map says holds
//    an obstacle, that holds or touches a hit of this scan, or one of the
//    last `fine_steps` before the end node. From there every ray goes on by
//    itself: nodes it may clear are cleared whole, the others it crosses
//    voxel by voxel, as do the last `fine_steps` nodes and the end node.
//    Where coarse nodes span many voxels (clear_depth > walk_depth, at
//    millimetre resolutions), a node the ray may not clear whole is split
//    into the children it crosses, which are cleared whole where allowed,
//    down to walk_depth: only the small nodes at or next to obstacles and
//    hits, and the tail (the end node and the `fine_steps` nodes before it,
//    counted in nodes of walk_depth), are walked voxel by voxel.
//    Hits are added for the whole scan before any ray
//    (ScanContext::hits_first), so that every tracer knows them.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "umbra/core/aabb.hpp"
#include "umbra/core/grid.hpp"
#include "umbra/core/vec3.hpp"
#include "ray/node_walk.hpp"
#include "tree/occupancy_tree.hpp"
#include "tree/update_batch.hpp"

namespace umbra {

struct InsertStats;

/// The voxels of a bounding box: finest keys [min, max] on every axis.
struct KeyBox {
  Key min;
  Key max;
  [[nodiscard]] bool contains(Key k) const {
    return k.x >= min.x && k.x <= max.x && k.y >= min.y && k.y <= max.y && k.z >= min.z && k.z <= max.z;
  }
};

/// What all tracers of one scan read.
struct ScanContext {
  const Grid* grid = nullptr;
  Vec3f origin;
  Key origin_key;
  double max_range = -1.0;   ///< <= 0: unlimited
  bool fast = false;         ///< the fast integrator (else simple / discrete rules)
  int clear_depth = 0;       ///< fast: depth of the nodes cleared whole
  /// fast: a node deeper than this that may not be cleared whole is split
  /// into its children, each cleared whole if allowed; nodes at this depth
  /// are walked voxel by voxel. Equal to clear_depth: no splitting.
  int walk_depth = 0;
  int fine_steps = 0;        ///< fast: nodes before the end node traced voxel by voxel
  bool hits_first = false;   ///< hits are already in every tracer's batch
  const OccupancyTree* tree = nullptr;  ///< fast: where obstacles are (read only)
  std::optional<Aabb> box;   ///< clip rays to this box
  std::optional<KeyBox> box_keys;
};

/// A ray after max-range truncation and box clipping.
struct PreparedRay {
  Vec3f begin;
  Key begin_key;
  Vec3f end;
  Key end_key;
  std::uint64_t end_code;  ///< Morton code of end_key
  bool hit;       ///< the end voxel gets a hit
  bool miss_end;  ///< the end voxel gets a miss (the ray was clipped there)
};

/// The ray to `point` into `ray`, or false (counted in `stats` when given)
/// when it updates nothing (then `ray` holds garbage).
bool prepare_ray(const ScanContext& scan, Vec3f point, InsertStats* stats, PreparedRay& ray);

// Aligned to a cache line: the tracers of a scan are allocated one after
// the other, and their hot members (the batch's path cache) must not share a
// line with the neighbour's.
class alignas(64) RayTracer {
 public:
  /// Empties the batch for a scan of a map with `depth_levels`.
  void start(int depth_levels);
  /// Traces the rays to `ends` (points, or voxel centres) into the batch.
  void trace(const ScanContext& scan, std::span<const Vec3f> ends, InsertStats& stats);
  /// The fast integrator's first pass: the hits of a scan (finest codes, in
  /// consecutive parts), and the marks that keep the coarse nodes next to
  /// them from being cleared whole.
  void add_hits(const ScanContext& scan, std::span<const std::vector<std::uint64_t>> hit_parts);
  /// The fast integrator: `rays`, whose ends all lie in one coarse node.
  void trace_group(const ScanContext& scan, std::span<const PreparedRay> rays, OccupancyTree::Cursor& cursor);

  [[nodiscard]] UpdateBatch& batch() { return batch_; }
  /// Scratch memory kept between scans (the batch is emptied after each).
  [[nodiscard]] std::size_t memory_bytes() const;

 private:
  /// Misses for the voxels from `from` up to, not including, the voxel of `to`.
  void add_segment_misses(const ScanContext& scan, Vec3f from, Key from_key, Vec3f to, Key to_key);
  /// Misses for the voxels of the runs walk(run) hands to run(brick, voxels)
  /// (only those in the box, if there is one).
  template <typename Walk>
  void add_walk_misses(const ScanContext& scan, Walk&& walk);
  void add_end(const ScanContext& scan, const PreparedRay& ray);
  /// Marks the depth-`depth` nodes holding or next to one of `hits` (finest
  /// codes), and their ancestors up to `up_to`, so that they are not cleared whole.
  void keep_neighbours(const ScanContext& scan, std::span<const std::uint64_t> hits, int depth, int up_to);
  /// Fast integrator: clears the depth-`depth` node `code` (walk_depth <=
  /// depth <= clear_depth) whole if nothing forbids it (a known obstacle, a
  /// hit of this scan in or next to it, the box); true if it is cleared whole now.
  bool clear_node_whole(const ScanContext& scan, std::uint64_t code, int depth, OccupancyTree::Cursor& cursor);
  /// Fast integrator: misses for the part of a ray from `a` to `b` (both in
  /// the depth-`depth` node `code`, which may not be cleared whole): children
  /// cleared whole where allowed, voxel by voxel at walk_depth (in the
  /// ray's end node up to, not including, its end voxel).
  void split_node(const ScanContext& scan, std::uint64_t code, int depth, Vec3d a, Vec3d b,
                  OccupancyTree::Cursor& cursor);
  /// Whether the depth-`depth` node `code` holds one of the ray's tail nodes.
  [[nodiscard]] bool holds_tail(std::uint64_t code, int depth) const;
  /// Fast integrator: one ray from `from` (on it) to its end: nodes cleared
  /// whole where allowed, voxel by voxel elsewhere and over the last
  /// fine_steps nodes and the end node.
  void trace_rest(const ScanContext& scan, const PreparedRay& ray, Vec3f from, Key from_key,
                  OccupancyTree::Cursor& cursor);

  /// What clear_node_whole decided for a node in this scan (it cannot
  /// change during a scan), direct-mapped by the low 4 bits of the node's
  /// coordinates: rays of one group cross the same nodes.
  struct NodeDecision {
    std::uint64_t code;
    int depth;
    bool cleared;
  };
  static constexpr std::size_t kDecisions = 4096;

  UpdateBatch batch_;
  std::vector<NodeDecision> decisions_ = std::vector<NodeDecision>(kDecisions);
  std::vector<NodeCrossing> crossings_;  // fast: the guide ray's coarse nodes
  std::vector<std::uint64_t> tail_;      // fast: the nodes one ray traces voxel by voxel whatever
  std::uint64_t end_code_ = 0;           // fast, splitting: the traced ray's end voxel ...
  Vec3f end_;                            // ... and end point
};

}  // namespace umbra
