// NodeContext: what a traversal knows about the node it stands on, read
// once from the tree; what compiled predicates and collision checks test.
#pragma once

#include <cstdint>

#include "tree/make_node.hpp"
#include "tree/occupancy_tree.hpp"
#include "umbra/core/aabb.hpp"
#include "umbra/core/grid.hpp"
#include "umbra/core/morton.hpp"

namespace umbra::detail {

/// The tree and grid a query reads, and the depth it treats as leaves.
struct QueryScope {
  const OccupancyTree* tree;
  const Grid* grid;
  int depth;  ///< nodes at this depth count as leaves
};

/// Key of child `slot` (slot bits: x = 1, y = 2, z = 4) of the depth-`depth`
/// node whose lowest voxel has `key`.
inline Key child_key(Key key, int depth, unsigned slot) {
  const std::uint32_t half = 1u << (depth - 1);
  return {key.x + ((slot & 1u) ? half : 0u), key.y + ((slot & 2u) ? half : 0u), key.z + ((slot & 4u) ? half : 0u)};
}

struct NodeContext {
  NodeRef ref;
  Key key;     ///< finest key of the node's lowest corner voxel
  int depth;
  float value;            ///< maximum over the node's voxels
  bool contains_free;
  bool contains_unknown;
  bool has_children;
  bool leaf;              ///< no children at the query's depth

  /// Reads the node `ref` (whose lowest voxel has `key`) for a query of `scope`.
  static NodeContext read(const QueryScope& scope, NodeRef ref, Key key) {
    const OccupancyTree& tree = *scope.tree;
    NodeContext n;
    n.ref = ref;
    n.key = key;
    n.depth = ref.depth;
    n.value = tree.log_odds(ref);
    n.contains_free = tree.contains_free(ref);
    n.contains_unknown = tree.contains_unknown(ref);
    n.has_children = tree.has_children(ref);
    n.leaf = n.depth <= scope.depth || !n.has_children || tree.all_children_same(ref);
    return n;
  }

  [[nodiscard]] std::uint64_t code() const { return morton::encode(key); }
  /// The node's cube in metres.
  [[nodiscard]] Aabb cube(const Grid& grid) const {
    const Vec3d low = grid.min_corner(key, depth);
    const double size = grid.node_size(depth);
    return {low, low + Vec3d{size, size, size}};
  }
  /// Key of child `slot` (slot bits: x = 1, y = 2, z = 4).
  [[nodiscard]] Key child_key(unsigned slot) const { return detail::child_key(key, depth, slot); }
  [[nodiscard]] Node to_node(const QueryScope& scope) const {
    return make_node(*scope.tree, *scope.grid, ref, code());
  }
};

}  // namespace umbra::detail
