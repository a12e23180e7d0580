// Collision checks of regions and segments on a tree (the algorithms behind
// OccupancyMap::is_free, which holds the map for reading around them).
//
// A region (box, sphere, oriented box, capsule) is checked by one descent
// that only follows nodes holding something blocking (BlockingRule) and
// meeting the shape: first straight down to the smallest node containing
// the shape's bounding box (no geometry needed there), then recursively
// through the children whose key range meets that bounding box. A node
// wholly inside the shape that holds a blocking voxel ends the check at
// once (any blocking voxel below it is in the shape). Free space costs
// nothing per voxel: a free or unobserved-but-allowed subtree is dismissed
// by its value and indicator, whatever its size.
//
// A segment is its ray walk (shapes.hpp) looked up with BlockingLookup, in
// walk order, so the blocking node reported is the first along it.
#include "query/collision_check.hpp"

#include <algorithm>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <type_traits>

#include "query/blocking_lookup.hpp"
#include "query/geometry.hpp"
#include "query/query_walk.hpp"
#include "ray/exact_dda.hpp"
#include "tree/make_node.hpp"

namespace umbra {
namespace {

using detail::BlockingLookup;
using detail::BlockingRule;
using detail::NodeContext;
using detail::child_key;
using detail::Overlap;
using detail::QueryScope;
using detail::SegmentWalk;

/// Finest keys [min, max] per axis of a region's bounding box.
struct KeyBounds {
  Key min;
  Key max;
  [[nodiscard]] bool meets(Key node_key, int depth) const {
    const std::uint32_t last = (1u << depth) - 1;
    for (int axis = 0; axis < 3; ++axis) {
      if (node_key[axis] > max[axis] || node_key[axis] + last < min[axis]) return false;
    }
    return true;
  }
};

Aabb bounds_of(const Aabb& box) { return box; }
Aabb bounds_of(const Sphere& s) {
  const Vec3d r{s.radius, s.radius, s.radius};
  return {s.center - r, s.center + r};
}
Aabb bounds_of(const Capsule& c) {
  const Vec3d r{c.radius, c.radius, c.radius};
  return {Vec3d{std::min(c.a.x, c.b.x), std::min(c.a.y, c.b.y), std::min(c.a.z, c.b.z)} - r,
          Vec3d{std::max(c.a.x, c.b.x), std::max(c.a.y, c.b.y), std::max(c.a.z, c.b.z)} + r};
}
Aabb bounds_of(const OrientedBox& b) {
  Vec3d extent;
  for (int axis = 0; axis < 3; ++axis) {
    extent[axis] = 0.0;
    for (int i = 0; i < 3; ++i) extent[axis] += b.half_extents[i] * std::fabs(b.axes[i][axis]);
  }
  return {b.center - extent, b.center + extent};
}

/// The voxels a region's bounding box covers; throws std::out_of_range
/// naming the region when part of it lies outside the map.
KeyBounds key_bounds(const Grid& grid, const Aabb& box, const char* what) {
  const std::optional<Key> low = grid.key_checked(box.min);
  const std::optional<Key> high = grid.key_checked(box.max);
  if (!low || !high) {
    throw std::out_of_range(std::string(what) + " reaches outside the map, which spans [" +
                            std::to_string(-grid.half_extent()) + ", " + std::to_string(grid.half_extent()) +
                            ") on every axis: its bounding box is (" + std::to_string(box.min.x) + ", " +
                            std::to_string(box.min.y) + ", " + std::to_string(box.min.z) + ") - (" +
                            std::to_string(box.max.x) + ", " + std::to_string(box.max.y) + ", " +
                            std::to_string(box.max.z) + ")");
  }
  return {*low, *high};
}

const char* name_of(const Aabb&) { return "the box"; }
const char* name_of(const Sphere&) { return "the sphere"; }
const char* name_of(const Capsule&) { return "the capsule"; }
const char* name_of(const OrientedBox&) { return "the oriented box"; }

template <typename Shape>
class RegionCheck {
 public:
  RegionCheck(const QueryScope& scope, const BlockingRule& rule, const Shape& shape, const KeyBounds& bounds)
      : scope_(scope), rule_(rule), shape_(shape), bounds_(bounds) {}

  CollisionResult run() {
    const OccupancyTree& tree = *scope_.tree;
    // Straight down while a single child holds the whole bounding box,
    // reading only what decides the step (the whole context once, below).
    NodeRef ref = tree.root();
    Key key{};
    while (rule_.holds_blocking(tree.log_odds(ref), tree.contains_unknown(ref)) && ref.depth > scope_.depth &&
           tree.has_children(ref) && !tree.all_children_same(ref)) {
      const unsigned slot = only_child_meeting_bounds(key, ref.depth);
      if (slot == 8) break;
      key = child_key(key, ref.depth, slot);
      ref = tree.child(ref, slot);
    }
    CollisionResult result;
    if (const std::optional<NodeContext> blocking = check(NodeContext::read(scope_, ref, key))) {
      result.free = false;
      result.blocking = blocking->to_node(scope_);
    }
    return result;
  }

 private:
  [[nodiscard]] bool holds_blocking(const NodeContext& n) const {
    return rule_.holds_blocking(n.value, n.contains_unknown);
  }

  /// The child whose key range holds the whole bounding box, or 8 when it straddles.
  [[nodiscard]] unsigned only_child_meeting_bounds(Key key, int depth) const {
    const std::uint32_t half = 1u << (depth - 1);
    unsigned slot = 0;
    for (int axis = 0; axis < 3; ++axis) {
      const bool low = bounds_.min[axis] < key[axis] + half;
      const bool high = bounds_.max[axis] >= key[axis] + half;
      if (low && high) return 8;
      if (high) slot |= 1u << axis;
    }
    return slot;
  }

  /// A blocking node meeting the shape in the subtree of `n`, if any.
  std::optional<NodeContext> check(const NodeContext& n) const {
    if (!holds_blocking(n)) return std::nullopt;
    const Overlap overlap = detail::overlap(shape_, n.cube(*scope_.grid));
    if (overlap == Overlap::outside) return std::nullopt;
    if (n.leaf) return n;
    if (overlap == Overlap::inside) return any_blocking_leaf(n);
    for (unsigned slot = 0; slot < 8; ++slot) {
      const Key key = n.child_key(slot);
      if (!bounds_.meets(key, n.depth - 1)) continue;
      const NodeRef child = scope_.tree->child(n.ref, slot);
      // Most children hold nothing blocking: two reads decide that, before
      // the whole context (leaf test, indicators) is read.
      if (!rule_.holds_blocking(scope_.tree->log_odds(child), scope_.tree->contains_unknown(child))) continue;
      if (auto found = check(NodeContext::read(scope_, child, key))) return found;
    }
    return std::nullopt;
  }

  /// A leaf below `n` (which holds something blocking) that blocks.
  [[nodiscard]] NodeContext any_blocking_leaf(NodeContext n) const {
    while (!n.leaf) {
      for (unsigned slot = 0; slot < 8; ++slot) {
        const NodeContext child = NodeContext::read(scope_, scope_.tree->child(n.ref, slot), n.child_key(slot));
        if (holds_blocking(child)) {
          n = child;
          break;
        }
      }
    }
    return n;
  }

  QueryScope scope_;
  BlockingRule rule_;
  const Shape& shape_;
  KeyBounds bounds_;
};

BlockingRule rule_of(const OccupancyTree& tree, const CollisionOptions& options) {
  return {tree.thresholds(), !options.unknown_is_free};
}

template <typename Shape>
CollisionResult check_region(const OccupancyTree& tree, const Grid& grid, const Shape& shape,
                             const CollisionOptions& options) {
  shape.validate();
  const KeyBounds bounds = key_bounds(grid, bounds_of(shape), name_of(shape));
  const QueryScope scope = detail::scope_of(tree, grid, options.depth);
  return RegionCheck<Shape>(scope, rule_of(tree, options), shape, bounds).run();
}

/// A segment's walk; throws for a bad segment or one reaching outside the map.
SegmentWalk segment_walk(const Grid& grid, const Segment& segment) {
  segment.validate();
  // The walk works on float points, as OctoMap's computeRayKeys.
  const Vec3f from(segment.from);
  const Vec3f to(segment.to);
  const Key from_key = key_of_rounded(grid, from, "segment: its start");  // throw std::out_of_range naming it
  const Key to_key = key_of_rounded(grid, to, "segment: its end");
  return {grid, from, from_key, to, to_key};
}

CollisionResult check_segment(const OccupancyTree& tree, const Grid& grid, const Segment& segment,
                              const CollisionOptions& options) {
  SegmentWalk walk = segment_walk(grid, segment);
  const QueryScope scope = detail::scope_of(tree, grid, options.depth);
  BlockingLookup lookup(scope, rule_of(tree, options));
  CollisionResult result;
  // Stops at the first blocking voxel; jumps over each node found to hold
  // nothing blocking (from 2^3 voxels up).
  for (; !walk.done(); walk.next(lookup.clear_depth())) {
    NodeRef blocking{};
    if (lookup.blocks(walk.code(), &blocking)) {
      result.free = false;
      result.blocking = detail::make_node(tree, grid, blocking, walk.code());
      break;
    }
  }
  return result;
}

}  // namespace

namespace detail {

template <CollisionShape Shape>
CollisionResult check_collision(const OccupancyTree& tree, const Grid& grid, const Shape& shape,
                                const CollisionOptions& options) {
  if constexpr (std::is_same_v<Shape, Segment>) {
    return check_segment(tree, grid, shape, options);
  } else {
    return check_region(tree, grid, shape, options);
  }
}
template CollisionResult check_collision(const OccupancyTree&, const Grid&, const Aabb&, const CollisionOptions&);
template CollisionResult check_collision(const OccupancyTree&, const Grid&, const Sphere&, const CollisionOptions&);
template CollisionResult check_collision(const OccupancyTree&, const Grid&, const OrientedBox&,
                                         const CollisionOptions&);
template CollisionResult check_collision(const OccupancyTree&, const Grid&, const Capsule&, const CollisionOptions&);
template CollisionResult check_collision(const OccupancyTree&, const Grid&, const Segment&, const CollisionOptions&);

}  // namespace detail
}  // namespace umbra
