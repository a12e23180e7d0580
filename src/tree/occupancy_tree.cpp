#include "umbra/tree/occupancy_tree.hpp"

#include <algorithm>
#include <stdexcept>

namespace umbra {
namespace {

constexpr std::uint8_t bit(unsigned slot) { return static_cast<std::uint8_t>(1u << slot); }

void assign_bit(std::uint8_t& mask, unsigned slot, bool value) {
  mask = static_cast<std::uint8_t>(value ? (mask | bit(slot)) : (mask & ~bit(slot)));
}

}  // namespace

OccupancyTree::OccupancyTree(int depth_levels, LogOddsRange range, LogOddsThresholds thresholds)
    : depth_levels_(depth_levels), range_(range), thresholds_(thresholds) {
  if (depth_levels < 1 || depth_levels > kMaxDepthLevels) {
    throw std::invalid_argument("depth_levels must be in [1, 21], got " + std::to_string(depth_levels));
  }
  clear();
}

void OccupancyTree::clear() {
  leaves_.clear();
  inner_.clear();
  inner_.resize(static_cast<std::size_t>(depth_levels_) + 1);
  [[maybe_unused]] const std::uint32_t root_group = new_inner_group(depth_levels_, 0.0f);
  UMBRA_ASSERT(root_group == 0);
}

// --- groups ---------------------------------------------------------------

std::uint32_t OccupancyTree::new_leaf_group(float value) {
  const std::uint32_t index = leaves_.allocate();
  leaves_[index].log_odds.fill(value);
  return index;
}

std::uint32_t OccupancyTree::new_inner_group(int depth, float value) {
  const std::uint32_t index = inner_[depth].allocate();
  InnerGroup& group = inner_[depth][index];
  group.log_odds.fill(value);
  group.child.fill(kNoGroup);
  group.contains_free = thresholds_.is_free(value) ? 0xFF : 0;
  group.contains_unknown = thresholds_.is_unknown(value) ? 0xFF : 0;
  group.all_same = 0;
  return index;
}

void OccupancyTree::release_group(int depth, std::uint32_t group) {
  if (depth == 0) {
    leaves_.release(group);
  } else {
    inner_[depth].release(group);
  }
}

void OccupancyTree::set_childless(InnerGroup& group, unsigned slot, float value) const {
  UMBRA_ASSERT(group.child[slot] == kNoGroup);
  group.log_odds[slot] = value;
  assign_bit(group.contains_free, slot, thresholds_.is_free(value));
  assign_bit(group.contains_unknown, slot, thresholds_.is_unknown(value));
  assign_bit(group.all_same, slot, false);
}

void OccupancyTree::expand(int depth, InnerGroup& group, unsigned slot) {
  UMBRA_ASSERT(depth >= 1 && group.child[slot] == kNoGroup);
  const float value = group.log_odds[slot];
  // `group` lives in the pool of `depth`; allocating one depth below never moves it.
  group.child[slot] = depth == 1 ? new_leaf_group(value) : new_inner_group(depth - 1, value);
  assign_bit(group.all_same, slot, true);
}

void OccupancyTree::refresh(int depth, InnerGroup& group, unsigned slot, bool allow_prune) {
  const std::uint32_t child = group.child[slot];
  UMBRA_ASSERT(child != kNoGroup);
  float max;
  bool any_free;
  bool any_unknown;
  bool same = true;
  if (depth == 1) {
    const auto& values = leaves_[child].log_odds;
    max = values[0];
    any_free = false;
    any_unknown = false;
    for (const float v : values) {
      max = std::max(max, v);
      any_free |= thresholds_.is_free(v);
      any_unknown |= thresholds_.is_unknown(v);
      same &= v == values[0];
    }
  } else {
    const InnerGroup& children = inner_[depth - 1][child];
    max = children.log_odds[0];
    for (unsigned i = 0; i < 8; ++i) {
      max = std::max(max, children.log_odds[i]);
      same &= children.child[i] == kNoGroup && children.log_odds[i] == children.log_odds[0];
    }
    any_free = children.contains_free != 0;
    any_unknown = children.contains_unknown != 0;
  }
  if (same && allow_prune) {
    release_group(depth - 1, child);
    group.child[slot] = kNoGroup;
    set_childless(group, slot, max);
    return;
  }
  group.log_odds[slot] = max;
  assign_bit(group.contains_free, slot, any_free);
  assign_bit(group.contains_unknown, slot, any_unknown);
  assign_bit(group.all_same, slot, same);
}

// --- reading ----------------------------------------------------------------

NodeSummary OccupancyTree::find(std::uint64_t code, int depth) const {
  UMBRA_ASSERT(depth >= 0 && depth <= depth_levels_);
  std::uint32_t group = 0;
  for (int d = depth_levels_;; --d) {
    if (d == 0) {
      const float value = leaves_[group].log_odds[morton::slot(code, 0)];
      return {value, thresholds_.is_free(value), thresholds_.is_unknown(value), false, 0};
    }
    const InnerGroup& node = inner_[d][group];
    const unsigned slot = morton::slot(code, d);
    if (d == depth || node.child[slot] == kNoGroup) {
      return {node.log_odds[slot], (node.contains_free & bit(slot)) != 0,
              (node.contains_unknown & bit(slot)) != 0, node.child[slot] != kNoGroup, d};
    }
    group = node.child[slot];
  }
}

bool OccupancyTree::contains_free(NodeRef node) const {
  if (node.depth == 0) return thresholds_.is_free(log_odds(node));
  return (inner_[node.depth][node.group].contains_free & bit(node.slot)) != 0;
}

bool OccupancyTree::contains_unknown(NodeRef node) const {
  if (node.depth == 0) return thresholds_.is_unknown(log_odds(node));
  return (inner_[node.depth][node.group].contains_unknown & bit(node.slot)) != 0;
}

// --- writing ----------------------------------------------------------------

template <typename Change>
void OccupancyTree::modify_voxel(std::uint64_t code, Change change) {
  std::array<std::uint32_t, kMaxDepthLevels + 1> path{};
  std::uint32_t group = 0;
  path[depth_levels_] = group;
  for (int d = depth_levels_; d >= 1; --d) {
    InnerGroup& node = inner_[d][group];
    const unsigned slot = morton::slot(code, d);
    if (node.child[slot] == kNoGroup) {
      // An inner leaf covers the voxel: split it only if the voxel changes.
      if (change(node.log_odds[slot]) == node.log_odds[slot]) return;
      expand(d, node, slot);
    }
    group = node.child[slot];
    path[d - 1] = group;
  }
  float& value = leaves_[group].log_odds[morton::slot(code, 0)];
  const float changed = change(value);
  if (changed == value) return;
  value = changed;
  for (int d = 1; d <= depth_levels_; ++d) {
    refresh(d, inner_[d][path[d]], morton::slot(code, d), auto_prune_);
  }
}

void OccupancyTree::update(std::uint64_t code, float delta) {
  modify_voxel(code, [&](float v) { return range_.add(v, delta); });
}

void OccupancyTree::set(std::uint64_t code, float log_odds) {
  const float value = range_.clamp(log_odds) + 0.0f;  // + 0.0f turns -0 into +0
  modify_voxel(code, [&](float) { return value; });
}

void OccupancyTree::apply(const UpdateBatch& batch, float hit, float miss) {
  if (batch.depth_levels() != depth_levels_) {
    throw std::invalid_argument("update batch has " + std::to_string(batch.depth_levels()) +
                                " depth levels, the tree " + std::to_string(depth_levels_));
  }
  apply_group(depth_levels_, 0, batch, 0, hit, miss);
}

void OccupancyTree::apply_group(int depth, std::uint32_t group, const UpdateBatch& batch,
                                std::uint32_t batch_group, float hit, float miss) {
  if (depth == 1) {
    apply_brick(group, batch.brick(batch_group), hit, miss);
    return;
  }
  const UpdateBatch::Inner& todo = batch.inner(depth, batch_group);
  for (unsigned slot = 0; slot < 8; ++slot) {
    const bool full = (todo.full & bit(slot)) != 0;
    const std::uint32_t todo_child = todo.child[slot];
    if (!full && todo_child == kNoGroup) continue;
    // Recursion below only allocates and releases in deeper pools: `node` stays valid.
    InnerGroup& node = inner_[depth][group];
    if (full) {
      apply_everywhere(depth, node, slot, miss);
      continue;
    }
    if (node.child[slot] == kNoGroup) expand(depth, node, slot);
    apply_group(depth - 1, node.child[slot], batch, todo_child, hit, miss);
    refresh(depth, node, slot, auto_prune_);
  }
}

void OccupancyTree::apply_brick(std::uint32_t group, const UpdateBatch::Brick& todo, float hit, float miss) {
  InnerGroup& node = inner_[1][group];
  for (unsigned slot = 0; slot < 8; ++slot) {
    const std::uint8_t misses = todo.miss[slot];
    const std::uint8_t hits = todo.hit[slot];
    if ((misses | hits) == 0) continue;
    if (misses == 0xFF && hits == 0) {
      apply_everywhere(1, node, slot, miss);  // an inner leaf stays one node
      continue;
    }
    if (node.child[slot] == kNoGroup) expand(1, node, slot);
    auto& values = leaves_[node.child[slot]].log_odds;
    for (unsigned i = 0; i < 8; ++i) {
      if (hits & bit(i)) {
        values[i] = range_.add(values[i], hit);
      } else if (misses & bit(i)) {
        values[i] = range_.add(values[i], miss);
      }
    }
    refresh(1, node, slot, auto_prune_);
  }
}

void OccupancyTree::apply_everywhere(int depth, InnerGroup& group, unsigned slot, float delta) {
  const std::uint32_t child = group.child[slot];
  if (child == kNoGroup) {
    set_childless(group, slot, range_.add(group.log_odds[slot], delta));
    return;
  }
  if (depth == 1) {
    for (float& v : leaves_[child].log_odds) v = range_.add(v, delta);
  } else {
    InnerGroup& children = inner_[depth - 1][child];
    for (unsigned i = 0; i < 8; ++i) apply_everywhere(depth - 1, children, i, delta);
  }
  refresh(depth, group, slot, auto_prune_);
}

// --- indicators, pruning ------------------------------------------------------

void OccupancyTree::set_thresholds(LogOddsThresholds thresholds) {
  thresholds_ = thresholds;
  refresh_all();
}

void OccupancyTree::set_range(LogOddsRange range) {
  range_ = range;
  clamp_below(depth_levels_, inner_[depth_levels_][0], 0);
}

void OccupancyTree::clamp_below(int depth, InnerGroup& group, unsigned slot) {
  const std::uint32_t child = group.child[slot];
  if (child == kNoGroup) {
    set_childless(group, slot, range_.clamp(group.log_odds[slot]));
    return;
  }
  if (depth == 1) {
    for (float& v : leaves_[child].log_odds) v = range_.clamp(v);
  } else {
    InnerGroup& children = inner_[depth - 1][child];
    for (unsigned i = 0; i < 8; ++i) clamp_below(depth - 1, children, i);
  }
  refresh(depth, group, slot, auto_prune_);
}

void OccupancyTree::set_auto_prune(bool on) {
  auto_prune_ = on;
  if (on) prune();
}

void OccupancyTree::prune() { prune_below(depth_levels_, inner_[depth_levels_][0], 0); }

void OccupancyTree::prune_below(int depth, InnerGroup& group, unsigned slot) {
  const std::uint32_t child = group.child[slot];
  if (child == kNoGroup) return;
  if (depth > 1) {
    InnerGroup& children = inner_[depth - 1][child];
    for (unsigned i = 0; i < 8; ++i) prune_below(depth - 1, children, i);
  }
  refresh(depth, group, slot, true);
}

void OccupancyTree::refresh_all() { refresh_below(depth_levels_, inner_[depth_levels_][0], 0); }

void OccupancyTree::refresh_below(int depth, InnerGroup& group, unsigned slot) {
  const std::uint32_t child = group.child[slot];
  if (child == kNoGroup) {
    set_childless(group, slot, group.log_odds[slot]);
    return;
  }
  if (depth > 1) {
    InnerGroup& children = inner_[depth - 1][child];
    for (unsigned i = 0; i < 8; ++i) refresh_below(depth - 1, children, i);
  }
  refresh(depth, group, slot, false);
}

// --- building -------------------------------------------------------------------

void OccupancyTree::subdivide(NodeRef node) {
  if (node.depth < 1 || has_children(node)) {
    throw std::logic_error("subdivide: node must be childless and above the finest depth");
  }
  expand(node.depth, inner_[node.depth][node.group], node.slot);
}

void OccupancyTree::set_childless_value(NodeRef node, float log_odds) {
  if (node.depth == 0) {
    leaves_[node.group].log_odds[node.slot] = log_odds;
    return;
  }
  if (has_children(node)) throw std::logic_error("set_childless_value: node has children");
  set_childless(inner_[node.depth][node.group], node.slot, log_odds);
}

// --- statistics, checks -----------------------------------------------------------

NodeCounts OccupancyTree::count_nodes() const {
  NodeCounts counts;
  // Every allocated group holds 8 nodes (the root group holds 1).
  counts.leaf = leaves_.size() * 8;
  for (int d = 1; d <= depth_levels_; ++d) {
    const std::size_t nodes = d == depth_levels_ ? 1 : inner_[d].size() * 8;
    // A node is inner iff it owns a group one depth below.
    const std::size_t with_children = d == 1 ? leaves_.size() : inner_[d - 1].size();
    counts.inner += with_children;
    counts.inner_leaf += nodes - with_children;
  }
  return counts;
}

std::size_t OccupancyTree::memory_bytes() const {
  std::size_t bytes = sizeof(*this) + leaves_.memory_bytes() + inner_.capacity() * sizeof(inner_[0]);
  for (const auto& pool : inner_) bytes += pool.memory_bytes();
  return bytes;
}

std::string OccupancyTree::check_invariants() const {
  std::vector<std::vector<bool>> seen(static_cast<std::size_t>(depth_levels_) + 1);
  std::string problem = check_node(depth_levels_, 0, 0, seen);
  if (!problem.empty()) return problem;
  for (int d = 0; d < depth_levels_; ++d) {
    const std::size_t used = static_cast<std::size_t>(std::count(seen[d].begin(), seen[d].end(), true));
    const std::size_t in_pool = d == 0 ? leaves_.size() : inner_[d].size();
    if (used != in_pool) {
      return "depth " + std::to_string(d) + ": " + std::to_string(in_pool) + " groups in use, " +
             std::to_string(used) + " reachable";
    }
  }
  return {};
}

std::string OccupancyTree::check_node(int depth, std::uint32_t group_index, unsigned slot,
                                      std::vector<std::vector<bool>>& seen) const {
  const InnerGroup& group = inner_[depth][group_index];
  const std::string where = "node depth " + std::to_string(depth) + " group " +
                            std::to_string(group_index) + " slot " + std::to_string(slot) + ": ";
  const float value = group.log_odds[slot];
  const std::uint32_t child = group.child[slot];
  const bool free_bit = (group.contains_free & bit(slot)) != 0;
  const bool unknown_bit = (group.contains_unknown & bit(slot)) != 0;
  const bool same_bit = (group.all_same & bit(slot)) != 0;
  if (child == kNoGroup) {
    if (value < range_.min || value > range_.max) return where + "value outside the clamping range";
    if (free_bit != thresholds_.is_free(value)) return where + "contains_free wrong (childless)";
    if (unknown_bit != thresholds_.is_unknown(value)) return where + "contains_unknown wrong (childless)";
    if (same_bit) return where + "all_same set on a childless node";
    return {};
  }
  auto& seen_here = seen[depth - 1];
  if (seen_here.size() <= child) seen_here.resize(child + 1, false);
  if (seen_here[child]) return where + "child group referenced twice";
  seen_here[child] = true;

  float max = -1e30f;
  bool any_free = false;
  bool any_unknown = false;
  bool same = true;
  if (depth == 1) {
    const auto& values = leaves_[child].log_odds;
    for (const float v : values) {
      if (v < range_.min || v > range_.max) return where + "leaf value outside the clamping range";
      max = std::max(max, v);
      any_free |= thresholds_.is_free(v);
      any_unknown |= thresholds_.is_unknown(v);
      same &= v == values[0];
    }
  } else {
    const InnerGroup& children = inner_[depth - 1][child];
    for (unsigned i = 0; i < 8; ++i) {
      std::string problem = check_node(depth - 1, child, i, seen);
      if (!problem.empty()) return problem;
      max = std::max(max, children.log_odds[i]);
      any_free |= (children.contains_free & bit(i)) != 0;
      any_unknown |= (children.contains_unknown & bit(i)) != 0;
      same &= children.child[i] == kNoGroup && children.log_odds[i] == children.log_odds[0];
    }
  }
  if (value != max) return where + "value is not the maximum of the children";
  if (free_bit != any_free) return where + "contains_free differs from the children";
  if (unknown_bit != any_unknown) return where + "contains_unknown differs from the children";
  if (same_bit != same) return where + "all_same differs from the children";
  if (same && auto_prune_) return where + "eight equal childless children left unpruned";
  return {};
}

}  // namespace umbra
