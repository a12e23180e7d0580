#include "query/compiled_predicate.hpp"

#include <algorithm>
#include <stdexcept>

#include "ray/voxel_walk.hpp"

namespace umbra::detail {

bool SegmentVoxels::any_in(std::uint64_t begin, int depth) const {
  const std::uint64_t end = begin + (std::uint64_t{1} << (3 * depth));
  const auto it = std::lower_bound(codes.begin(), codes.end(), begin);
  return it != codes.end() && *it < end;
}

std::vector<std::uint64_t> segment_voxel_codes(const Grid& grid, const Segment& segment) {
  // OctoMap's computeRayKeys works on float points: so does the walk.
  const Vec3f from(segment.from);
  const Vec3f to(segment.to);
  const Key from_key = key_of_rounded(grid, from, "segment: its start");  // throw std::out_of_range naming it
  const Key to_key = key_of_rounded(grid, to, "segment: its end");
  std::vector<std::uint64_t> codes;
  walk_ray(grid, from, from_key, to, to_key, [&](std::uint64_t code) { codes.push_back(code); });
  codes.push_back(morton::encode(to_key));
  return codes;
}

bool any_center_inside(const FrustumGeometry& frustum, const Aabb& centres, int depth, double step) {
  switch (frustum.overlap(centres)) {
    case Overlap::outside: return false;
    case Overlap::inside: return true;
    case Overlap::partly: break;
  }
  if (depth == 0) return frustum.contains(centres.min);
  const double offset = step * double(1u << (depth - 1));  // distance between the two halves' first centres
  const double extent = centres.max.x - centres.min.x - offset;
  for (unsigned slot = 0; slot < 8; ++slot) {
    Aabb child;
    for (int axis = 0; axis < 3; ++axis) {
      child.min[axis] = centres.min[axis] + ((slot >> axis & 1u) ? offset : 0.0);
      child.max[axis] = child.min[axis] + extent;
    }
    if (any_center_inside(frustum, child, depth - 1, step)) return true;
  }
  return false;
}

CompiledPredicate::CompiledPredicate(const Predicate& predicate, const QueryScope& scope)
    : scope_(scope), thresholds_(scope.tree->thresholds()) {
  root_ = compile(predicate.term());
}

int CompiledPredicate::compile(const PredicateTerm& term) {
  Op op;
  op.kind = term.kind;
  op.depth = term.depth;
  switch (term.kind) {
    case Kind::all_of:
    case Kind::any_of:
      op.a = compile(*term.a);
      op.b = compile(*term.b);
      break;
    case Kind::none_of:
      op.a = compile(*term.a);
      break;
    case Kind::rule:
      op.rule = &term.rule;  // the Predicate outlives the query (the range keeps a copy)
      break;
    case Kind::shape:
      op.shape = static_cast<int>(shapes_.size());
      std::visit(
          [&](const auto& shape) {
            using T = std::decay_t<decltype(shape)>;
            if constexpr (std::is_same_v<T, Segment>) {
              SegmentVoxels voxels{segment_voxel_codes(*scope_.grid, shape)};
              std::sort(voxels.codes.begin(), voxels.codes.end());
              voxels.codes.erase(std::unique(voxels.codes.begin(), voxels.codes.end()), voxels.codes.end());
              shapes_.emplace_back(std::move(voxels));
            } else if constexpr (std::is_same_v<T, Frustum>) {
              shapes_.emplace_back(FrustumGeometry(shape));
            } else {
              shapes_.emplace_back(shape);
            }
          },
          term.shape);
      break;
    default:
      break;
  }
  ops_.push_back(op);
  return static_cast<int>(ops_.size()) - 1;
}

Overlap CompiledPredicate::shape_overlap(const Shape& shape, const NodeContext& node) const {
  return std::visit(
      [&](const auto& s) -> Overlap {
        using T = std::decay_t<decltype(s)>;
        if constexpr (std::is_same_v<T, SegmentVoxels>) {
          if (!s.any_in(node.code(), node.depth)) return Overlap::outside;
          return node.depth == 0 ? Overlap::inside : Overlap::partly;
        } else if constexpr (std::is_same_v<T, FrustumGeometry>) {
          // The box of the node's voxel centres.
          const double half = 0.5 * scope_.grid->resolution();
          const Aabb cube = node.cube(*scope_.grid);
          return s.overlap({cube.min + Vec3d{half, half, half}, cube.max - Vec3d{half, half, half}});
        } else {
          return overlap(s, node.cube(*scope_.grid));
        }
      },
      shape);
}

bool CompiledPredicate::shape_matches(const Shape& shape, const NodeContext& node) const {
  const Overlap o = shape_overlap(shape, node);
  if (o != Overlap::partly) return o == Overlap::inside;
  if (const auto* frustum = std::get_if<FrustumGeometry>(&shape)) {
    const double half = 0.5 * scope_.grid->resolution();
    const Aabb cube = node.cube(*scope_.grid);
    return any_center_inside(*frustum, {cube.min + Vec3d{half, half, half}, cube.max - Vec3d{half, half, half}},
                             node.depth, scope_.grid->resolution());
  }
  return true;  // "partly" is a real intersection for every other shape
}

Matches CompiledPredicate::classify(int index, const NodeContext& n) const {
  const Op& op = ops_[static_cast<std::size_t>(index)];
  const LogOddsThresholds& t = thresholds_;
  const bool occupied = t.is_occupied(n.value);  // some voxel is occupied
  const bool all_free = t.is_free(n.value);      // the maximum is free: every voxel is
  const bool in_band = !occupied && !all_free;
  switch (op.kind) {
    case Kind::any: return Matches::all;
    case Kind::occupied:
    case Kind::contains_occupied:
      if (!occupied) return Matches::none;
      return n.leaf ? Matches::all : Matches::some;
    case Kind::free:
      if (all_free) return Matches::all;
      if (!n.contains_free || n.leaf) return Matches::none;
      return Matches::some;
    case Kind::unknown:
      // A node's maximum is in the band only if some voxel below is unknown.
      if (!n.contains_unknown) return Matches::none;
      if (in_band && !n.contains_free) return Matches::all;  // every voxel is unknown
      if (n.leaf) return in_band ? Matches::all : Matches::none;
      return Matches::some;
    case Kind::contains_free:
      if (!n.contains_free) return Matches::none;
      return all_free || n.leaf ? Matches::all : Matches::some;
    case Kind::contains_unknown:
      if (!n.contains_unknown) return Matches::none;
      return n.leaf || (in_band && !n.contains_free) ? Matches::all : Matches::some;
    case Kind::leaf: return n.leaf ? Matches::all : Matches::some;
    case Kind::depth_exactly:
      if (n.leaf) return n.depth == op.depth ? Matches::all : Matches::none;
      // Nodes below lie at depths [query depth, depth - 1].
      return op.depth > n.depth || op.depth < scope_.depth ? Matches::none : Matches::some;
    case Kind::depth_at_least:
      if (n.depth < op.depth) return Matches::none;
      return n.leaf || scope_.depth >= op.depth ? Matches::all : Matches::some;
    case Kind::depth_at_most:
      if (n.depth <= op.depth) return Matches::all;
      return n.leaf || scope_.depth > op.depth ? Matches::none : Matches::some;
    case Kind::shape: {
      const Shape& shape = shapes_[static_cast<std::size_t>(op.shape)];
      switch (shape_overlap(shape, n)) {
        case Overlap::outside: return Matches::none;
        case Overlap::inside: return Matches::all;
        case Overlap::partly: break;
      }
      if (!n.leaf) return Matches::some;
      return shape_matches(shape, n) ? Matches::all : Matches::none;
    }
    case Kind::rule: return Matches::some;
    case Kind::all_of: {
      const Matches a = classify(op.a, n);
      if (a == Matches::none) return Matches::none;
      const Matches b = classify(op.b, n);
      if (b == Matches::none) return Matches::none;
      return a == Matches::all && b == Matches::all ? Matches::all : Matches::some;
    }
    case Kind::any_of: {
      const Matches a = classify(op.a, n);
      if (a == Matches::all) return Matches::all;
      const Matches b = classify(op.b, n);
      if (b == Matches::all) return Matches::all;
      return a == Matches::none && b == Matches::none ? Matches::none : Matches::some;
    }
    case Kind::none_of:
      switch (classify(op.a, n)) {
        case Matches::none: return Matches::all;
        case Matches::all: return Matches::none;
        case Matches::some: return Matches::some;
      }
  }
  return Matches::some;
}

bool CompiledPredicate::matches(int index, const NodeContext& n) const {
  const Op& op = ops_[static_cast<std::size_t>(index)];
  const LogOddsThresholds& t = thresholds_;
  switch (op.kind) {
    case Kind::any: return true;
    case Kind::occupied:
    case Kind::contains_occupied: return t.is_occupied(n.value);
    case Kind::free: return t.is_free(n.value);
    case Kind::unknown: return t.is_unknown(n.value);
    case Kind::contains_free: return n.contains_free;
    case Kind::contains_unknown: return n.contains_unknown;
    case Kind::leaf: return n.leaf;
    case Kind::depth_exactly: return n.depth == op.depth;
    case Kind::depth_at_least: return n.depth >= op.depth;
    case Kind::depth_at_most: return n.depth <= op.depth;
    case Kind::shape: return shape_matches(shapes_[static_cast<std::size_t>(op.shape)], n);
    case Kind::rule: return (*op.rule)(n.to_node(scope_));
    case Kind::all_of: return matches(op.a, n) && matches(op.b, n);
    case Kind::any_of: return matches(op.a, n) || matches(op.b, n);
    case Kind::none_of: return !matches(op.a, n);
  }
  return false;
}

}  // namespace umbra::detail
