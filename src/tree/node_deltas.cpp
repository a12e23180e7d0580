// OccupancyTree::add_to_nodes: per-node additions in one walk (merging maps).
//
// The regions are sorted by code and disjoint, so the regions inside any node
// form one contiguous run: the walk splits the run by child slot at each
// depth, as add_colors does with its samples. A region that is exactly the
// node reached is added with apply_everywhere, which changes a childless
// node alone (a pruned block of another map lands on a pruned block here in
// one step); only a region smaller than a childless node expands it.
#include <algorithm>

#include "tree/occupancy_tree.hpp"

namespace umbra {

void OccupancyTree::add_to_nodes(std::span<const NodeDelta> regions) {
  if (regions.empty()) return;
  UMBRA_ASSERT(std::is_sorted(regions.begin(), regions.end(),
                              [](const NodeDelta& a, const NodeDelta& b) { return a.code < b.code; }));
  add_to_nodes_below(depth_levels_, 0, 0, regions);
}

void OccupancyTree::add_to_nodes_below(int depth, std::uint32_t group, unsigned slot,
                                       std::span<const NodeDelta> regions) {
  // Every region lies in node (depth, group, slot), depth >= 1.
  if (regions.size() == 1 && regions[0].depth == depth) {
    apply_everywhere(depth, group, slot, regions[0].delta);
    return;
  }
  UMBRA_ASSERT(std::all_of(regions.begin(), regions.end(), [&](const NodeDelta& r) { return r.depth < depth; }));
  if (inner_[depth][group].child[slot] == kNoGroup) expand(depth, group, slot);
  add_to_nodes_in_group(depth - 1, inner_[depth][group].child[slot], regions);
  refresh(depth, group, slot, auto_prune_);
}

void OccupancyTree::add_to_nodes_in_group(int depth, std::uint32_t group, std::span<const NodeDelta> regions) {
  std::size_t begin = 0;
  while (begin < regions.size()) {
    const unsigned slot = morton::slot(regions[begin].code, depth);
    std::size_t end = begin + 1;
    while (end < regions.size() && morton::slot(regions[end].code, depth) == slot) ++end;
    if (depth == 0) {
      UMBRA_ASSERT(end == begin + 1);  // disjoint: one region per voxel
      catch_up(0, group);
      float& value = leaves_[group].log_odds[slot];
      value = range_.add(value, regions[begin].delta);
    } else {
      add_to_nodes_below(depth, group, slot, regions.subspan(begin, end - begin));
    }
    begin = end;
  }
}

}  // namespace umbra
