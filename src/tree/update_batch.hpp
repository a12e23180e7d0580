// UpdateBatch: the voxels one scan updates and how, collected before the
// tree is touched.
//
// OctoMap's rule for one scan is: every voxel a ray passes gets one miss,
// every end voxel one hit, a voxel is updated at most once, and a hit wins
// over a miss. OctoMap collects the keys in two hash sets; umbra collects
// them in this small octree of bit masks, shaped like the map:
//
//   Inner group (depth >= 2, 8 sibling nodes)      Brick (depth 1: 8 nodes x 8 voxels)
//   +--------------------------+------+            +-------------+-------------+
//   | child[8]: uint32 indices | full |            | miss[8]: u8 | hit[8]: u8  |  one bit per voxel
//   +--------------------------+------+            +-------------+-------------+
//
// The finest level is a brick of 4x4x4 voxels held in 16 bytes, so the
// three quarters of ray steps that stay within one brick only set a bit.
// A `full` bit means "every voxel of that node gets a miss and none a hit";
// for a depth-1 node that is miss == 0xFF and hit == 0. When the eight nodes
// of a group are all full, the group is released and its parent's bit is
// set instead: the dense free space near a sensor collapses to a few coarse
// nodes, so the batch stays small and later rays through it stop after one
// comparison.
//
// Adding codes in ray order is cheap: the path of the previous code is
// cached, and a new code only descends from the highest depth at which the
// two paths differ. The tree applies a batch in one depth-first walk
// (OccupancyTree::apply). Inner groups also remember which nodes hold a hit,
// so that the fast integrator can avoid clearing a coarse node wholesale
// when this scan saw a surface inside it.
//
// Not thread-safe; use one batch per thread and merge() them.
#pragma once

#include <array>
#include <bit>
#include <cstdint>
#include <vector>

#include "umbra/core/morton.hpp"
#include "tree/group_pool.hpp"

namespace umbra {

class UpdateBatch {
 public:
  struct Inner {
    std::array<std::uint32_t, 8> child;  // group one depth below, kNoGroup: nothing there (unless `full`)
    std::uint8_t full;                   // bit i: node i's whole region gets a miss
    std::uint8_t hits;                   // bit i: node i's region holds a hit
    std::uint8_t keep;                   // bit i: never clear node i whole (see keep_fine)
  };
  struct Brick {
    std::array<std::uint8_t, 8> miss;  // miss[i] bit j: voxel j of depth-1 node i gets a miss ...
    std::array<std::uint8_t, 8> hit;   // ... unless this bit is set: then it gets a hit
    std::uint8_t keep;                 // bit i: never clear depth-1 node i whole (see keep_fine)
  };
  // Read as one little-endian uint64, bit (8 i + j) of `miss` is voxel
  // 8 i + j of the brick, i.e. the low 6 bits of its Morton code.
  static_assert(std::endian::native == std::endian::little, "Brick masks are read as little-endian words");

  explicit UpdateBatch(int depth_levels = 16);
  /// A copy holds the same marks; its path cache starts empty.
  UpdateBatch(const UpdateBatch& other);
  UpdateBatch& operator=(const UpdateBatch& other);
  UpdateBatch(UpdateBatch&&) noexcept = default;
  UpdateBatch& operator=(UpdateBatch&&) noexcept = default;

  /// Empties the batch (and frees its memory) for a map of `depth_levels`.
  void reset(int depth_levels);

  /// The finest voxel `code` gets a hit (wins over any miss). True when it
  /// had none before.
  bool add_hit(std::uint64_t code) { return add_hits_in_brick(code, std::uint64_t{1} << (code & 63)) != 0; }

  /// Hits for several voxels of one brick (bit i of `voxels`: the voxel
  /// whose code is (code & ~63) + i, as for add_misses_in_brick): one
  /// descent for all of them. Returns how many had no hit before.
  int add_hits_in_brick(std::uint64_t code, std::uint64_t voxels);

  /// The finest voxel `code` gets a miss, unless it gets a hit.
  void add_miss(std::uint64_t code) { add_misses_in_brick(code, std::uint64_t{1} << (code & 63)); }

  /// Misses for several voxels of one brick (the 4x4x4 voxels of the depth-2
  /// node containing `code`): bit i of `voxels` stands for the voxel whose
  /// code is (code & ~63) + i. Rays collect the voxels they pass in one brick
  /// and hand them over together (see Integrator::trace).
  void add_misses_in_brick(std::uint64_t code, std::uint64_t voxels) {
    // Inline fast paths: still inside the full node that covered the
    // previous code; the same brick; a sibling brick in the same group.
    const int top = morton::highest_differing_depth(code, last_code_);
    if (top < covered_depth_) return;
    if (top <= 1 && valid_from_ == 1) {
      or_misses(code, voxels);
      return;
    }
    if (top == 2 && valid_from_ <= 2) {
      const Inner& group = *group2_;
      const unsigned slot = morton::slot(code, 2);
      const std::uint32_t child = group.child[slot];
      if ((group.full >> slot & 1u) != 0) {
        last_code_ = code;
        covered_depth_ = 2;
        valid_from_ = 2;
        return;
      }
      if (child != kNoGroup) {
        path_[1] = child;
        brick_ = &bricks_[child];
        valid_from_ = 1;
        covered_depth_ = -1;
        or_misses(code, voxels);
        return;
      }
    }
    add_misses_slow(code, voxels);
  }

  /// Every voxel of the depth-`depth` node containing `code` gets a miss
  /// (voxels with a hit keep it).
  void add_miss_node(std::uint64_t code, int depth);
  /// The same, unless the node holds a hit or was marked with keep_fine: then
  /// nothing is marked and the result is false (the fast integrator then
  /// traces the node voxel by voxel).
  bool add_miss_node_unless_hit(std::uint64_t code, int depth);
  /// Marks the depth-`depth` node (>= 1) containing `code`, and its
  /// ancestors up to depth `up_to` (>= depth), so that add_miss_node_unless_hit
  /// refuses them. The answer for a marked node must not depend on the misses
  /// added before it (the fast integrator's workers each see only their own
  /// rays' misses, yet must decide alike): a group holding a mark is never
  /// collapsed into its parent, so the mark stays even when every voxel of
  /// the node has been missed, and a full node never covers a marked one
  /// below it (their ancestors up to the marked depth are marked too).
  void keep_fine(std::uint64_t code, int depth, int up_to);
  void keep_fine(std::uint64_t code, int depth) { keep_fine(code, depth, depth); }
  /// Merges another batch over the same depth levels into this one; its
  /// hits too unless `with_hits` is false (when both already hold the same hits).
  void merge(const UpdateBatch& other, bool with_hits = true);

  [[nodiscard]] bool empty() const;
  /// Groups in use at `depth` (bricks at depth 1).
  [[nodiscard]] std::size_t group_count(int depth) const {
    return depth == 1 ? bricks_.size() : inner_[depth].size();
  }
  /// Whether the depth-`depth` node containing `code` holds a hit (a walk from the root).
  [[nodiscard]] bool holds_hit(std::uint64_t code, int depth) const;
  [[nodiscard]] int depth_levels() const { return depth_levels_; }
  [[nodiscard]] std::size_t memory_bytes() const;

  // Read access for the walk that applies the batch. The root is slot 0 of
  // group 0 at depth depth_levels() (a brick when depth_levels() == 1).
  [[nodiscard]] const Inner& inner(int depth, std::uint32_t group) const { return inner_[depth][group]; }
  [[nodiscard]] const Brick& brick(std::uint32_t group) const { return bricks_[group]; }

  /// True when every voxel of the brick gets a miss and none a hit.
  static bool is_full(const Brick& brick) {
    return std::bit_cast<std::uint64_t>(brick.miss) == ~std::uint64_t{0} &&
           std::bit_cast<std::uint64_t>(brick.hit) == 0;
  }

 private:
  enum class Mark { hit, miss };
  void add_misses_slow(std::uint64_t code, std::uint64_t voxels);
  /// ORs misses into the cached brick (which holds `code`).
  void or_misses(std::uint64_t code, std::uint64_t voxels) {
    last_code_ = code;
    Brick& brick = *brick_;
    const std::uint64_t misses = std::bit_cast<std::uint64_t>(brick.miss) | voxels;
    brick.miss = std::bit_cast<std::array<std::uint8_t, 8>>(misses);
    if (misses == ~std::uint64_t{0} && is_full(brick) && brick.keep == 0) collapse_upwards(code, 1);
  }
  /// Walks the cached path down to the group at `depth` (>= 1) on the path of
  /// `code` and returns it, or kNoGroup when a full node above already covers
  /// it (only for misses: a hit splits full nodes on its way down).
  std::uint32_t descend(std::uint64_t code, int depth, Mark mark);
  /// The group at `depth` on the path of `code` is entirely full and holds no
  /// keep mark: release it and set its parent's bit instead, repeating upwards
  /// while the parent is full and unmarked too. A group with a keep mark stays
  /// (see keep_fine: the mark must outlive its node being missed).
  void collapse_upwards(std::uint64_t code, int depth);
  /// Marks every voxel below group (depth, group) missed; true if all are now full.
  bool fill_with_misses(int depth, std::uint32_t group);
  std::uint32_t new_group(int depth, bool full);
  /// add_miss_node and add_miss_node_unless_hit.
  bool miss_node(std::uint64_t code, int depth, bool unless_hit);
  void release_group(int depth, std::uint32_t group);
  void merge_group(const UpdateBatch& other, int depth, std::uint32_t other_group, std::uint64_t first_code,
                   bool with_hits);
  /// Forgets the cached path (after the pools were replaced).
  void reset_cache();

  int depth_levels_ = 0;
  GroupPool<Brick> bricks_;              // depth 1
  std::vector<GroupPool<Inner>> inner_;  // index = depth >= 2; [0] and [1] are unused

  // Cache of the last added code's path (see the file comment).
  std::uint64_t last_code_ = 0;
  std::array<std::uint32_t, kMaxDepthLevels + 1> path_{};  // group per depth, valid from valid_from_ up
  int valid_from_ = 1;
  int covered_depth_ = -1;   // depth of the full node that contained the last code, or -1
  // Pointers to the cached path's groups at depths 1 and 2, valid while
  // valid_from_ <= 1 resp. <= 2. Only descend() allocates, and it renews them.
  Brick* brick_ = nullptr;
  Inner* group2_ = nullptr;
};

}  // namespace umbra
