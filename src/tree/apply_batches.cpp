// OccupancyTree::apply of several update batches at once (occupancy_tree.hpp).
//
// The projective integrator's workers each fill a batch of their own (the
// misses of the subtrees they traced, and the hits in them). Merging those
// batches into one before applying it was serial work on the critical path
// (UpdateBatch::merge re-adds every mark); instead the walk that applies a
// batch reads all of them side by side. Below a node only one batch has
// marks in (the workers' subtrees are disjoint), the walk is apply()'s own
// single-batch walk; where several meet (the top levels, and hits routed to
// a batch of their own), their marks are combined as merge() would:
//  - a voxel with a hit in any batch gets a hit, else one with a miss in any
//    a miss (a brick's masks are ORed: apply_brick lets a hit win);
//  - a node that no batch marks with a hit and whose voxels the batches
//    cover with misses between them gets one miss for its whole region, as
//    the merged batch's full node would (merge() collapses eight full
//    siblings into their parent). One batch alone is already collapsed that
//    way (UpdateBatch's groups never hold eight full nodes and no hit), so
//    only nodes where two or more batches meet are checked voxel by voxel.
// So the map is the merged batch's, bit for bit, pruned or not.
#include <algorithm>
#include <bit>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/assert.hpp"
#include "tree/occupancy_tree.hpp"

namespace umbra {
namespace {

/// The fewest bricks (of all batches) per subtree of a parallel apply, but
/// for a floor of 16 subtrees a thread (apply_batches_in_parallel).
constexpr std::size_t kApplyBricksPerTask = 256;

constexpr std::uint8_t bit(unsigned slot) { return static_cast<std::uint8_t>(1u << slot); }

// Templates over OccupancyTree's private BatchGroup (deduced from the calls).

/// One list of batch groups per depth in `scratch` (room for every batch).
template <typename BatchGroup>
std::span<BatchGroup> level(std::span<BatchGroup> scratch, int depth, std::size_t batches) {
  return scratch.subspan(static_cast<std::size_t>(depth) * batches, batches);
}

/// Whether the batches' groups `groups` (at `depth`, all of one node, none
/// with a hit below) mark every voxel of that node with a miss between them.
template <typename BatchGroup>
bool covered(int depth, std::span<const BatchGroup> groups, std::span<BatchGroup> scratch, std::size_t batches) {
  if (depth == 1) {
    std::uint64_t misses = 0;
    for (const BatchGroup& g : groups) misses |= std::bit_cast<std::uint64_t>(g.batch->brick(g.group).miss);
    return misses == ~std::uint64_t{0};
  }
  const std::span<BatchGroup> below = level(scratch, depth - 1, batches);
  for (unsigned slot = 0; slot < 8; ++slot) {
    bool full = false;
    std::size_t n = 0;
    for (const BatchGroup& g : groups) {
      const UpdateBatch::Inner& inner = g.batch->inner(depth, g.group);
      if ((inner.full & bit(slot)) != 0) {
        full = true;
        break;
      }
      if (inner.child[slot] != kNoGroup) below[n++] = {g.batch, inner.child[slot]};
    }
    if (full) continue;
    // One batch alone never leaves a node it misses whole uncollapsed.
    if (n < 2 || !covered(depth - 1, std::span<const BatchGroup>(below.first(n)), scratch, batches)) return false;
  }
  return true;
}

}  // namespace

void OccupancyTree::apply(std::span<const UpdateBatch* const> batches, float hit, float miss, ThreadPool* pool) {
  std::vector<const UpdateBatch*> marked;
  for (const UpdateBatch* batch : batches) {
    if (batch->depth_levels() != depth_levels_) {
      throw std::invalid_argument("update batch has " + std::to_string(batch->depth_levels()) +
                                  " depth levels, the tree " + std::to_string(depth_levels_));
    }
    if (!batch->empty()) marked.push_back(batch);
  }
  if (marked.empty()) return;
  if (marked.size() == 1) {
    apply(*marked[0], hit, miss, pool);
    return;
  }
  if (pool == nullptr || pool->size() < 2 || depth_levels_ < 3) {
    std::vector<BatchGroup> todo;
    for (const UpdateBatch* batch : marked) todo.push_back({batch, 0});
    std::vector<BatchGroup> scratch((static_cast<std::size_t>(depth_levels_) + 1) * marked.size());
    apply_groups(depth_levels_, 0, todo, false, hit, miss, scratch);
    return;
  }
  apply_batches_in_parallel(marked, hit, miss, *pool);
}

OccupancyTree::SlotUpdate OccupancyTree::slot_update(int depth, unsigned slot, std::span<const BatchGroup> todo,
                                                     bool missed, std::span<BatchGroup> scratch,
                                                     std::span<const BatchGroup>& children,
                                                     bool& children_missed) const {
  UMBRA_ASSERT(depth >= 2);
  const std::size_t batches = scratch.size() / (static_cast<std::size_t>(depth_levels_) + 1);
  const std::span<BatchGroup> below = level(scratch, depth - 1, batches);
  bool full = missed;
  bool hits = false;
  std::size_t n = 0;
  for (const BatchGroup& g : todo) {
    const UpdateBatch::Inner& inner = g.batch->inner(depth, g.group);
    full = full || (inner.full & bit(slot)) != 0;
    hits = hits || (inner.hits & bit(slot)) != 0;
    if (inner.child[slot] != kNoGroup) below[n++] = {g.batch, inner.child[slot]};
  }
  children = below.first(n);
  children_missed = full;
  if (!full && n == 0) return SlotUpdate::none;
  if (!hits && (full || (n >= 2 && covered(depth - 1, children, scratch, batches)))) return SlotUpdate::everywhere;
  return SlotUpdate::below;
}

void OccupancyTree::apply_groups(int depth, std::uint32_t group, std::span<const BatchGroup> todo, bool missed,
                                 float hit, float miss, std::span<BatchGroup> scratch) {
  if (!missed && todo.size() == 1) {  // one batch alone: apply()'s walk
    apply_group(depth, group, *todo[0].batch, todo[0].group, hit, miss);
    return;
  }
  if (depth == 1) {
    std::uint64_t misses = missed ? ~std::uint64_t{0} : 0;
    std::uint64_t hits = 0;
    for (const BatchGroup& g : todo) {
      const UpdateBatch::Brick& brick = g.batch->brick(g.group);
      misses |= std::bit_cast<std::uint64_t>(brick.miss);
      hits |= std::bit_cast<std::uint64_t>(brick.hit);
    }
    UpdateBatch::Brick combined{};
    combined.miss = std::bit_cast<std::array<std::uint8_t, 8>>(misses);
    combined.hit = std::bit_cast<std::array<std::uint8_t, 8>>(hits);
    apply_brick(group, combined, hit, miss);
    return;
  }
  for (unsigned slot = 0; slot < 8; ++slot) {
    std::span<const BatchGroup> children;
    bool children_missed = false;
    switch (slot_update(depth, slot, todo, missed, scratch, children, children_missed)) {
      case SlotUpdate::none:
        continue;
      case SlotUpdate::everywhere:
        apply_everywhere(depth, group, slot, miss);
        continue;
      case SlotUpdate::below:
        break;
    }
    if (inner_[depth][group].child[slot] == kNoGroup) expand(depth, group, slot);
    apply_groups(depth - 1, inner_[depth][group].child[slot], children, children_missed, hit, miss, scratch);
    refresh(depth, group, slot, auto_prune_);
  }
}

void OccupancyTree::apply_batches_in_parallel(std::span<const UpdateBatch* const> batches, float hit, float miss,
                                              ThreadPool& pool) {
  // As apply_in_parallel: walk down from the root until there are enough
  // independent subtrees (tasks), splitting map nodes on the way; a task owns
  // the map group it updates ("everywhere" tasks: the slots of their group
  // that get a miss whole).
  struct Task {
    int depth;
    std::uint32_t group;            // map group at `depth`
    std::vector<BatchGroup> todo;   // the batches' groups at `depth`
    bool missed;                    // every voxel below gets a miss from a full node above
    std::uint8_t everywhere_slots;  // everywhere task: the slots of `group` missed whole
  };
  const std::size_t levels = static_cast<std::size_t>(depth_levels_) + 1;
  std::vector<BatchGroup> scratch(levels * batches.size());
  std::vector<Task> tasks(1);
  tasks[0] = {depth_levels_, 0, {}, false, 0};
  for (const UpdateBatch* batch : batches) tasks[0].todo.push_back({batch, 0});
  std::vector<SplitNode> parents;  // nodes above the tasks, top down: refreshed at the end
  // Up to 256 subtrees a thread, more than apply_in_parallel's 16: a scan's
  // marks are where its surfaces are, so the subtrees are very uneven (TUM
  // at 4 mm on two threads: with 16 or 64 a thread, one worker's share of a
  // frame's apply was up to 1.7 times the other's; with 256, 1.0 to 1.3
  // times). But the split is serial and each subtree costs the pool a task:
  // for small batches (TUM at 2 cm) 256 a thread made the split 4% of a
  // frame, and 64 bricks a subtree still gave ~480 tasks of 10 us each, so
  // at least 256 bricks a subtree.
  std::size_t bricks = 0;
  for (const UpdateBatch* batch : batches) bricks += batch->group_count(1);
  const std::size_t wanted =
      std::clamp(bricks / kApplyBricksPerTask, std::size_t{pool.size()} * 16, std::size_t{pool.size()} * 256);
  std::vector<Task> final_tasks;  // not split further
  while (!tasks.empty() && final_tasks.size() + tasks.size() < wanted) {
    std::vector<Task> next;
    for (Task& task : tasks) {
      if (task.depth <= 2) {
        final_tasks.push_back(std::move(task));
        continue;
      }
      if (task.everywhere_slots != 0) {
        // A node missed whole costs as much as the map holds below it (a
        // wide free region seen before at full detail): split it into its
        // children, as apply_everywhere would recurse, refreshing it after.
        std::uint8_t childless = 0;
        InnerGroup& node = inner_[task.depth][task.group];
        catch_up(task.depth, task.group);  // the shortcut below reads a value
        for (unsigned slot = 0; slot < 8; ++slot) {
          if ((task.everywhere_slots & bit(slot)) == 0) continue;
          if (node.child[slot] == kNoGroup) {
            childless |= bit(slot);
          } else if (!(miss <= 0.0f && node.log_odds[slot] == range_.min)) {  // apply_everywhere's shortcut
            parents.push_back({task.depth, task.group, slot});
            next.push_back({task.depth - 1, node.child[slot], {}, false, 0xFF});
          }
        }
        if (childless != 0) final_tasks.push_back({task.depth, task.group, {}, false, childless});
        continue;
      }
      std::uint8_t everywhere = 0;
      for (unsigned slot = 0; slot < 8; ++slot) {
        std::span<const BatchGroup> children;
        bool children_missed = false;
        const SlotUpdate update = slot_update(task.depth, slot, task.todo, task.missed, scratch, children,
                                              children_missed);
        if (update == SlotUpdate::none) continue;
        if (update == SlotUpdate::everywhere) {
          everywhere |= bit(slot);
          continue;
        }
        if (inner_[task.depth][task.group].child[slot] == kNoGroup) expand(task.depth, task.group, slot);
        parents.push_back({task.depth, task.group, slot});
        next.push_back({task.depth - 1, inner_[task.depth][task.group].child[slot],
                        std::vector<BatchGroup>(children.begin(), children.end()), children_missed, 0});
      }
      if (everywhere != 0) next.push_back({task.depth, task.group, {}, false, everywhere});
    }
    tasks.swap(next);
  }
  for (Task& task : tasks) final_tasks.push_back(std::move(task));
  tasks.swap(final_tasks);

  // A map node gains children only where some batch has a group below it.
  std::vector<std::size_t> new_groups(levels, 0);
  for (const UpdateBatch* batch : batches) {
    new_groups[0] += 8 * batch->group_count(1);
    for (int d = 1; d < depth_levels_; ++d) new_groups[static_cast<std::size_t>(d)] += batch->group_count(d);
  }
  run_concurrently(pool, new_groups, tasks.size(),
                   [&](std::size_t i) {
                     const Task& task = tasks[i];
                     if (task.everywhere_slots != 0) {
                       for (unsigned slot = 0; slot < 8; ++slot) {
                         if ((task.everywhere_slots & bit(slot)) != 0) apply_everywhere(task.depth, task.group, slot, miss);
                       }
                       return;
                     }
                     std::vector<BatchGroup> task_scratch(levels * batches.size());
                     apply_groups(task.depth, task.group, task.todo, task.missed, hit, miss, task_scratch);
                   },
                   parents);
}

}  // namespace umbra
