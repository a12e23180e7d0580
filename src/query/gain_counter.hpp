// GainCounter: the information gain of one pose at a time (definition in
// include/umbra/query/information_gain.hpp; how and why in docs/design.md,
// "Information gain").
//
// For a pose it
//  1. draws the occupied voxels and solid occupied nodes of the field of
//     view into a ViewImage (the obstacles, grown by the margin that covers
//     the ray walk's rounding) and into an OccupiedBitmap;
//  2. walks the tree through the nodes that hold unknown space and whose
//     voxel centres can lie in the frustum, and decides whole nodes:
//     visible when the node's footprint in the image shows no obstacle
//     nearer than its farthest centre (its unknown voxels in the frustum
//     are then counted without looking at rays); hidden when an
//     OcclusionSweep proves every walk to it blocked. Any other node is
//     split (a childless node into virtual children of its value);
//  3. decides each remaining voxel by its own ray: visible when its pixel
//     shows no obstacle before it, or none of the pixel's candidate
//     obstacles comes near the ray; blocked when the ray passes through the
//     inside of a candidate; otherwise (rays grazing an obstacle, pixels
//     with too many obstacles) the voxel walk itself decides, stopping at
//     the first occupied voxel.
// The fast method also decides an undecided node of at most 2^fast_depth
// voxels per edge by the rays to its two opposite corner voxels when they
// agree (both visible: counted whole; both blocked: skipped), and splits it
// when they do not. Inside the frustum it asks the corners without the
// image, and it sweeps nothing: a hidden node's corners are blocked, so
// both give its answers for less.
//
// Every "surely" uses `margin_`, a bound on how far the walk's float
// arithmetic strays from the exact segment (see margin_for()): a voxel the
// walk visits is always within the margin of the segment, and the walk
// always visits a voxel whose inside, shrunk by the margin, the segment
// crosses. When the margin is not small against the voxels (huge
// coordinates), nothing is decided from the image and every voxel is walked.
//
// Cost: drawing is O(obstacles in view x their footprint in pixels); the
// walk visits O(nodes on the boundaries of visibility and of the frustum);
// a walked ray costs a few nanoseconds per voxel it passes. One counter per
// thread: it keeps its image and buffers between poses. The caller holds
// the map for reading.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <vector>

#include "query/geometry.hpp"
#include "query/occlusion_sweep.hpp"
#include "query/view_image.hpp"
#include "tree/occupancy_tree.hpp"
#include "umbra/core/grid.hpp"
#include "umbra/query/information_gain.hpp"
#include "umbra/query/shapes.hpp"

namespace umbra::detail {

class GainCounter {
 public:
  explicit GainCounter(const Grid& grid);
  /// The gain of `frustum` (validated by the caller) in `tree`, which the
  /// caller holds for reading. Throws std::out_of_range when the frustum's
  /// origin lies outside the map.
  GainResult count(const OccupancyTree& tree, const Frustum& frustum, const GainOptions& options);
  /// The work the last count() took, in GainOptions::max_steps's steps.
  [[nodiscard]] std::uint64_t steps() const { return steps_; }

 private:
  enum class Visibility : unsigned char { visible, blocked, undecided };

  void setup_pose(const Frustum& frustum);
  /// The farthest distance from `apex` of a point of an occupied voxel that
  /// lies within `range` of it (0 when there is none), or a bound at least
  /// that: beyond it no walk meets an obstacle.
  [[nodiscard]] double obstacle_reach(Vec3d apex, double range) const;
  /// Sets the bits of the drawn obstacles in a bitmap covering them (within
  /// `reach` of the apex). Throws MemoryLimitError naming the range when
  /// the bitmap would need more than memory_limit().
  void fill_occupied_bitmap(double reach);
  void draw_obstacles(const FrustumGeometry& view, NodeRef ref, Key key, Overlap overlap);
  void draw_solid_obstacle(const FrustumGeometry& view, Key key, int depth);
  // The walk over unknown space: a tree node, or a region of one value (a
  // childless node or part of one).
  void visit_node(NodeRef ref, Key key, Overlap overlap);
  void visit_region(Key key, int depth, float value, Overlap overlap);
  // Counting every unknown voxel in the frustum, once visibility is settled.
  void count_node(NodeRef ref, Key key, Overlap overlap);
  void count_region(Key key, int depth, float value, Overlap overlap);
  void add(std::uint64_t voxels, float value);
  /// Counts work (see GainOptions::max_steps); past the limit, refuse().
  void spend(std::uint64_t steps) {
    steps_ += steps;
    if (steps_ > max_steps_) refuse();
  }
  /// Throws std::invalid_argument naming the range, the resolution and the limit.
  [[noreturn]] void refuse() const;
  /// What the image (and, if `sweep`, an OcclusionSweep) proves of a node.
  [[nodiscard]] Visibility node_visibility(Key key, int depth, bool sweep);
  bool voxel_visible(Key key);
  /// Whether one obstacle drawn into the middle pixel of `rect` (the
  /// footprint of `targets`) surely hides every target.
  [[nodiscard]] bool hidden_by_one_candidate(const Aabb& targets, const PixelRect& rect) const;
  /// What the image and the sweep prove of a node (whose value, the maximum
  /// of its voxels, is `value`); for the fast method also what its corner
  /// voxels suggest.
  Visibility decide(Key key, int depth, float value, Overlap overlap);
  [[nodiscard]] Visibility ray_visibility_from_image(Key key) const;
  bool walk_is_clear(Key key);
  [[nodiscard]] Vec3d centre_of(Key key) const;  // of a finest voxel
  [[nodiscard]] Aabb centres_of(Key key, int depth) const;
  /// Whether the centre of voxel `key` lies in the frustum, given what its parent region's overlap was.
  [[nodiscard]] bool in_frustum(Key key, Overlap parent) const;
  /// The cube of the node at `depth` whose first voxel is `key`.
  [[nodiscard]] Aabb cube_of(Key key, int depth) const;

  const Grid& grid_;
  const OccupancyTree* tree_ = nullptr;  // the tree of the current count()
  LogOddsThresholds thresholds_;

  // The pose.
  double requested_range_ = 0.0;           // max_range as asked (for messages)
  std::optional<FrustumGeometry> frustum_;  // the frustum, its range clipped to the map
  Vec3f origin_;      // the rays' float origin (the image's apex)
  Key origin_key_;
  double margin_ = 0.0;         // how far walks stray near obstacles (within the last obstacle's distance)
  double target_margin_ = 0.0;  // how far rounded centres and whole walks stray (the whole range)
  bool use_image_ = false;
  bool touching_ = false;  // an obstacle touches the origin: the image proves no visibility
  double touching_distance_ = 0.0;  // obstacles this near the apex may reach before the near plane
  bool fast_ = false;
  int fast_depth_ = 0;

  ViewImage image_;
  bool sweeps_ = false;      // whether nodes may be swept (not for fast)
  OccupiedBitmap occupied_;  // the drawn obstacles' voxels (kept only when sweeping)
  OcclusionSweep sweep_;
  OcclusionSweep::Pose sweep_pose_{};
  std::vector<Aabb> obstacles_;  // cubes of the drawn obstacles (not grown)
  struct ObstacleKeys {
    Key first;          // the obstacle's first voxel
    std::uint32_t last;  // its edge in voxels, minus one
  };
  std::vector<ObstacleKeys> obstacle_keys_;  // the same obstacles' voxels (kept only when sweeping)

  std::uint64_t last_blocking_step_ = 0;  // a walk's voxels after this many are beyond every obstacle

  // The work so far (GainOptions::max_steps).
  std::uint64_t steps_ = 0;
  std::uint64_t max_steps_ = 0;

  // The result so far.
  std::uint64_t voxels_ = 0;
  double entropy_ = 0.0;
  float entropy_value_ = 0.0f;  // the value entropy_of_value_ belongs to
  double entropy_of_value_ = 1.0;

  // Memo of the occupied-voxel lookup of walked rays: the last node found to
  // hold no occupied voxel (its code prefix), so a ray through it needs no lookup.
  unsigned clear_shift_ = 64;
  std::uint64_t clear_prefix_ = 0;
  // The nodes of the last lookup, path_[d] at depth d for d >= path_depth_
  // (64: none yet), all holding voxel path_code_.
  std::array<NodeRef, kMaxDepthLevels + 1> path_{};
  std::uint64_t path_code_ = 0;
  int path_depth_ = 64;
};

}  // namespace umbra::detail
