// OccupancyTree::decay: every value moves toward 0 (unknown) by one step
// (docs/design.md, "Decay toward unknown").
//
// One depth-first walk that skips what cannot change: a subtree whose values
// are all 0, or all of a sign whose step is 0, as the node's maximum and its
// contains_free bit tell (see skip_subtree), and subtrees outside the
// region. A childless node (a pruned block) is one value however many voxels
// it covers, so a step costs the stored nodes that can change, not the
// voxels or the map's volume. On the way back each node is refreshed from
// its children (value, indicators, color, pruning), as apply() does.
// With a thread pool and no region, the groups below a split are walked by
// the workers, each group by one worker, as apply() splits a scan (a step
// then allocates nothing: only a region's boundary expands childless nodes).
#include <algorithm>
#include <optional>
#include <vector>

#include "tree/key_box_overlap.hpp"
#include "tree/occupancy_tree.hpp"

namespace umbra {
using detail::Overlap;
using detail::overlap;

void OccupancyTree::forget_color(int depth, std::uint32_t group, unsigned slot) {
  // A voxel decayed to unknown is as if never observed: no color either.
  if (!has_color()) return;
  ColorGroup& own = colors(depth, group);
  own.rgb[slot] = Rgb{};
  own.weight[slot] = 0;
}

bool OccupancyTree::decay_may_change(int depth, std::uint32_t group, unsigned slot, DecayStep step) const {
  const InnerGroup& node = inner_[depth][group];
  if (node.child[slot] == kNoGroup) return decayed(node.log_odds[slot], step) != node.log_odds[slot];
  // Nothing below can change when every value is 0 or of a sign that does
  // not decay. The maximum bounds the positive values; contains_free rules
  // out negative ones only when every negative value is free (free
  // threshold >= 0, i.e. p_free >= 0.5, the default).
  const bool no_positive = node.log_odds[slot] <= 0.0f;
  const bool no_negative = thresholds_.free >= 0.0f && (node.contains_free & (1u << slot)) == 0;
  return !((no_positive || step.occupied == 0.0f) && (no_negative || step.free == 0.0f));
}

void OccupancyTree::decay(DecayStep step, const std::optional<KeyBox>& region, std::vector<DecayChange>* changes,
                          int change_depth, ThreadPool* pool) {
  UMBRA_ASSERT(step.occupied >= 0.0f && step.free >= 0.0f);
  if (step.occupied == 0.0f && step.free == 0.0f) return;
  if (pool == nullptr || pool->size() < 2 || depth_levels_ < 3 || region) {
    decay_below(depth_levels_, 0, 0, 0, step, region, changes, change_depth);
    return;
  }
  decay_in_parallel(step, changes, change_depth, *pool);
}

void OccupancyTree::decay_in_parallel(DecayStep step, std::vector<DecayChange>* changes, int change_depth,
                                      ThreadPool& pool) {
  // 1. Split from the root into tasks, about 16 per worker: a task is some
  //    slots of one group (the group's indicator bits are bytes shared by
  //    its slots, so one group is written by one task only). A group is
  //    split when it lies above depth 2 and above change_depth: its slots
  //    with children become nodes refreshed after the tasks, their child
  //    groups tasks; its childless slots stay one task. So every node at
  //    change_depth lies in a task, which records it.
  struct Task {
    int depth;
    std::uint32_t group;
    std::uint64_t code;  // first finest voxel of the group
    std::uint8_t slots;  // the slots this task decays
  };
  const auto changing_slots = [&](int depth, std::uint32_t group) {
    std::uint8_t slots = 0;
    for (unsigned i = 0; i < 8; ++i) {
      if (decay_may_change(depth, group, i, step)) slots |= static_cast<std::uint8_t>(1u << i);
    }
    return slots;
  };
  if (!decay_may_change(depth_levels_, 0, 0, step)) return;
  std::vector<Task> tasks{{depth_levels_, 0, 0, 1}};  // the root, slot 0
  std::vector<SplitNode> parents;                      // top down
  const std::size_t wanted = std::size_t{pool.size()} * 16;
  const int lowest = std::max(2, change_depth);
  for (bool deeper = true; deeper && tasks.size() < wanted;) {
    deeper = false;
    std::vector<Task> next;
    for (const Task& task : tasks) {
      if (task.depth <= lowest) {
        next.push_back(task);
        continue;
      }
      std::uint8_t childless = 0;
      std::vector<Task> below;
      for (unsigned i = 0; i < 8; ++i) {
        if ((task.slots >> i & 1u) == 0) continue;
        const std::uint32_t child = inner_[task.depth][task.group].child[i];
        if (child == kNoGroup) {
          childless |= static_cast<std::uint8_t>(1u << i);
          continue;
        }
        deeper = true;
        parents.push_back({task.depth, task.group, i});
        const int child_depth = task.depth - 1;
        const std::uint8_t slots = changing_slots(child_depth, child);
        if (slots != 0) below.push_back({child_depth, child, task.code | (std::uint64_t{i} << (3 * task.depth)), slots});
      }
      if (childless != 0) next.push_back({task.depth, task.group, task.code, childless});
      next.insert(next.end(), below.begin(), below.end());
    }
    tasks.swap(next);
  }
  // 2. The tasks, each with its own list of changes. Without a region
  // nothing is expanded: no new groups; pruning releases groups into the
  // worker's own list.
  std::vector<std::vector<DecayChange>> task_changes(changes != nullptr ? tasks.size() : 0);
  const std::vector<std::size_t> new_groups(static_cast<std::size_t>(depth_levels_) + 1, 0);
  run_concurrently(
      pool, new_groups, tasks.size(),
      [&](std::size_t t) {
        const Task& task = tasks[t];
        for (unsigned i = 0; i < 8; ++i) {
          if ((task.slots >> i & 1u) == 0) continue;
          decay_below(task.depth, task.group, i, task.code | (std::uint64_t{i} << (3 * task.depth)), step,
                      std::nullopt, changes != nullptr ? &task_changes[t] : nullptr, change_depth);
        }
      },
      parents);
  if (changes == nullptr) return;
  // The recorded nodes are disjoint, so the serial walk lists them in
  // Morton order of their first voxels: the same order here.
  const std::size_t first = changes->size();
  for (const std::vector<DecayChange>& list : task_changes) changes->insert(changes->end(), list.begin(), list.end());
  std::sort(changes->begin() + static_cast<std::ptrdiff_t>(first), changes->end(),
            [](const DecayChange& a, const DecayChange& b) { return a.code < b.code; });
}

bool OccupancyTree::decay_below(int depth, std::uint32_t group, unsigned slot, std::uint64_t code, DecayStep step,
                                const std::optional<KeyBox>& region, std::vector<DecayChange>* changes,
                                int change_depth) {
  const Overlap where = overlap(code, depth, region);
  if (where == Overlap::outside) return false;
  const auto record = [&](int at) {
    if (changes != nullptr) changes->push_back({code, at});
  };
  {
    InnerGroup& node = inner_[depth][group];
    if (node.child[slot] == kNoGroup) {
      const float value = node.log_odds[slot];
      const float next = decayed(value, step);
      if (next == value) return false;  // unknown already, or its sign does not decay
      if (where == Overlap::inside) {
        set_childless(node, slot, next);
        if (next == 0.0f) forget_color(depth, group, slot);
        const bool changed = thresholds_.classify(value) != thresholds_.classify(next);
        if (changed && depth >= change_depth) record(depth);
        return changed;
      }
      expand(depth, group, slot);  // only a part of it decays
    } else {
      // Nothing below can change when every value is 0 or of a sign that
      // does not decay. The maximum bounds the positive values; contains_free
      // rules out negative ones only when every negative value is free
      // (free threshold >= 0, i.e. p_free >= 0.5, the default).
      const bool no_positive = node.log_odds[slot] <= 0.0f;
      const bool no_negative = thresholds_.free >= 0.0f && (node.contains_free & (1u << slot)) == 0;
      if ((no_positive || step.occupied == 0.0f) && (no_negative || step.free == 0.0f)) return false;
    }
  }
  const std::uint32_t child = inner_[depth][group].child[slot];
  bool changed = false;
  if (depth == 1) {
    LeafGroup& leaves = leaves_[child];
    for (unsigned i = 0; i < 8; ++i) {
      const std::uint64_t leaf_code = code | i;
      if (where == Overlap::partial && overlap(leaf_code, 0, region) == Overlap::outside) continue;
      const float value = leaves.log_odds[i];
      const float next = decayed(value, step);
      if (next == value) continue;
      leaves.log_odds[i] = next;
      if (next == 0.0f) forget_color(0, child, i);
      if (thresholds_.classify(value) != thresholds_.classify(next)) {
        changed = true;
        if (change_depth == 0 && changes != nullptr) changes->push_back({leaf_code, 0});
      }
    }
  } else {
    const int child_depth = depth - 1;
    for (unsigned i = 0; i < 8; ++i) {
      changed |= decay_below(child_depth, child, i, code | (std::uint64_t{i} << (3 * child_depth)), step, region,
                             changes, change_depth);
    }
  }
  refresh(depth, group, slot, auto_prune_);
  if (changed && depth == change_depth) record(depth);
  return changed;
}

}  // namespace umbra
