// Predicate: which nodes a query wants, as a small value built from the
// functions in namespace umbra::pred and combined with &&, || and !.
//
//   using namespace umbra;
//   auto obstacles = pred::leaf() && pred::occupied() && pred::intersects(Sphere{{1, 2, 0.5}, 2.0});
//   for (const Node& node : map.query(obstacles)) { ... }
//
// A query visits the nodes of the map from the root down to its depth d (a
// depth-d node counts as a leaf there, with the maximum of its voxels as its
// value) and yields every node the predicate holds for, parents before
// children. Without pred::leaf() that includes inner nodes: pred::leaf()
// keeps the nodes that have no children at the query's depth (childless
// nodes, depth-d nodes, and nodes whose eight children are equal and
// childless while automatic pruning is off), which together tile the map
// exactly once.
//
// Every predicate also tells, from a node's value, its indicators and its
// cube, whether no node below can match, or all can; the query then skips
// the subtree, or stops testing in it. That is why a query for unknown space
// in a mostly known map, or for obstacles in a small sphere, touches a few
// hundred nodes instead of millions.
//
// States (thresholds as the map's, read when the query starts):
//   occupied: value > occupied threshold (some voxel in the node is occupied);
//   free: value < free threshold (every voxel is free);
//   unknown: neither; contains_free / contains_unknown: the node's indicators.
// Shapes: see shapes.hpp for when a node belongs to each.
// Predicates are immutable and cheap to copy (they share their parts).
#pragma once

#include <functional>
#include <memory>

#include "umbra/core/aabb.hpp"
#include "umbra/core/node.hpp"
#include "umbra/query/shapes.hpp"

namespace umbra {

namespace detail {
struct PredicateTerm;
}

class Predicate {
 public:
  /// Matches every node (pred::any()).
  Predicate();
  explicit Predicate(std::shared_ptr<const detail::PredicateTerm> term);

  friend Predicate operator&&(const Predicate& a, const Predicate& b);
  friend Predicate operator||(const Predicate& a, const Predicate& b);
  friend Predicate operator!(const Predicate& a);

  [[nodiscard]] const detail::PredicateTerm& term() const { return *term_; }

 private:
  std::shared_ptr<const detail::PredicateTerm> term_;
};

namespace pred {

Predicate any();
Predicate occupied();
Predicate free();
Predicate unknown();
Predicate contains_occupied();
Predicate contains_free();
Predicate contains_unknown();
/// No children at the query's depth (see the file comment).
Predicate leaf();
Predicate depth(int exactly);
Predicate min_depth(int depth);
Predicate max_depth(int depth);
Predicate intersects(const Aabb& box);
Predicate intersects(const Sphere& sphere);
Predicate intersects(const OrientedBox& box);
Predicate intersects(const Capsule& capsule);
Predicate intersects(const Segment& segment);
Predicate intersects(const Frustum& frustum);
/// Any rule over a node, e.g. [](const Node& n) { return n.log_odds > 1.5f; }.
/// The query cannot know which subtrees it may skip for such a rule: combine
/// it with the predicates above to keep a query fast. Called only for nodes
/// the rest of an && already admits, on the querying thread.
Predicate satisfies(std::function<bool(const Node&)> rule);

}  // namespace pred
}  // namespace umbra
