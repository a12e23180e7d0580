// OccupancyTree::forget_outside: everything outside a box of keys becomes
// unknown and the subtrees wholly outside it are freed (docs/design.md, "A
// map that moves").
//
// One depth-first walk: a node inside the box is left alone, a node wholly
// outside it is made a childless unknown node (its subtree returned to the
// pools), a node the box's faces cut is descended into. Nodes that hold
// nothing known (childless, value 0, no color) stop the walk, so for a box
// aligned to coarse nodes the walk costs the cut nodes above that depth and
// the nodes it frees, not the map. On the way back each cut node is
// refreshed from its children (value, indicators, color, pruning), as
// apply() does.
#include <vector>

#include "tree/key_box_overlap.hpp"
#include "tree/occupancy_tree.hpp"

namespace umbra {
using detail::Overlap;
using detail::overlap;

std::size_t OccupancyTree::forget_outside(const KeyBox& keep, std::vector<DecayChange>* changes, int change_depth) {
  std::size_t freed = 0;
  forget_outside_below(depth_levels_, 0, 0, 0, keep, changes, change_depth, freed);
  return freed;
}

void OccupancyTree::release_subtree(int depth, std::uint32_t group, std::size_t& freed) {
  if (depth > 0) {
    // Copied first: releasing a group below never moves this pool, but the
    // group itself is released last, after its children.
    const std::array<std::uint32_t, 8> children = inner_[depth][group].child;
    for (const std::uint32_t child : children) {
      if (child != kNoGroup) release_subtree(depth - 1, child, freed);
    }
  }
  release_group(depth, group);
  ++freed;
}

bool OccupancyTree::forget_outside_below(int depth, std::uint32_t group, unsigned slot, std::uint64_t code,
                                         const KeyBox& keep, std::vector<DecayChange>* changes, int change_depth,
                                         std::size_t& freed) {
  const Overlap where = overlap(code, depth, keep);
  if (where == Overlap::inside) return false;
  {
    InnerGroup& node = inner_[depth][group];
    catch_up(depth, group);
    const bool split = node.child[slot] != kNoGroup;
    const bool colored = has_color() && colors(depth, group).weight[slot] != 0;
    if (!split && node.log_odds[slot] == 0.0f && !colored) return false;  // unknown already
    if (where == Overlap::outside) {
      if (split) {
        const std::uint32_t child = node.child[slot];
        node.child[slot] = kNoGroup;
        release_subtree(depth - 1, child, freed);
      }
      set_childless(depth, group, slot, 0.0f);
      forget_color(depth, group, slot);
      if (changes != nullptr && depth >= change_depth) changes->push_back({code, depth});
      return true;
    }
    if (!split) expand(depth, group, slot);  // known, and the box cuts it: only a part is forgotten
  }
  const std::uint32_t child = inner_[depth][group].child[slot];
  bool changed = false;
  if (depth == 1) {
    catch_up(0, child);
    LeafGroup& leaves = leaves_[child];
    for (unsigned i = 0; i < 8; ++i) {
      const std::uint64_t leaf_code = code | i;
      if (overlap(leaf_code, 0, keep) == Overlap::inside) continue;
      const bool colored = has_color() && colors(0, child).weight[i] != 0;
      if (leaves.log_odds[i] == 0.0f && !colored) continue;
      leaves.log_odds[i] = 0.0f;
      forget_color(0, child, i);
      changed = true;
      if (change_depth == 0 && changes != nullptr) changes->push_back({leaf_code, 0});
    }
  } else {
    const int child_depth = depth - 1;
    for (unsigned i = 0; i < 8; ++i) {
      changed |= forget_outside_below(child_depth, child, i, code | (std::uint64_t{i} << (3 * child_depth)), keep,
                                      changes, change_depth, freed);
    }
  }
  refresh(depth, group, slot, auto_prune_);
  if (changed && depth == change_depth && changes != nullptr) changes->push_back({code, depth});
  return changed;
}

}  // namespace umbra
