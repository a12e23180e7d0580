// CompiledPredicate: a Predicate bound to one map for one query.
//
// Binding reads the thresholds once, walks each segment's voxels once
// (sorted Morton codes, so "does this node hold one?" is a binary search),
// and sets up each frustum's planes. Then, per node:
//   classify(n): can the node or anything below it (down to the query's
//                depth) match? none / some / all;
//   matches(n):  does the node itself match?
// The traversal skips a subtree on "none", stops evaluating in it on "all",
// and asks matches() only on "some". A user rule (pred::satisfies) always
// classifies as "some" and is called only by matches(), after the parts of
// an && before it admitted the node.
#pragma once

#include <cstdint>
#include <functional>
#include <variant>
#include <vector>

#include "query/geometry.hpp"
#include "query/node_context.hpp"
#include "query/predicate_term.hpp"
#include "umbra/query/predicate.hpp"

namespace umbra::detail {

enum class Matches : unsigned char { none, some, all };

/// The voxels of a segment's ray walk, sorted by Morton code.
struct SegmentVoxels {
  std::vector<std::uint64_t> codes;
  /// Holds the node whose first voxel is `begin` at `depth` one of them?
  [[nodiscard]] bool any_in(std::uint64_t begin, int depth) const;
};

/// The voxels a segment's line check looks at: OctoMap's computeRayKeys
/// from `from` to `to` plus the voxel of `to`, in walk order. Throws
/// std::out_of_range when an end lies outside the map.
std::vector<std::uint64_t> segment_voxel_codes(const Grid& grid, const Segment& segment);

class CompiledPredicate {
 public:
  CompiledPredicate(const Predicate& predicate, const QueryScope& scope);

  [[nodiscard]] Matches classify(const NodeContext& node) const { return classify(root_, node); }
  [[nodiscard]] bool matches(const NodeContext& node) const { return matches(root_, node); }

 private:
  using Kind = PredicateTerm::Kind;
  using Shape = std::variant<Aabb, Sphere, OrientedBox, Capsule, SegmentVoxels, FrustumGeometry>;
  struct Op {
    Kind kind;
    int depth = 0;        // depth_*
    int a = -1;           // operands (indices into ops_)
    int b = -1;
    int shape = -1;       // index into shapes_
    const std::function<bool(const Node&)>* rule = nullptr;
  };

  int compile(const PredicateTerm& term);
  [[nodiscard]] Matches classify(int op, const NodeContext& node) const;
  [[nodiscard]] bool matches(int op, const NodeContext& node) const;
  [[nodiscard]] Overlap shape_overlap(const Shape& shape, const NodeContext& node) const;
  [[nodiscard]] bool shape_matches(const Shape& shape, const NodeContext& node) const;

  QueryScope scope_;
  LogOddsThresholds thresholds_;
  std::vector<Op> ops_;
  std::vector<Shape> shapes_;
  int root_ = 0;
};

/// Whether some voxel centre of the box of centres `centres` (of a node at
/// `depth`: 2^depth centres per axis, `step` apart) lies in the frustum,
/// exactly as FrustumGeometry::contains decides it for each centre.
bool any_center_inside(const FrustumGeometry& frustum, const Aabb& centres, int depth, double step);

}  // namespace umbra::detail
