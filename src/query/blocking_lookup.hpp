// What blocks a robot or a ray, and a lookup that finds it voxel by voxel
// along a path (line checks, ray casts).
//
// A node holds something blocking when its value (the maximum of its
// voxels) is occupied, or, when unknown space blocks, when its
// contains-unknown indicator is set. Exactness at depth 0 and conservatism
// above follow from the indicators being exact: a depth-d node holds a
// blocking voxel iff this test says so.
//
// BlockingLookup::blocks(code) descends from the root to the node at the
// query's depth holding the voxel, but stops at the first node that holds
// nothing blocking and remembers it: later voxels of the path inside that
// node (the common case in free space) cost one shift and compare, no
// lookup. Otherwise the descent starts at the deepest node of the previous
// one that also holds this voxel (the path is kept per depth; consecutive
// voxels of a walk share all but the last few levels), not at the root:
// about a third less time per segment check on the 3DTK scans at 5 cm.
#pragma once

#include <algorithm>
#include <array>
#include <bit>
#include <cstdint>

#include "query/node_context.hpp"
#include "tree/occupancy_tree.hpp"
#include "umbra/core/log_odds.hpp"

namespace umbra::detail {

struct BlockingRule {
  LogOddsThresholds thresholds;
  bool unknown_blocks = true;

  [[nodiscard]] bool holds_blocking(float value, bool contains_unknown) const {
    return thresholds.is_occupied(value) || (unknown_blocks && contains_unknown);
  }
};

class BlockingLookup {
 public:
  BlockingLookup(const QueryScope& scope, const BlockingRule& rule) : scope_(scope), rule_(rule) { path_.fill(scope.tree->root()); }

  /// Whether finest voxel `code` lies in a blocking node at the scope's
  /// depth (or in a blocking childless node above it); `node` receives that
  /// node and `node_code` its first voxel's code when it does.
  bool blocks(std::uint64_t code, NodeRef* node = nullptr) {
    if (clear_shift_ < 64 && (code >> clear_shift_) == clear_prefix_) return false;
    const OccupancyTree& tree = *scope_.tree;
    NodeRef ref = tree.root();
    if (path_low_ <= ref.depth) {
      // The nodes holding both voxels are those above the highest level at
      // which the codes differ: depth (msb / 3) + 1 and up.
      const std::uint64_t diff = code ^ path_code_;
      const int shared = diff == 0 ? 0 : (63 - std::countl_zero(diff)) / 3 + 1;
      if (shared <= ref.depth) {
        const int start = std::max(shared, path_low_);
        ref = path_[static_cast<std::size_t>(start)];
        // A node above the last one looked at was found to hold something
        // blocking and to have children: go straight to the child.
        if (start > path_low_) ref = tree.child(ref, morton::slot(code, ref.depth - 1));
      }
    }
    path_code_ = code;
    for (;;) {
      path_[static_cast<std::size_t>(ref.depth)] = ref;
      path_low_ = ref.depth;
      const float value = tree.log_odds(ref);
      if (!rule_.holds_blocking(value, tree.contains_unknown(ref))) {
        clear_shift_ = 3 * ref.depth;
        clear_prefix_ = code >> clear_shift_;
        return false;
      }
      if (ref.depth <= scope_.depth || !tree.has_children(ref) || tree.all_children_same(ref)) {
        if (node != nullptr) *node = ref;
        return true;
      }
      ref = tree.child(ref, morton::slot(code, ref.depth - 1));
    }
  }

  /// After blocks() returned false: the depth of the node found to hold
  /// nothing blocking around that voxel (a path may jump over it).
  [[nodiscard]] int clear_depth() const { return static_cast<int>(clear_shift_ / 3); }

 private:
  QueryScope scope_;
  BlockingRule rule_;
  unsigned clear_shift_ = 64;  // 64: no clear node remembered
  std::uint64_t clear_prefix_ = 0;
  // The last descent: path_[d] is its node at depth d, for d >= path_low_
  // (path_low_ > the root's depth: none yet).
  std::array<NodeRef, kMaxDepthLevels + 1> path_{};
  int path_low_ = kMaxDepthLevels + 1;
  std::uint64_t path_code_ = 0;
};

}  // namespace umbra::detail
