#include "tree/occupancy_tree.hpp"

#include <algorithm>
#include <stdexcept>
#include <tuple>

#include "tree/group_lanes.hpp"

namespace umbra {
namespace {

constexpr std::uint8_t bit(unsigned slot) { return static_cast<std::uint8_t>(1u << slot); }

// The worker this thread is during a parallel apply(); its pools then
// allocate from that worker's blocks (GroupPool's concurrent phase).
thread_local unsigned t_worker = 0;

void assign_bit(std::uint8_t& mask, unsigned slot, bool value) {
  mask = static_cast<std::uint8_t>(value ? (mask | bit(slot)) : (mask & ~bit(slot)));
}

/// Rounded average of the colored entries of a color group (weight 0: none).
std::pair<Rgb, std::uint8_t> average_color(const OccupancyTree::ColorGroup& colors) {
  unsigned r = 0;
  unsigned g = 0;
  unsigned b = 0;
  unsigned n = 0;
  for (unsigned i = 0; i < 8; ++i) {
    if (colors.weight[i] == 0) continue;
    r += colors.rgb[i].r;
    g += colors.rgb[i].g;
    b += colors.rgb[i].b;
    ++n;
  }
  if (n == 0) return {Rgb{}, 0};
  auto mean = [n](unsigned sum) { return static_cast<std::uint8_t>((sum + n / 2) / n); };
  return {Rgb{mean(r), mean(g), mean(b)}, 1};
}

bool same_colors(const OccupancyTree::ColorGroup& colors) {
  for (unsigned i = 1; i < 8; ++i) {
    if (colors.rgb[i] != colors.rgb[0] || colors.weight[i] != colors.weight[0]) return false;
  }
  return true;
}

}  // namespace

OccupancyTree::OccupancyTree(int depth_levels, LogOddsRange range, LogOddsThresholds thresholds, bool with_color)
    : depth_levels_(depth_levels),
      range_(range),
      thresholds_(thresholds),
      with_color_(with_color),
      leaves_(with_color) {
  if (depth_levels < 1 || depth_levels > kMaxDepthLevels) {
    throw std::invalid_argument("depth_levels must be in [1, 21], got " + std::to_string(depth_levels));
  }
  clear();
}

void OccupancyTree::clear() {
  leaves_.clear();
  inner_.clear();
  for (int d = 0; d <= depth_levels_; ++d) inner_.emplace_back(with_color_);
  [[maybe_unused]] const std::uint32_t root_group = new_inner_group(depth_levels_, 0.0f);
  UMBRA_ASSERT(root_group == 0);
  if (has_color()) {
    colors(depth_levels_, 0).rgb.fill(Rgb{});
    colors(depth_levels_, 0).weight.fill(0);
  }
}

// --- groups ---------------------------------------------------------------

std::uint32_t OccupancyTree::new_leaf_group(float value) {
  const std::uint32_t index = concurrent_ ? leaves_.allocate(t_worker) : leaves_.allocate();
  leaves_[index].log_odds.fill(value);
  return index;
}

std::uint32_t OccupancyTree::new_inner_group(int depth, float value) {
  const std::uint32_t index = concurrent_ ? inner_[depth].allocate(t_worker) : inner_[depth].allocate();
  InnerGroup& group = inner_[depth][index];
  group.log_odds.fill(value);
  group.child.fill(kNoGroup);
  group.contains_free = thresholds_.is_free(value) ? 0xFF : 0;
  group.contains_unknown = thresholds_.is_unknown(value) ? 0xFF : 0;
  group.all_same = 0;
  return index;
}

void OccupancyTree::release_group(int depth, std::uint32_t group) {
  // A group's colors are attached to it: they go with it.
  if (concurrent_) {
    if (depth == 0) {
      leaves_.release(t_worker, group);
    } else {
      inner_[depth].release(t_worker, group);
    }
    return;
  }
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

void OccupancyTree::expand(int depth, std::uint32_t group, unsigned slot) {
  InnerGroup& node = inner_[depth][group];
  UMBRA_ASSERT(depth >= 1 && node.child[slot] == kNoGroup);
  const float value = node.log_odds[slot];
  // `node` lives in the pool of `depth`; allocating one depth below never moves it.
  const std::uint32_t child = depth == 1 ? new_leaf_group(value) : new_inner_group(depth - 1, value);
  node.child[slot] = child;
  assign_bit(node.all_same, slot, true);
  if (has_color()) {
    const ColorGroup& parent = colors(depth, group);
    ColorGroup& children = colors(depth - 1, child);
    children.rgb.fill(parent.rgb[slot]);
    children.weight.fill(parent.weight[slot]);
  }
}

OccupancyTree::ChildrenSummary OccupancyTree::summarize_children(int depth, std::uint32_t child) const {
  if (depth == 1) {
    const detail::LaneSummary lanes = detail::summarize_lanes(leaves_[child].log_odds, thresholds_);
    return {lanes.max, lanes.free != 0, lanes.unknown != 0, lanes.same};
  }
  // Inner children carry their own maximum and indicator bits.
  const InnerGroup& children = inner_[depth - 1][child];
  const detail::LaneSummary lanes = detail::summarize_lanes(children.log_odds, thresholds_);
  bool childless = true;
  for (const std::uint32_t c : children.child) childless &= c == kNoGroup;
  return {lanes.max, children.contains_free != 0, children.contains_unknown != 0, lanes.same && childless};
}

void OccupancyTree::refresh(int depth, std::uint32_t group, unsigned slot, bool allow_prune) {
  const std::uint32_t child = inner_[depth][group].child[slot];
  UMBRA_ASSERT(child != kNoGroup);
  refresh_from(depth, group, slot, summarize_children(depth, child), allow_prune);
}

void OccupancyTree::refresh_from(int depth, std::uint32_t group, unsigned slot, const ChildrenSummary& summary,
                                 bool allow_prune) {
  InnerGroup& node = inner_[depth][group];
  const std::uint32_t child = node.child[slot];
  UMBRA_ASSERT(child != kNoGroup);
  const float max = summary.max;
  const bool any_free = summary.any_free;
  const bool any_unknown = summary.any_unknown;
  bool same = summary.same;
  if (has_color()) {
    const ColorGroup& child_colors = colors(depth - 1, child);
    ColorGroup& own = colors(depth, group);
    same &= same_colors(child_colors);
    if (same && allow_prune) {
      own.rgb[slot] = child_colors.rgb[0];
      own.weight[slot] = child_colors.weight[0];
    } else {
      std::tie(own.rgb[slot], own.weight[slot]) = average_color(child_colors);
    }
  }
  if (same && allow_prune) {
    release_group(depth - 1, child);
    node.child[slot] = kNoGroup;
    set_childless(node, slot, max);
    return;
  }
  node.log_odds[slot] = max;
  assign_bit(node.contains_free, slot, any_free);
  assign_bit(node.contains_unknown, slot, any_unknown);
  assign_bit(node.all_same, slot, same);
}

// --- reading ----------------------------------------------------------------

NodeSummary OccupancyTree::find(std::uint64_t code, int depth) const {
  UMBRA_ASSERT(depth >= 0 && depth <= depth_levels_);
  std::uint32_t group = 0;
  for (int d = depth_levels_;; --d) {
    if (d == 0) {
      const unsigned slot = morton::slot(code, 0);
      const float value = leaves_[group].log_odds[slot];
      return {value, thresholds_.is_free(value), thresholds_.is_unknown(value), false, 0,
              NodeRef{group, static_cast<std::uint8_t>(slot), 0}};
    }
    const InnerGroup& node = inner_[d][group];
    const unsigned slot = morton::slot(code, d);
    if (d == depth || node.child[slot] == kNoGroup) {
      return {node.log_odds[slot], (node.contains_free & bit(slot)) != 0,
              (node.contains_unknown & bit(slot)) != 0, node.child[slot] != kNoGroup, d,
              NodeRef{group, static_cast<std::uint8_t>(slot), static_cast<std::int8_t>(d)}};
    }
    group = node.child[slot];
  }
}

OccupancyTree::Cursor::Cursor(const OccupancyTree& tree) : tree_(tree), valid_from_(tree.depth_levels_) {
  path_[tree.depth_levels_] = 0;
}

float OccupancyTree::Cursor::max_log_odds(std::uint64_t code, int depth) {
  // Groups at depths >= the highest differing depth are shared with the last path.
  const int top = morton::highest_differing_depth(code, last_code_);
  int d = std::max({top, valid_from_, depth});
  last_code_ = code;
  std::uint32_t group = path_[d];
  for (;; --d) {
    if (d == 0) {
      valid_from_ = 0;
      return tree_.leaves_[group].log_odds[morton::slot(code, 0)];
    }
    const InnerGroup& node = tree_.inner_[d][group];
    const unsigned slot = morton::slot(code, d);
    if (d == depth || node.child[slot] == kNoGroup) {
      valid_from_ = d;
      return node.log_odds[slot];
    }
    group = node.child[slot];
    path_[d - 1] = group;
  }
}

std::optional<Rgb> OccupancyTree::color(NodeRef node) const {
  if (!has_color()) return std::nullopt;
  const ColorGroup& group = colors(node.depth, node.group);
  if (group.weight[node.slot] == 0) return std::nullopt;
  return group.rgb[node.slot];
}

bool OccupancyTree::contains_free(NodeRef node) const {
  if (node.depth == 0) return thresholds_.is_free(log_odds(node));
  return (inner_[node.depth][node.group].contains_free & bit(node.slot)) != 0;
}


// --- writing single voxels ---------------------------------------------------

std::uint32_t OccupancyTree::descend_splitting(std::uint64_t code, Path& path) {
  std::uint32_t group = 0;
  path[depth_levels_] = group;
  for (int d = depth_levels_; d >= 1; --d) {
    const unsigned slot = morton::slot(code, d);
    if (inner_[d][group].child[slot] == kNoGroup) expand(d, group, slot);
    group = inner_[d][group].child[slot];
    path[d - 1] = group;
  }
  return group;
}

void OccupancyTree::refresh_path(std::uint64_t code, const Path& path) {
  for (int d = 1; d <= depth_levels_; ++d) refresh(d, path[d], morton::slot(code, d), auto_prune_);
}

void OccupancyTree::update(std::uint64_t code, float delta) {
  const NodeSummary covering = find(code, 0);
  if (range_.add(covering.log_odds, delta) == covering.log_odds) return;  // already clamped: nothing to split
  Path path;
  float& value = leaves_[descend_splitting(code, path)].log_odds[morton::slot(code, 0)];
  value = range_.add(value, delta);
  refresh_path(code, path);
}

void OccupancyTree::set(std::uint64_t code, float log_odds) {
  const float value = range_.clamp(log_odds) + 0.0f;  // + 0.0f turns -0 into +0
  if (find(code, 0).log_odds == value) return;  // the childless node covering it has the value already
  Path path;
  leaves_[descend_splitting(code, path)].log_odds[morton::slot(code, 0)] = value;
  refresh_path(code, path);
}

void OccupancyTree::blend(Rgb& rgb, std::uint8_t& weight, Rgb sample) {
  if (weight == 0) {
    rgb = sample;
    weight = 1;
    return;
  }
  const unsigned n = weight;
  auto mix = [n](std::uint8_t old, std::uint8_t add) {
    return static_cast<std::uint8_t>((old * n + add + (n + 1) / 2) / (n + 1));
  };
  rgb = {mix(rgb.r, sample.r), mix(rgb.g, sample.g), mix(rgb.b, sample.b)};
  if (weight < 255) ++weight;
}

void OccupancyTree::add_color(std::uint64_t code, Rgb rgb) {
  const ColorSample sample{code, rgb};
  add_colors(std::span<const ColorSample>(&sample, 1));
}

void OccupancyTree::set_color(std::uint64_t code, Rgb rgb, std::uint8_t weight) {
  if (!has_color()) throw std::logic_error("set_color: the tree has no color");
  if (weight == 0) throw std::invalid_argument("set_color: weight must be at least 1");
  Path path;
  ColorGroup& leaf_colors = colors(0, descend_splitting(code, path));
  leaf_colors.rgb[morton::slot(code, 0)] = rgb;
  leaf_colors.weight[morton::slot(code, 0)] = weight;
  refresh_path(code, path);
}

void OccupancyTree::add_colors(std::span<const ColorSample> samples, ThreadPool* pool) {
  if (!has_color()) throw std::logic_error("add_colors: the tree has no color");
  if (samples.empty()) return;
  UMBRA_ASSERT(std::is_sorted(samples.begin(), samples.end(),
                              [](const ColorSample& a, const ColorSample& b) { return a.code < b.code; }));
  if (pool == nullptr || pool->size() < 2 || depth_levels_ < 3) {
    add_colors_below(depth_levels_, 0, 0, samples);
    return;
  }
  add_colors_in_parallel(samples, *pool);
}

void OccupancyTree::add_colors_below(int depth, std::uint32_t group, unsigned slot,
                                     std::span<const ColorSample> samples) {
  // Every sample lies in node (depth, group, slot).
  if (inner_[depth][group].child[slot] == kNoGroup) expand(depth, group, slot);
  add_colors_to_group(depth - 1, inner_[depth][group].child[slot], samples);
  refresh(depth, group, slot, auto_prune_);
}

void OccupancyTree::add_colors_to_group(int depth, std::uint32_t group, std::span<const ColorSample> samples) {
  // The samples are sorted, so each node's samples are one contiguous run.
  std::size_t begin = 0;
  while (begin < samples.size()) {
    const unsigned slot = morton::slot(samples[begin].code, depth);
    std::size_t end = begin + 1;
    while (end < samples.size() && morton::slot(samples[end].code, depth) == slot) ++end;
    if (depth == 0) {
      ColorGroup& leaf_colors = colors(0, group);
      for (std::size_t i = begin; i < end; ++i) blend(leaf_colors.rgb[slot], leaf_colors.weight[slot], samples[i].rgb);
    } else {
      add_colors_below(depth, group, slot, samples.subspan(begin, end - begin));
    }
    begin = end;
  }
}

void OccupancyTree::add_colors_in_parallel(std::span<const ColorSample> samples, ThreadPool& pool) {
  // 1. Walk down from the root, splitting the sorted samples by node, until
  //    there are enough groups with samples (tasks); a task owns its group.
  struct Task {
    int depth;
    std::uint32_t group;
    std::span<const ColorSample> samples;  // all in `group`
  };
  std::vector<SplitNode> parents{{depth_levels_, 0, 0}};
  if (inner_[depth_levels_][0].child[0] == kNoGroup) expand(depth_levels_, 0, 0);
  std::vector<Task> tasks{{depth_levels_ - 1, inner_[depth_levels_][0].child[0], samples}};
  const std::size_t wanted = std::size_t{pool.size()} * 16;
  while (tasks.size() < wanted) {
    std::vector<Task> next;
    bool deeper = false;
    for (const Task& task : tasks) {
      if (task.depth <= 2) {
        next.push_back(task);
        continue;
      }
      deeper = true;
      std::size_t begin = 0;
      while (begin < task.samples.size()) {
        // The run of this slot's samples, by binary search: scanning every
        // sample on every level was serial work on the whole scan's samples
        // (1.7 ms a TUM frame at 4 mm, a quarter of two threads' serial part).
        const unsigned slot = morton::slot(task.samples[begin].code, task.depth);
        const auto rest = task.samples.subspan(begin);
        const std::size_t end =
            begin + static_cast<std::size_t>(std::partition_point(rest.begin(), rest.end(),
                                                                  [&](const ColorSample& sample) {
                                                                    return morton::slot(sample.code, task.depth) == slot;
                                                                  }) -
                                             rest.begin());
        if (inner_[task.depth][task.group].child[slot] == kNoGroup) expand(task.depth, task.group, slot);
        parents.push_back({task.depth, task.group, slot});
        const std::uint32_t child = inner_[task.depth][task.group].child[slot];
        next.push_back({task.depth - 1, child, task.samples.subspan(begin, end - begin)});
        begin = end;
      }
    }
    tasks.swap(next);
    if (!deeper) break;
  }

  // 2. The tasks in parallel. A node is expanded only where samples lie, so
  //    the new groups at depth d are at most the distinct nodes of depth
  //    d + 1 that hold samples: 1 + the samples whose path parts from the
  //    previous sample's at depth d + 1 or above.
  std::vector<std::size_t> parting(static_cast<std::size_t>(depth_levels_) + 1, 0);
  for (std::size_t i = 1; i < samples.size(); ++i) {
    const int depth = morton::highest_differing_depth(samples[i].code, samples[i - 1].code);
    if (depth >= 0) ++parting[static_cast<std::size_t>(std::min(depth, depth_levels_))];
  }
  std::vector<std::size_t> new_groups(static_cast<std::size_t>(depth_levels_) + 1, 0);
  std::size_t parting_at_or_above = 0;
  for (int d = depth_levels_ - 1; d >= 0; --d) {
    parting_at_or_above += parting[static_cast<std::size_t>(d) + 1];
    new_groups[static_cast<std::size_t>(d)] = 1 + parting_at_or_above;
  }
  run_concurrently(pool, new_groups, tasks.size(),
                   [&](std::size_t i) { add_colors_to_group(tasks[i].depth, tasks[i].group, tasks[i].samples); },
                   parents);
}

// --- applying a scan ------------------------------------------------------------

void OccupancyTree::apply(const UpdateBatch& batch, float hit, float miss, ThreadPool* pool) {
  if (batch.depth_levels() != depth_levels_) {
    throw std::invalid_argument("update batch has " + std::to_string(batch.depth_levels()) +
                                " depth levels, the tree " + std::to_string(depth_levels_));
  }
  // Small trees and one thread go serially.
  if (pool == nullptr || pool->size() < 2 || depth_levels_ < 3) {
    apply_group(depth_levels_, 0, batch, 0, hit, miss);
    return;
  }
  apply_in_parallel(batch, hit, miss, *pool);
}

void OccupancyTree::apply_in_parallel(const UpdateBatch& batch, float hit, float miss, ThreadPool& pool) {
  // 1. Walk down from the root until there are enough independent subtrees
  //    (tasks), splitting map nodes on the way. A task owns map groups no
  //    other task writes: "group" tasks own the map group they update,
  //    "everywhere" tasks own the map group whose full slots they update.
  struct Task {
    int depth;
    std::uint32_t group;        // map group at `depth`
    std::uint32_t batch_group;  // group task: the batch group at `depth`
    std::uint8_t full_slots;    // everywhere task: slots of `group` wholly missed
  };
  std::vector<Task> tasks{{depth_levels_, 0, 0, 0}};
  std::vector<SplitNode> parents;  // nodes above the tasks, top down: refreshed at the end
  const std::size_t wanted = std::size_t{pool.size()} * 16;
  while (tasks.size() < wanted) {
    std::vector<Task> next;
    bool deeper = false;
    for (const Task& task : tasks) {
      if (task.full_slots != 0 || task.depth <= 2) {
        next.push_back(task);
        continue;
      }
      deeper = true;
      const UpdateBatch::Inner& todo = batch.inner(task.depth, task.batch_group);
      if (todo.full != 0) next.push_back({task.depth, task.group, 0, todo.full});
      for (unsigned slot = 0; slot < 8; ++slot) {
        if (todo.child[slot] == kNoGroup) continue;
        if (inner_[task.depth][task.group].child[slot] == kNoGroup) expand(task.depth, task.group, slot);
        parents.push_back({task.depth, task.group, slot});
        next.push_back({task.depth - 1, inner_[task.depth][task.group].child[slot], todo.child[slot], 0});
      }
    }
    tasks.swap(next);
    if (!deeper) break;
  }

  // 2. The tasks in parallel. A map node gains children only where the
  // batch has a group below it: that bounds the new groups per depth (a
  // brick can split its 8 nodes).
  std::vector<std::size_t> new_groups(static_cast<std::size_t>(depth_levels_) + 1, 0);
  new_groups[0] = 8 * batch.group_count(1);
  for (int d = 1; d < depth_levels_; ++d) new_groups[static_cast<std::size_t>(d)] = batch.group_count(d);
  run_concurrently(pool, new_groups, tasks.size(),
                   [&](std::size_t i) {
                     const Task& task = tasks[i];
                     if (task.full_slots != 0) {
                       for (unsigned slot = 0; slot < 8; ++slot) {
                         if ((task.full_slots & bit(slot)) != 0) apply_everywhere(task.depth, task.group, slot, miss);
                       }
                     } else {
                       apply_group(task.depth, task.group, batch, task.batch_group, hit, miss);
                     }
                   },
                   parents);
}

void OccupancyTree::run_concurrently(ThreadPool& pool, const std::vector<std::size_t>& new_groups, std::size_t tasks,
                                     const std::function<void(std::size_t)>& task,
                                     const std::vector<SplitNode>& parents) {
  // Each worker allocates from its own chunks (GroupPool's concurrent phase).
  leaves_.begin_concurrent(pool.size(), new_groups[0]);
  for (int d = 1; d <= depth_levels_; ++d) {
    inner_[d].begin_concurrent(pool.size(), new_groups[static_cast<std::size_t>(d)]);
  }
  concurrent_ = true;
  const auto end_concurrent = [&] {
    concurrent_ = false;
    leaves_.end_concurrent();
    for (int d = 1; d <= depth_levels_; ++d) inner_[d].end_concurrent();
  };
  try {
    pool.run(tasks, [&](std::size_t i, unsigned worker) {
      t_worker = worker;
      task(i);
      t_worker = 0;
    });
  } catch (...) {
    end_concurrent();
    throw;
  }
  end_concurrent();
  // The nodes above the tasks, bottom up.
  for (auto it = parents.rbegin(); it != parents.rend(); ++it) refresh(it->depth, it->group, it->slot, auto_prune_);
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
    if (full) {
      apply_everywhere(depth, group, slot, miss);
      continue;
    }
    if (inner_[depth][group].child[slot] == kNoGroup) expand(depth, group, slot);
    apply_group(depth - 1, inner_[depth][group].child[slot], batch, todo_child, hit, miss);
    refresh(depth, group, slot, auto_prune_);
  }
}

void OccupancyTree::apply_brick(std::uint32_t group, const UpdateBatch::Brick& todo, float hit, float miss) {
  // Only the leaves' pool allocates below: `node` stays where it is.
  InnerGroup& node = inner_[1][group];
  for (unsigned slot = 0; slot < 8; ++slot) {
    const std::uint8_t misses = todo.miss[slot];
    const std::uint8_t hits = todo.hit[slot];
    if ((misses | hits) == 0) continue;
    if (misses == 0xFF && hits == 0) {
      apply_everywhere(1, group, slot, miss);  // an inner leaf stays one node
      continue;
    }
    std::uint32_t child = node.child[slot];
    if (child == kNoGroup && !has_color()) {
      // A childless node (most of a scan's new space): its voxels' new
      // values from its one value, straight into a new group, or none when
      // they come out equal and pruning is on. What expand(), update_lanes
      // and refresh_from() gave, without filling a group first, the
      // refresh's call and, for a node that stays one value, a group
      // allocated and released (a fifth of applying a 3DTK scan).
      std::array<float, 8> values;
      values.fill(node.log_odds[slot]);
      const detail::LaneSummary leaves = detail::update_lanes(values, hits, misses, hit, miss, range_, thresholds_);
      if (leaves.same && auto_prune_) {
        set_childless(node, slot, leaves.max);
        continue;
      }
      child = new_leaf_group(0.0f);
      leaves_[child].log_odds = values;
      node.child[slot] = child;
      node.log_odds[slot] = leaves.max;
      assign_bit(node.contains_free, slot, leaves.free != 0);
      assign_bit(node.contains_unknown, slot, leaves.unknown != 0);
      assign_bit(node.all_same, slot, leaves.same);
      continue;
    }
    if (child == kNoGroup) {
      expand(1, group, slot);
      child = node.child[slot];
    }
    const detail::LaneSummary leaves =
        detail::update_lanes(leaves_[child].log_odds, hits, misses, hit, miss, range_, thresholds_);
    refresh_from(1, group, slot, {leaves.max, leaves.free != 0, leaves.unknown != 0, leaves.same}, auto_prune_);
  }
}

void OccupancyTree::apply_everywhere(int depth, std::uint32_t group, unsigned slot, float delta) {
  InnerGroup& node = inner_[depth][group];
  const std::uint32_t child = node.child[slot];
  if (child == kNoGroup) {
    set_childless(node, slot, range_.add(node.log_odds[slot], delta));
    return;
  }
  // A miss changes nothing below a node whose maximum is already the
  // clamping minimum: every voxel there is at it (free space seen again and
  // again, kept unpruned by differences elsewhere).
  if (delta <= 0.0f && node.log_odds[slot] == range_.min) return;
  if (depth == 1) {
    for (float& v : leaves_[child].log_odds) v = range_.add(v, delta);
  } else {
    for (unsigned i = 0; i < 8; ++i) apply_everywhere(depth - 1, child, i, delta);
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
  clamp_below(depth_levels_, 0, 0);
}

void OccupancyTree::clamp_below(int depth, std::uint32_t group, unsigned slot) {
  InnerGroup& node = inner_[depth][group];
  const std::uint32_t child = node.child[slot];
  if (child == kNoGroup) {
    set_childless(node, slot, range_.clamp(node.log_odds[slot]));
    return;
  }
  if (depth == 1) {
    for (float& v : leaves_[child].log_odds) v = range_.clamp(v);
  } else {
    for (unsigned i = 0; i < 8; ++i) clamp_below(depth - 1, child, i);
  }
  refresh(depth, group, slot, auto_prune_);
}

void OccupancyTree::set_auto_prune(bool on) {
  auto_prune_ = on;
  if (on) prune();
}

void OccupancyTree::prune() { prune_below(depth_levels_, 0, 0); }

void OccupancyTree::prune_below(int depth, std::uint32_t group, unsigned slot) {
  const std::uint32_t child = inner_[depth][group].child[slot];
  if (child == kNoGroup) return;
  if (depth > 1) {
    for (unsigned i = 0; i < 8; ++i) prune_below(depth - 1, child, i);
  }
  refresh(depth, group, slot, true);
}

void OccupancyTree::refresh_all() { refresh_below(depth_levels_, 0, 0); }

void OccupancyTree::refresh_below(int depth, std::uint32_t group, unsigned slot) {
  InnerGroup& node = inner_[depth][group];
  const std::uint32_t child = node.child[slot];
  if (child == kNoGroup) {
    set_childless(node, slot, node.log_odds[slot]);
    return;
  }
  if (depth > 1) {
    for (unsigned i = 0; i < 8; ++i) refresh_below(depth - 1, child, i);
  }
  refresh(depth, group, slot, false);
}

// --- building -------------------------------------------------------------------

void OccupancyTree::subdivide(NodeRef node) {
  if (node.depth < 1 || has_children(node)) {
    throw std::logic_error("subdivide: node must be childless and above the finest depth");
  }
  expand(node.depth, node.group, node.slot);
}

void OccupancyTree::set_childless_value(NodeRef node, float log_odds) {
  if (node.depth == 0) {
    leaves_[node.group].log_odds[node.slot] = log_odds;
    return;
  }
  if (has_children(node)) throw std::logic_error("set_childless_value: node has children");
  set_childless(inner_[node.depth][node.group], node.slot, log_odds);
}

void OccupancyTree::set_childless_color(NodeRef node, Rgb rgb, std::uint8_t weight) {
  if (!has_color()) throw std::logic_error("set_childless_color: the tree has no color");
  if (has_children(node)) throw std::logic_error("set_childless_color: node has children");
  ColorGroup& group = colors(node.depth, node.group);
  group.rgb[node.slot] = weight == 0 ? Rgb{} : rgb;
  group.weight[node.slot] = weight;
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
  // The pools count their attached colors.
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
  // Only spelt out for a problem: check_invariants visits every node, and
  // building this text for each was most of its time.
  const auto where = [&] {
    return "node depth " + std::to_string(depth) + " group " + std::to_string(group_index) + " slot " +
           std::to_string(slot) + ": ";
  };
  const float value = group.log_odds[slot];
  const std::uint32_t child = group.child[slot];
  const bool free_bit = (group.contains_free & bit(slot)) != 0;
  const bool unknown_bit = (group.contains_unknown & bit(slot)) != 0;
  const bool same_bit = (group.all_same & bit(slot)) != 0;
  if (child == kNoGroup) {
    if (value < range_.min || value > range_.max) return where() + "value outside the clamping range";
    if (free_bit != thresholds_.is_free(value)) return where() + "contains_free wrong (childless)";
    if (unknown_bit != thresholds_.is_unknown(value)) return where() + "contains_unknown wrong (childless)";
    if (same_bit) return where() + "all_same set on a childless node";
    return {};
  }
  auto& seen_here = seen[depth - 1];
  if (seen_here.size() <= child) seen_here.resize(child + 1, false);
  if (seen_here[child]) return where() + "child group referenced twice";
  seen_here[child] = true;

  if (depth == 1) {
    for (const float v : leaves_[child].log_odds) {
      if (v < range_.min || v > range_.max) return where() + "leaf value outside the clamping range";
    }
  } else {
    for (unsigned i = 0; i < 8; ++i) {
      std::string problem = check_node(depth - 1, child, i, seen);
      if (!problem.empty()) return problem;
    }
  }
  const ChildrenSummary summary = summarize_children(depth, child);
  const float max = summary.max;
  const bool any_free = summary.any_free;
  const bool any_unknown = summary.any_unknown;
  bool same = summary.same;
  if (has_color()) {
    const ColorGroup& child_colors = colors(depth - 1, child);
    same &= same_colors(child_colors);
    const auto [rgb, weight] = average_color(child_colors);
    const ColorGroup& own = colors(depth, group_index);
    if (own.weight[slot] != weight || (weight != 0 && own.rgb[slot] != rgb)) {
      return where() + "color is not the average of the colored children";
    }
  }
  if (value != max) return where() + "value is not the maximum of the children";
  if (free_bit != any_free) return where() + "contains_free differs from the children";
  if (unknown_bit != any_unknown) return where() + "contains_unknown differs from the children";
  if (same_bit != same) return where() + "all_same differs from the children";
  if (same && auto_prune_) return where() + "eight equal childless children left unpruned";
  return {};
}

}  // namespace umbra
