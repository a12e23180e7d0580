// The walks behind OccupancyMap::query, query_nearest and count.
//
// PredicateWalk is the pruned depth-first traversal every predicate query
// uses: an explicit stack (so a range can stop and resume), one tree read
// per visited node, subtrees skipped when the predicate says none of them
// can match, and no evaluation inside a subtree it says all match.
// NearestWalk is the same with a priority queue ordered by the distance
// from a point to each node's cube: a child's cube lies inside its
// parent's, so nodes come out nearest first.
// Cost: O(visited nodes) with one small allocation per growth of the stack;
// the walk holds no lock itself (QueryWalk and NearestWalk do: they read a
// tree behind the map's ReadGate, which they are given with it).
#pragma once

#include <cstddef>
#include <limits>
#include <queue>
#include <vector>

#include "core/read_gate.hpp"
#include "query/compiled_predicate.hpp"
#include "query/node_context.hpp"
#include "umbra/query/query_range.hpp"

namespace umbra::detail {

class PredicateWalk {
 public:
  PredicateWalk(const QueryScope& scope, const CompiledPredicate& predicate);
  /// The next node that matches, or null when there is none.
  const NodeContext* next();

 private:
  struct Frame {
    NodeRef ref;
    Key key;
    bool all;  // the predicate holds for the whole subtree
  };
  QueryScope scope_;
  const CompiledPredicate& predicate_;
  std::vector<Frame> stack_;
  NodeContext node_{};
};

/// A query's state: the tree held for reading (through its gate), the predicate bound to it, the walk.
class QueryWalk {
 public:
  QueryWalk(const ReadGate& gate, const OccupancyTree& tree, const Grid& grid, const Predicate& predicate, int depth);
  bool advance();
  [[nodiscard]] const Node& current() const { return current_; }
  /// The matches left, without building Nodes.
  std::size_t count_rest();

 private:
  ReadLock lock_;  // first: held before anything reads the tree
  Predicate predicate_;
  QueryScope scope_;
  CompiledPredicate compiled_;
  PredicateWalk walk_;
  Node current_;
};

class NearestWalk {
 public:
  NearestWalk(const ReadGate& gate, const OccupancyTree& tree, const Grid& grid, Vec3d point,
              const Predicate& predicate, int depth, double max_distance);
  bool advance();
  [[nodiscard]] const NearNode& current() const { return current_; }

 private:
  struct Frame {
    double distance_squared;
    NodeRef ref;
    Key key;
    bool all;
    bool operator>(const Frame& other) const { return distance_squared > other.distance_squared; }
  };
  /// Queues a node unless it is beyond the distance limit; `floor` is its
  /// parent's distance (a child is never nearer, rounding aside).
  void push(NodeRef ref, Key key, int depth, bool all, double floor);

  ReadLock lock_;
  Predicate predicate_;
  QueryScope scope_;
  CompiledPredicate compiled_;
  Vec3d point_;
  double max_distance_squared_;
  std::priority_queue<Frame, std::vector<Frame>, std::greater<>> queue_;
  NearNode current_;
};

/// The scope of a query of `tree` at `depth`; throws std::out_of_range for a bad depth.
QueryScope scope_of(const OccupancyTree& tree, const Grid& grid, int depth);

}  // namespace umbra::detail
