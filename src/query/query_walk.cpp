#include "query/query_walk.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "query/geometry.hpp"

namespace umbra::detail {

QueryScope scope_of(const OccupancyTree& tree, const Grid& grid, int depth) {
  if (depth < 0 || depth > grid.depth_levels()) {
    throw std::out_of_range("query depth " + std::to_string(depth) + " is outside [0, " +
                            std::to_string(grid.depth_levels()) + "]");
  }
  return {&tree, &grid, depth};
}

// --- the depth-first walk ---------------------------------------------------------

PredicateWalk::PredicateWalk(const QueryScope& scope, const CompiledPredicate& predicate)
    : scope_(scope), predicate_(predicate) {
  stack_.reserve(8 * static_cast<std::size_t>(scope.tree->depth_levels()) + 1);
  stack_.push_back({scope.tree->root(), Key{}, false});
}

const NodeContext* PredicateWalk::next() {
  while (!stack_.empty()) {
    const Frame frame = stack_.back();
    stack_.pop_back();
    node_ = NodeContext::read(scope_, frame.ref, frame.key);
    bool all = frame.all;
    if (!all) {
      const Matches matches = predicate_.classify(node_);
      if (matches == Matches::none) continue;
      all = matches == Matches::all;
    }
    if (!node_.leaf) {
      // Last slot pushed first, so that slot 0 comes out first (Morton order).
      for (unsigned slot = 8; slot-- > 0;) {
        stack_.push_back({scope_.tree->child(frame.ref, slot), node_.child_key(slot), all});
      }
    }
    if (all || predicate_.matches(node_)) return &node_;
  }
  return nullptr;
}

QueryWalk::QueryWalk(const ReadGate& gate, const OccupancyTree& tree, const Grid& grid, const Predicate& predicate,
                     int depth)
    : lock_(gate),
      predicate_(predicate),
      scope_(scope_of(tree, grid, depth)),
      compiled_(predicate_, scope_),
      walk_(scope_, compiled_) {}

bool QueryWalk::advance() {
  const NodeContext* node = walk_.next();
  if (node == nullptr) {
    lock_.release();  // the loop is over: let a writer in before the range is destroyed
    return false;
  }
  current_ = node->to_node(scope_);
  return true;
}

std::size_t QueryWalk::count_rest() {
  std::size_t count = 0;
  while (walk_.next() != nullptr) ++count;
  return count;
}

// --- nearest first ------------------------------------------------------------------

NearestWalk::NearestWalk(const ReadGate& gate, const OccupancyTree& tree, const Grid& grid, Vec3d point,
                         const Predicate& predicate, int depth, double max_distance)
    : lock_(gate),
      predicate_(predicate),
      scope_(scope_of(tree, grid, depth)),
      compiled_(predicate_, scope_),
      point_(point) {
  if (!point.is_finite()) throw std::invalid_argument("nearest query: the point is not finite");
  if (std::isnan(max_distance) || max_distance < 0.0) {
    throw std::invalid_argument("nearest query: max_distance must be >= 0, got " + std::to_string(max_distance));
  }
  max_distance_squared_ = max_distance * max_distance;
  push(scope_.tree->root(), Key{}, scope_.tree->depth_levels(), false, 0.0);
}

void NearestWalk::push(NodeRef ref, Key key, int depth, bool all, double floor) {
  const Vec3d low = scope_.grid->min_corner(key, depth);
  const double size = scope_.grid->node_size(depth);
  const double d2 = std::max(floor, distance_squared(point_, Aabb{low, low + Vec3d{size, size, size}}));
  if (d2 <= max_distance_squared_) queue_.push({d2, ref, key, all});
}

bool NearestWalk::advance() {
  while (!queue_.empty()) {
    const Frame frame = queue_.top();
    queue_.pop();
    const NodeContext node = NodeContext::read(scope_, frame.ref, frame.key);
    bool all = frame.all;
    if (!all) {
      const Matches matches = compiled_.classify(node);
      if (matches == Matches::none) continue;
      all = matches == Matches::all;
    }
    if (!node.leaf) {
      for (unsigned slot = 0; slot < 8; ++slot) {
        push(scope_.tree->child(frame.ref, slot), node.child_key(slot), node.depth - 1, all, frame.distance_squared);
      }
    }
    if (all || compiled_.matches(node)) {
      current_ = {node.to_node(scope_), std::sqrt(frame.distance_squared)};
      return true;
    }
  }
  lock_.release();
  return false;
}

// --- what the public ranges call ------------------------------------------------------

bool advance(QueryWalk& walk) { return walk.advance(); }
bool advance(NearestWalk& walk) { return walk.advance(); }
const Node& current(const QueryWalk& walk) { return walk.current(); }
const NearNode& current(const NearestWalk& walk) { return walk.current(); }
void WalkDeleter::operator()(QueryWalk* walk) const { delete walk; }
void WalkDeleter::operator()(NearestWalk* walk) const { delete walk; }

}  // namespace umbra::detail
