// make_node: the public Node of a tree node (the one place that turns tree
// positions into keys, centres and states).
#pragma once

#include <cstdint>

#include "tree/occupancy_tree.hpp"
#include "umbra/core/grid.hpp"
#include "umbra/core/node.hpp"

namespace umbra::detail {

/// The node `ref`, whose first finest voxel has Morton code `code`.
inline Node make_node(const OccupancyTree& tree, const Grid& grid, NodeRef ref, std::uint64_t code) {
  Node node;
  node.depth = ref.depth;
  node.key = morton::decode(morton::node_begin(code, ref.depth));
  node.center = grid.center(node.key, ref.depth);
  node.size = grid.node_size(ref.depth);
  node.log_odds = tree.log_odds(ref);
  node.state = tree.thresholds().classify(node.log_odds);
  node.contains_free = tree.contains_free(ref);
  node.contains_unknown = tree.contains_unknown(ref);
  node.has_children = tree.has_children(ref);
  node.color = tree.color(ref);
  return node;
}

}  // namespace umbra::detail
