// TreeBuilder: fills an empty tree node by node, for the file readers.
//
// A file describes a tree top down: subdivide a node, set the values (and
// colors) of childless nodes. Inner values and indicators are left stale
// meanwhile and recomputed once by finish(); nothing else may read the tree
// before that (MapAccess::build keeps the map to the builder until then).
// This is the only way to reach OccupancyTree's building functions.
#pragma once

#include <optional>

#include "tree/occupancy_tree.hpp"

namespace umbra::detail {

class TreeBuilder {
 public:
  explicit TreeBuilder(OccupancyTree& tree) : tree_(tree) {}

  // Reading what has been built so far (shape, values of childless nodes).
  [[nodiscard]] NodeRef root() const { return tree_.root(); }
  [[nodiscard]] NodeRef child(NodeRef node, unsigned slot) const { return tree_.child(node, slot); }
  [[nodiscard]] bool has_children(NodeRef node) const { return tree_.has_children(node); }
  [[nodiscard]] float log_odds(NodeRef node) const { return tree_.log_odds(node); }
  [[nodiscard]] std::optional<Rgb> color(NodeRef node) const { return tree_.color(node); }
  [[nodiscard]] std::uint8_t color_weight(NodeRef node) const { return tree_.color_weight(node); }

  /// Gives a childless node eight children that all carry its value.
  void subdivide(NodeRef node) { tree_.subdivide(node); }
  /// Sets a childless node's value.
  void set_childless_value(NodeRef node, float log_odds) { tree_.set_childless_value(node, log_odds); }
  /// Sets a childless node's color (weight 0: no color).
  void set_childless_color(NodeRef node, Rgb rgb, std::uint8_t weight) {
    tree_.set_childless_color(node, rgb, weight);
  }
  /// Recomputes every inner value and indicator from the childless nodes.
  void finish() { tree_.refresh_all(); }

 private:
  OccupancyTree& tree_;
};

}  // namespace umbra::detail
