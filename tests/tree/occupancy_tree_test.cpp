// OccupancyTree: node kinds, propagation (max, indicators), pruning,
// thresholds, memory accounting; random update sequences keep every
// invariant (check_invariants recomputes everything from scratch).
#include <random>

#include <gtest/gtest.h>

#include "umbra/core/grid.hpp"
#include "tree/occupancy_tree.hpp"
#include "tree/update_batch.hpp"

namespace umbra {
namespace {

const SensorModel kSensor;
const LogOddsRange kRange = LogOddsRange::from(kSensor);
const LogOddsThresholds kThresholds = LogOddsThresholds::from(Thresholds{});

std::uint64_t code(std::uint32_t x, std::uint32_t y, std::uint32_t z) { return morton::encode({x, y, z}); }

TEST(OccupancyTree, StartsAsOneUnknownRoot) {
  const OccupancyTree tree(16, kRange, kThresholds);
  const NodeCounts counts = tree.count_nodes();
  EXPECT_EQ(counts.inner, 0u);
  EXPECT_EQ(counts.inner_leaf, 1u);
  EXPECT_EQ(counts.leaf, 0u);
  const NodeSummary root = tree.find(0, 16);
  EXPECT_EQ(root.log_odds, 0.0f);
  EXPECT_TRUE(root.contains_unknown);
  EXPECT_FALSE(root.contains_free);
  EXPECT_EQ(tree.find(code(5, 6, 7), 0).depth, 16) << "an unknown root covers every voxel";
  EXPECT_EQ(tree.check_invariants(), "");
}

TEST(OccupancyTree, OneUpdateCreatesAPathOfGroupsOfEight) {
  OccupancyTree tree(4, kRange, kThresholds);
  tree.update(code(3, 5, 9), kSensor.hit_log_odds());
  const NodeCounts counts = tree.count_nodes();
  EXPECT_EQ(counts.inner, 4u);        // root and one node per depth 3..1
  EXPECT_EQ(counts.inner_leaf, 21u);  // 7 unknown siblings at depths 3, 2, 1
  EXPECT_EQ(counts.leaf, 8u);
  EXPECT_EQ(tree.find(code(3, 5, 9), 0).log_odds, kSensor.hit_log_odds());
  EXPECT_EQ(tree.find(code(2, 5, 9), 0).log_odds, 0.0f);
  // Inner values are the maximum, indicators say "unknown inside".
  for (int depth = 1; depth <= 4; ++depth) {
    const NodeSummary s = tree.find(code(3, 5, 9), depth);
    EXPECT_EQ(s.log_odds, kSensor.hit_log_odds()) << depth;
    EXPECT_TRUE(s.contains_unknown) << depth;
    EXPECT_FALSE(s.contains_free) << depth;
    EXPECT_TRUE(s.has_children) << depth;
  }
  EXPECT_EQ(tree.check_invariants(), "");
}

TEST(OccupancyTree, MaximumAndIndicatorsFollowTheChildren) {
  OccupancyTree tree(3, kRange, kThresholds);
  tree.update(code(0, 0, 0), kSensor.miss_log_odds());
  NodeSummary s = tree.find(0, 1);
  EXPECT_EQ(s.log_odds, 0.0f) << "unknown siblings (0) are larger than a free voxel";
  EXPECT_TRUE(s.contains_free);
  EXPECT_TRUE(s.contains_unknown);
  for (std::uint32_t i = 1; i < 8; ++i) tree.update(morton::encode(morton::decode(i)), kSensor.miss_log_odds());
  // All eight equal: pruned into the depth-1 node.
  s = tree.find(0, 0);
  EXPECT_EQ(s.depth, 1);
  EXPECT_EQ(s.log_odds, kSensor.miss_log_odds());
  s = tree.find(0, 1);
  EXPECT_FALSE(s.has_children);
  EXPECT_TRUE(s.contains_free);
  EXPECT_FALSE(s.contains_unknown);
  EXPECT_EQ(tree.find(0, 2).log_odds, 0.0f);
  EXPECT_EQ(tree.check_invariants(), "");
}

TEST(OccupancyTree, UpdatingInsideAPrunedNodeSplitsItAndMergesAgain) {
  OccupancyTree tree(3, kRange, kThresholds);
  for (std::uint32_t i = 0; i < 8; ++i) tree.update(i, kSensor.miss_log_odds());
  ASSERT_EQ(tree.count_nodes().leaf, 0u);
  tree.update(5, kSensor.hit_log_odds());
  EXPECT_EQ(tree.count_nodes().leaf, 8u);
  EXPECT_EQ(tree.find(5, 0).log_odds, kRange.add(kSensor.miss_log_odds(), kSensor.hit_log_odds()));
  EXPECT_EQ(tree.find(4, 0).log_odds, kSensor.miss_log_odds());
  tree.set(5, kSensor.miss_log_odds());
  EXPECT_EQ(tree.count_nodes().leaf, 0u) << "equal again: merged";
  // An update that changes nothing (already clamped) does not split.
  for (int i = 0; i < 10; ++i) {
    for (std::uint32_t v = 0; v < 8; ++v) tree.update(v, kSensor.miss_log_odds());
  }
  ASSERT_EQ(tree.find(0, 0).log_odds, kRange.min);
  ASSERT_EQ(tree.find(0, 0).depth, 1);
  tree.update(3, kSensor.miss_log_odds());
  EXPECT_EQ(tree.count_nodes().leaf, 0u);
  EXPECT_EQ(tree.check_invariants(), "");
}

TEST(OccupancyTree, WithoutAutoPruningEqualChildrenStayAndSayAllSame) {
  OccupancyTree tree(3, kRange, kThresholds);
  tree.set_auto_prune(false);
  for (std::uint32_t i = 0; i < 8; ++i) tree.update(i, kSensor.miss_log_odds());
  EXPECT_EQ(tree.count_nodes().leaf, 8u);
  const NodeRef depth1 = tree.child(tree.child(tree.root(), 0), 0);
  EXPECT_EQ(depth1.depth, 1);
  EXPECT_TRUE(tree.all_children_same(depth1));
  EXPECT_EQ(tree.check_invariants(), "");
  tree.prune();
  EXPECT_EQ(tree.count_nodes().leaf, 0u);
  EXPECT_EQ(tree.check_invariants(), "");
  // Switching auto-pruning back on prunes what accumulated meanwhile.
  for (std::uint32_t i = 8; i < 16; ++i) tree.update(i, kSensor.miss_log_odds());
  EXPECT_EQ(tree.count_nodes().leaf, 8u);
  tree.set_auto_prune(true);
  EXPECT_EQ(tree.count_nodes().leaf, 0u);
  EXPECT_EQ(tree.check_invariants(), "");
}

TEST(OccupancyTree, ChangingThresholdsRecomputesEveryIndicator) {
  OccupancyTree tree(4, kRange, kThresholds);
  tree.update(code(1, 1, 1), kSensor.miss_log_odds());  // p = 0.4
  tree.update(code(9, 9, 9), kSensor.hit_log_odds());   // p = 0.7
  EXPECT_TRUE(tree.find(code(1, 1, 1), 4).contains_free);
  // Free below 0.35: the 0.4 voxel becomes unknown; nothing is free anymore.
  tree.set_thresholds(LogOddsThresholds::from(Thresholds{0.8, 0.35}));
  EXPECT_FALSE(tree.find(code(1, 1, 1), 4).contains_free);
  EXPECT_TRUE(tree.find(code(1, 1, 1), 1).contains_unknown);
  EXPECT_EQ(tree.thresholds().classify(tree.find(code(9, 9, 9), 0).log_odds), OccupancyState::unknown);
  EXPECT_EQ(tree.check_invariants(), "");
  tree.set_thresholds(kThresholds);
  EXPECT_TRUE(tree.find(code(1, 1, 1), 4).contains_free);
  EXPECT_EQ(tree.check_invariants(), "");
}

TEST(OccupancyTree, MemoryIsWhatThePoolsAllocated) {
  OccupancyTree tree(16, kRange, kThresholds);
  const std::size_t empty = tree.memory_bytes();
  std::mt19937 rng(1);
  for (int i = 0; i < 20000; ++i) tree.update(code(rng() % 4096, rng() % 4096, rng() % 64), kSensor.hit_log_odds());
  const std::size_t full = tree.memory_bytes();
  const NodeCounts counts = tree.count_nodes();
  // At least the groups in use, at most the groups in use plus one partly
  // filled block per depth and the block tables.
  const std::size_t in_use = counts.leaf / 8 * sizeof(OccupancyTree::LeafGroup) +
                             (counts.inner + counts.inner_leaf - 1) / 8 * sizeof(OccupancyTree::InnerGroup);
  EXPECT_GE(full, in_use);
  EXPECT_LE(full, in_use + 17 * 4096 * sizeof(OccupancyTree::InnerGroup) + 1024 * 1024);
  EXPECT_GT(full, empty);
  tree.clear();
  EXPECT_EQ(tree.memory_bytes(), empty);
}

TEST(OccupancyTree, RandomUpdateSequencesKeepEveryInvariant) {
  for (const int depth_levels : {1, 2, 3, 4, 6}) {
    for (const bool auto_prune : {true, false}) {
      OccupancyTree tree(depth_levels, kRange, kThresholds);
      tree.set_auto_prune(auto_prune);
      std::mt19937 rng(static_cast<std::uint32_t>(depth_levels * 10 + auto_prune));
      const std::uint32_t size = 1u << depth_levels;
      // A small region so that values repeat and merges happen.
      const std::uint32_t region = std::min<std::uint32_t>(size, 4);
      for (int step = 0; step < 3000; ++step) {
        const std::uint64_t c = code(rng() % region, rng() % region, rng() % region);
        switch (rng() % 5) {
          case 0: tree.update(c, kSensor.hit_log_odds()); break;
          case 1:
          case 2: tree.update(c, kSensor.miss_log_odds()); break;
          case 3: tree.set(c, kSensor.miss_log_odds()); break;
          default: tree.set(c, 0.0f); break;
        }
        if (step % 97 == 0) tree.set_thresholds(LogOddsThresholds::from(Thresholds{0.5 + (rng() % 4) * 0.1, 0.5 - (rng() % 4) * 0.1}));
        if (step % 251 == 0 && !auto_prune) tree.prune();
        ASSERT_EQ(tree.check_invariants(), "") << "depth levels " << depth_levels << " step " << step;
      }
    }
  }
}

TEST(OccupancyTree, ApplyingABatchUpdatesEachMarkedVoxelOnce) {
  // apply() against update() of every marked voxel (a hit wins over a
  // miss), over rounds of random batches on a small region, so that nodes
  // go childless at the clamping minimum and are then missed in part (their
  // voxels stay one value) and childless unknown or occupied nodes get
  // partial marks (a new leaf group), with pruning on and off.
  for (const int depth_levels : {3, 4}) {
    for (const bool auto_prune : {true, false}) {
      OccupancyTree tree(depth_levels, kRange, kThresholds);
      OccupancyTree expected(depth_levels, kRange, kThresholds);
      tree.set_auto_prune(auto_prune);
      expected.set_auto_prune(auto_prune);
      std::mt19937 rng(static_cast<std::uint32_t>(depth_levels * 10 + auto_prune));
      const std::uint64_t voxels = std::uint64_t{1} << (3 * depth_levels);
      for (int round = 0; round < 40; ++round) {
        UpdateBatch batch(depth_levels);
        std::vector<std::uint8_t> marks(voxels, 0);  // 1: miss, 2: hit
        // Mostly misses in the first 128 voxels (two bricks), a few hits.
        const int count = static_cast<int>(rng() % 200);
        for (int i = 0; i < count; ++i) {
          const std::uint64_t c = rng() % 4 == 0 ? rng() % voxels : rng() % 128;
          if (rng() % 10 == 0) {
            batch.add_hit(c);
            marks[c] = 2;
          } else {
            batch.add_miss(c);
            marks[c] = std::max<std::uint8_t>(marks[c], 1);
          }
        }
        if (rng() % 3 == 0) {  // a whole depth-1 node
          const std::uint64_t first = (rng() % voxels) & ~std::uint64_t{7};
          batch.add_miss_node(first, 1);
          for (std::uint64_t c = first; c < first + 8; ++c) marks[c] = std::max<std::uint8_t>(marks[c], 1);
        }
        tree.apply(batch, kSensor.hit_log_odds(), kSensor.miss_log_odds());
        for (std::uint64_t c = 0; c < voxels; ++c) {
          if (marks[c] != 0) expected.update(c, marks[c] == 2 ? kSensor.hit_log_odds() : kSensor.miss_log_odds());
        }
        ASSERT_EQ(tree.check_invariants(), "") << "round " << round;
        for (std::uint64_t c = 0; c < voxels; ++c) {
          ASSERT_EQ(tree.find(c, 0).log_odds, expected.find(c, 0).log_odds)
              << "depth levels " << depth_levels << " prune " << auto_prune << " round " << round << " voxel " << c;
        }
        if (auto_prune) {
          ASSERT_EQ(tree.count_nodes().inner, expected.count_nodes().inner) << "round " << round;
          ASSERT_EQ(tree.count_nodes().inner_leaf, expected.count_nodes().inner_leaf) << "round " << round;
        }
      }
    }
  }
}

}  // namespace
}  // namespace umbra
