#include "tree/update_batch.hpp"

#include <algorithm>

namespace umbra {

UpdateBatch::UpdateBatch(int depth_levels) { reset(depth_levels); }

UpdateBatch::UpdateBatch(const UpdateBatch& other) { *this = other; }

UpdateBatch& UpdateBatch::operator=(const UpdateBatch& other) {
  if (this == &other) return *this;
  depth_levels_ = other.depth_levels_;
  bricks_ = other.bricks_;
  inner_ = other.inner_;
  reset_cache();
  return *this;
}

void UpdateBatch::reset_cache() {
  last_code_ = 0;
  path_.fill(kNoGroup);
  path_[depth_levels_] = 0;
  valid_from_ = depth_levels_;
  covered_depth_ = -1;
  brick_ = depth_levels_ == 1 ? &bricks_[0] : nullptr;
  group2_ = depth_levels_ == 2 ? &inner_[2][0] : nullptr;
}

void UpdateBatch::reset(int depth_levels) {
  UMBRA_ASSERT(depth_levels >= 1 && depth_levels <= kMaxDepthLevels);
  depth_levels_ = depth_levels;
  // The pools keep their memory from scan to scan (GroupPool::recycle).
  bricks_.recycle();
  inner_.resize(static_cast<std::size_t>(depth_levels) + 1);
  for (GroupPool<Inner>& pool : inner_) pool.recycle();
  [[maybe_unused]] const std::uint32_t root_group = new_group(depth_levels, false);
  UMBRA_ASSERT(root_group == 0);
  reset_cache();
}

std::uint32_t UpdateBatch::new_group(int depth, bool full) {
  if (depth == 1) {
    const std::uint32_t group = bricks_.allocate();
    Brick& brick = bricks_[group];
    brick.miss.fill(full ? 0xFF : 0);
    brick.hit.fill(0);
    brick.keep = 0;
    return group;
  }
  const std::uint32_t group = inner_[depth].allocate();
  Inner& node = inner_[depth][group];
  node.child.fill(kNoGroup);
  node.full = full ? 0xFF : 0;
  node.hits = 0;
  node.keep = 0;
  return group;
}

void UpdateBatch::release_group(int depth, std::uint32_t group) {
  if (depth == 1) {
    bricks_.release(group);
  } else {
    inner_[depth].release(group);
  }
}

std::uint32_t UpdateBatch::descend(std::uint64_t code, int depth, Mark mark) {
  UMBRA_ASSERT(depth >= 1);
  const int top = morton::highest_differing_depth(code, last_code_);
  const int start = std::max({top, valid_from_, depth});
  std::uint32_t group = path_[start];
  for (int d = start; d > depth; --d) {
    Inner& node = inner_[d][group];
    const unsigned slot = morton::slot(code, d);
    const auto bit = static_cast<std::uint8_t>(1u << slot);
    std::uint32_t child = node.child[slot];
    if (node.full & bit) {
      if (mark == Mark::miss) {  // the whole node already gets a miss
        last_code_ = code;
        covered_depth_ = d;
        valid_from_ = d;
        if (d == 2) group2_ = &node;
        return kNoGroup;
      }
      // A hit inside a full node: split it into a full child group.
      // (`node` stays valid: allocation happens in the pool one depth below.)
      node.full = static_cast<std::uint8_t>(node.full & ~bit);
      child = new_group(d - 1, true);
      node.child[slot] = child;
    } else if (child == kNoGroup) {
      child = new_group(d - 1, false);
      node.child[slot] = child;
    }
    group = child;
    path_[d - 1] = group;
  }
  last_code_ = code;
  covered_depth_ = -1;
  valid_from_ = depth;
  if (depth == 1) brick_ = &bricks_[group];
  if (depth <= 2 && depth_levels_ >= 2) group2_ = &inner_[2][path_[2]];
  return group;
}

int UpdateBatch::add_hits_in_brick(std::uint64_t code, std::uint64_t voxels) {
  const std::uint32_t group = descend(code, 1, Mark::hit);
  Brick& brick = bricks_[group];
  const auto had = std::bit_cast<std::uint64_t>(brick.hit);
  const std::uint64_t added = voxels & ~had;
  if (added == 0) return 0;  // its path already holds the marks below
  brick.hit = std::bit_cast<std::array<std::uint8_t, 8>>(had | added);
  // Every group on the path now holds a hit (path_ is valid from depth 1 up;
  // a brick's voxels share their path from depth 2): above the first group
  // that already said so, all do.
  for (int d = 2; d <= depth_levels_; ++d) {
    std::uint8_t& marks = inner_[d][path_[d]].hits;
    const auto slot_bit = static_cast<std::uint8_t>(1u << morton::slot(code, d));
    if ((marks & slot_bit) != 0) break;
    marks |= slot_bit;
  }
  return std::popcount(added);
}

void UpdateBatch::add_misses_slow(std::uint64_t code, std::uint64_t voxels) {
  if (descend(code, 1, Mark::miss) == kNoGroup) return;
  or_misses(code, voxels);
}

void UpdateBatch::add_miss_node(std::uint64_t code, int depth) { miss_node(code, depth, false); }

bool UpdateBatch::add_miss_node_unless_hit(std::uint64_t code, int depth) { return miss_node(code, depth, true); }

bool UpdateBatch::miss_node(std::uint64_t code, int depth, bool unless_hit) {
  UMBRA_ASSERT(depth >= 0 && depth <= depth_levels_);
  if (depth == 0) {
    if (unless_hit && descend(code, 1, Mark::miss) != kNoGroup &&
        (bricks_[path_[1]].hit[morton::slot(code, 1)] >> morton::slot(code, 0) & 1u) != 0) {
      return false;
    }
    add_miss(code);
    return true;
  }
  // Inside the full node that covered the last code: missed already. A
  // marked node may be full itself (its voxels missed one by one), and is
  // still refused below.
  const int top = morton::highest_differing_depth(code, last_code_);
  if (top < covered_depth_ && (depth < covered_depth_ || (!unless_hit && depth == covered_depth_))) return true;
  const std::uint32_t group = descend(code, depth, Mark::miss);
  if (group == kNoGroup) return true;  // a full node above covers it
  const unsigned slot = morton::slot(code, depth);
  if (depth == 1) {
    Brick& brick = bricks_[group];
    if (unless_hit && (brick.hit[slot] != 0 || (brick.keep >> slot & 1u) != 0)) return false;
    brick.miss[slot] = 0xFF;
    if (is_full(brick) && brick.keep == 0) collapse_upwards(code, 1);
    return true;
  }
  Inner& node = inner_[depth][group];
  const auto bit = static_cast<std::uint8_t>(1u << slot);
  if (unless_hit && ((node.hits | node.keep) & bit) != 0) return false;
  if (!(node.full & bit)) {
    const std::uint32_t child = node.child[slot];
    if (child != kNoGroup) {
      if (!fill_with_misses(depth - 1, child)) return true;  // a hit below keeps the node partial
      release_group(depth - 1, child);
      node.child[slot] = kNoGroup;
    }
    node.full |= bit;
  }
  if (node.full == 0xFF && node.keep == 0) {
    collapse_upwards(code, depth);
  } else {
    covered_depth_ = depth;
    valid_from_ = depth;
  }
  return true;
}

void UpdateBatch::keep_fine(std::uint64_t code, int depth, int up_to) {
  UMBRA_ASSERT(depth >= 1 && depth <= up_to && up_to <= depth_levels_);
  // Descending as a hit does splits any full node on the way, which is right:
  // a kept node must stay open for voxel-by-voxel misses.
  const std::uint32_t group = descend(code, depth, Mark::hit);
  for (int d = depth; d <= up_to; ++d) {  // path_ is valid from `depth` up
    const auto bit = static_cast<std::uint8_t>(1u << morton::slot(code, d));
    if (d == 1) {
      bricks_[group].keep |= bit;
    } else {
      inner_[d][path_[d]].keep |= bit;
    }
  }
}

bool UpdateBatch::fill_with_misses(int depth, std::uint32_t group) {
  if (depth == 1) {
    Brick& brick = bricks_[group];
    brick.miss.fill(0xFF);
    return is_full(brick);
  }
  Inner& node = inner_[depth][group];
  for (unsigned slot = 0; slot < 8; ++slot) {
    const auto bit = static_cast<std::uint8_t>(1u << slot);
    const std::uint32_t child = node.child[slot];
    if (node.full & bit) continue;
    if (child == kNoGroup || fill_with_misses(depth - 1, child)) {
      if (child != kNoGroup) {
        release_group(depth - 1, child);
        node.child[slot] = kNoGroup;
      }
      node.full |= bit;
    }
  }
  return node.full == 0xFF;
}

void UpdateBatch::collapse_upwards(std::uint64_t code, int depth) {
  int d = depth;
  while (d < depth_levels_) {
    release_group(d, path_[d]);
    Inner& parent = inner_[d + 1][path_[d + 1]];
    const unsigned slot = morton::slot(code, d + 1);
    parent.child[slot] = kNoGroup;
    parent.full |= static_cast<std::uint8_t>(1u << slot);
    ++d;
    if (parent.full != 0xFF || parent.keep != 0) break;
  }
  last_code_ = code;
  covered_depth_ = d;
  valid_from_ = d;
}

void UpdateBatch::merge(const UpdateBatch& other, bool with_hits) {
  UMBRA_ASSERT(other.depth_levels_ == depth_levels_);
  merge_group(other, depth_levels_, 0, 0, with_hits);
}

void UpdateBatch::merge_group(const UpdateBatch& other, int depth, std::uint32_t other_group,
                              std::uint64_t first_code, bool with_hits) {
  // Slots of the root group beyond 0 are never used, so visiting them is harmless.
  if (depth == 1) {
    const Brick& brick = other.bricks_[other_group];
    if (const auto misses = std::bit_cast<std::uint64_t>(brick.miss); misses != 0) add_misses_in_brick(first_code, misses);
    if (!with_hits) return;
    for (auto hits = std::bit_cast<std::uint64_t>(brick.hit); hits != 0; hits &= hits - 1) {
      add_hit(first_code | static_cast<std::uint64_t>(std::countr_zero(hits)));
    }
    return;
  }
  const Inner& node = other.inner_[depth][other_group];
  for (unsigned slot = 0; slot < 8; ++slot) {
    const std::uint64_t code = first_code | (std::uint64_t{slot} << (3 * depth));
    if (node.full & (1u << slot)) {
      add_miss_node(code, depth);
    } else if (node.child[slot] != kNoGroup) {
      merge_group(other, depth - 1, node.child[slot], code, with_hits);
    }
  }
}

bool UpdateBatch::holds_hit(std::uint64_t code, int depth) const {
  std::uint32_t group = 0;
  for (int d = depth_levels_; d >= 1; --d) {
    const unsigned slot = morton::slot(code, d);
    if (d == 1) {
      const Brick& brick = bricks_[group];
      return depth == 1 ? brick.hit[slot] != 0 : (brick.hit[slot] >> morton::slot(code, 0) & 1u) != 0;
    }
    const Inner& node = inner_[d][group];
    if ((node.hits >> slot & 1u) == 0) return false;
    if (d == depth) return true;
    group = node.child[slot];
    if (group == kNoGroup) return false;
  }
  return false;
}

bool UpdateBatch::empty() const {
  if (depth_levels_ == 1) {
    const Brick& root = bricks_[0];
    return root.miss[0] == 0 && root.hit[0] == 0;
  }
  const Inner& root = inner_[depth_levels_][0];
  return root.child[0] == kNoGroup && root.full == 0;
}

std::size_t UpdateBatch::memory_bytes() const {
  std::size_t bytes = sizeof(*this) + bricks_.memory_bytes() + inner_.capacity() * sizeof(inner_[0]);
  for (const auto& pool : inner_) bytes += pool.memory_bytes();
  return bytes;
}

}  // namespace umbra
