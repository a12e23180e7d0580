// OccupancyTree::apply of several batches at once (tree/apply_batches.cpp)
// against apply() of the batches merged into one: the same tree, node for
// node and bit for bit, with and without automatic pruning, serially and on
// 2, 3 and 8 threads. The batches are built so that whole nodes are missed
// between several of them (eight children, each full in another batch; a
// brick's voxels spread over the batches), which the merged batch collapses
// into one full node, and so that a node full in one batch holds another
// batch's hits.
#include <memory>
#include <random>
#include <tuple>
#include <vector>

#include <gtest/gtest.h>

#include "tree/occupancy_tree.hpp"

namespace umbra {
namespace {

const SensorModel kSensor;
const LogOddsRange kRange = LogOddsRange::from(kSensor);
const LogOddsThresholds kThresholds = LogOddsThresholds::from(Thresholds{});

using Leaf = std::tuple<std::uint64_t, int, float, bool>;

std::vector<Leaf> leaves_of(const OccupancyTree& tree) {
  std::vector<Leaf> leaves;
  tree.for_each_leaf([&](NodeRef node, std::uint64_t code) {
    leaves.emplace_back(code, node.depth, tree.log_odds(node), tree.all_children_same(node));
  });
  return leaves;
}

/// A random code in the first `region` voxels along each axis.
std::uint64_t random_code(std::mt19937& rng, std::uint32_t region) {
  return morton::encode({static_cast<std::uint32_t>(rng() % region), static_cast<std::uint32_t>(rng() % region),
                         static_cast<std::uint32_t>(rng() % region)});
}

/// `count` batches whose marks meet: nodes of several depths split among
/// them (each child missed whole, or voxel by voxel, in a random batch),
/// random misses and whole-node misses, and a few hits.
std::vector<UpdateBatch> random_batches(std::mt19937& rng, int depth_levels, std::size_t count) {
  std::vector<UpdateBatch> batches;
  for (std::size_t i = 0; i < count; ++i) batches.emplace_back(depth_levels);
  const auto any = [&]() -> UpdateBatch& { return batches[rng() % count]; };
  const std::uint32_t region = std::min<std::uint32_t>(1u << depth_levels, 32);
  // A node of depth >= 1 missed whole between the batches: each child
  // missed whole in some batch, or (sometimes) split the same way again.
  const auto split = [&](const auto& self, std::uint64_t first, int depth) -> void {
    const std::uint64_t child_voxels = std::uint64_t{1} << (3 * (depth - 1));
    for (std::uint64_t slot = 0; slot < 8; ++slot) {
      if (depth >= 2 && rng() % 4 == 0) {
        self(self, first + slot * child_voxels, depth - 1);
      } else {
        any().add_miss_node(first + slot * child_voxels, depth - 1);
      }
    }
  };
  for (int i = 0; i < 6; ++i) {
    const int depth = 1 + static_cast<int>(rng() % static_cast<unsigned>(std::min(depth_levels, 4)));
    split(split, morton::node_begin(random_code(rng, region), depth), depth);
  }
  for (int brick = 0; brick < 4; ++brick) {
    // A brick's voxels missed one by one, spread over the batches.
    const std::uint64_t first = morton::node_begin(random_code(rng, region), 2);
    for (std::uint64_t v = 0; v < 64; ++v) any().add_miss(first + v);
  }
  for (int i = 0; i < 200; ++i) {
    const std::uint64_t c = random_code(rng, region);
    const unsigned what = rng() % 10;
    if (what == 0) {
      any().add_hit(c);
    } else if (what <= 2) {
      any().add_miss_node(c, static_cast<int>(rng() % static_cast<unsigned>(std::min(depth_levels, 3) + 1)));
    } else {
      any().add_miss(c);
    }
  }
  return batches;
}

/// A tree with some history: obstacles, free space and unknown, some pruned.
OccupancyTree random_tree(std::mt19937& rng, int depth_levels, bool auto_prune) {
  OccupancyTree tree(depth_levels, kRange, kThresholds);
  tree.set_auto_prune(auto_prune);
  const std::uint32_t region = std::min<std::uint32_t>(1u << depth_levels, 32);
  for (int i = 0; i < 40; ++i) {  // few: most nodes stay childless, where a whole-node miss differs
    tree.update(random_code(rng, region), rng() % 3 == 0 ? kSensor.hit_log_odds() : kSensor.miss_log_odds());
  }
  return tree;
}

TEST(ApplyBatches, SameTreeAsTheMergedBatch) {
  std::vector<std::unique_ptr<ThreadPool>> pools;
  for (const unsigned threads : {2u, 3u, 8u}) pools.push_back(std::make_unique<ThreadPool>(threads));
  int merged_nodes_differ = 0;  // trials where a node is missed whole only between batches
  for (const int depth_levels : {2, 3, 5, 8}) {
    for (const bool auto_prune : {true, false}) {
      for (std::uint32_t seed = 1; seed <= 8; ++seed) {
        SCOPED_TRACE(testing::Message() << "depth levels " << depth_levels << " auto prune " << auto_prune
                                        << " seed " << seed);
        std::mt19937 rng(seed);
        const std::size_t count = 2 + seed % 4;
        const std::vector<UpdateBatch> batches = random_batches(rng, depth_levels, count);
        std::vector<const UpdateBatch*> pointers;
        for (const UpdateBatch& batch : batches) pointers.push_back(&batch);
        UpdateBatch merged = batches[0];
        for (std::size_t i = 1; i < count; ++i) merged.merge(batches[i]);
        const std::uint32_t tree_seed = seed * 7 + static_cast<std::uint32_t>(depth_levels);
        std::mt19937 tree_rng(tree_seed);
        OccupancyTree expected = random_tree(tree_rng, depth_levels, auto_prune);
        expected.apply(merged, kSensor.hit_log_odds(), kSensor.miss_log_odds());
        ASSERT_EQ(expected.check_invariants(), "");
        const std::vector<Leaf> want = leaves_of(expected);
        std::vector<ThreadPool*> runs{nullptr};
        for (const auto& pool : pools) runs.push_back(pool.get());
        for (ThreadPool* pool : runs) {
          SCOPED_TRACE(testing::Message() << "threads " << (pool == nullptr ? 1u : pool->size()));
          tree_rng.seed(tree_seed);
          OccupancyTree tree = random_tree(tree_rng, depth_levels, auto_prune);
          tree.apply(pointers, kSensor.hit_log_odds(), kSensor.miss_log_odds(), pool);
          ASSERT_EQ(tree.check_invariants(), "");
          ASSERT_EQ(leaves_of(tree), want);
        }
        // Applying the batches one after the other is not the same scan (a
        // voxel in two batches gets two updates): the test's batches do meet.
        tree_rng.seed(tree_seed);
        OccupancyTree one_by_one = random_tree(tree_rng, depth_levels, auto_prune);
        for (const UpdateBatch& batch : batches) one_by_one.apply(batch, kSensor.hit_log_odds(), kSensor.miss_log_odds());
        if (leaves_of(one_by_one) != want) ++merged_nodes_differ;
      }
    }
  }
  EXPECT_GT(merged_nodes_differ, 0);
}

TEST(ApplyBatches, RefusesABatchOfAnotherDepth) {
  OccupancyTree tree(4, kRange, kThresholds);
  UpdateBatch a(4);
  UpdateBatch b(5);
  a.add_miss(1);
  b.add_miss(1);
  const std::vector<const UpdateBatch*> batches{&a, &b};
  EXPECT_THROW(tree.apply(batches, kSensor.hit_log_odds(), kSensor.miss_log_odds()), std::invalid_argument);
}

}  // namespace
}  // namespace umbra
