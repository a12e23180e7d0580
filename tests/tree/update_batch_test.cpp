// UpdateBatch against a std::map model: random hits, misses and whole-node
// misses in any order; hit wins; full groups collapse; merge is a union;
// nodes marked with keep_fine are refused whatever was missed before.
#include <map>
#include <random>
#include <set>
#include <utility>

#include <gtest/gtest.h>

#include "tree/update_batch.hpp"

namespace umbra {
namespace {

enum class Mark { miss, hit };
using Model = std::map<std::uint64_t, Mark>;

void add_to_model(Model& model, std::uint64_t code, Mark mark) {
  auto [it, inserted] = model.emplace(code, mark);
  if (!inserted && mark == Mark::hit) it->second = Mark::hit;
}

/// Every voxel the batch marks, expanded from full nodes.
Model contents(const UpdateBatch& batch) {
  Model out;
  auto expand_full = [&](std::uint64_t first, int depth) {
    const std::uint64_t count = std::uint64_t{1} << (3 * depth);
    for (std::uint64_t i = 0; i < count; ++i) out[first + i] = Mark::miss;
  };
  auto visit = [&](auto& self, int depth, std::uint32_t group, std::uint64_t first) -> void {
    if (depth == 1) {
      const UpdateBatch::Brick& brick = batch.brick(group);
      for (unsigned node = 0; node < 8; ++node) {
        for (unsigned voxel = 0; voxel < 8; ++voxel) {
          const std::uint64_t c = first | (std::uint64_t{node} << 3) | voxel;
          if (brick.hit[node] >> voxel & 1u) {
            out[c] = Mark::hit;
          } else if (brick.miss[node] >> voxel & 1u) {
            out[c] = Mark::miss;
          }
        }
      }
      return;
    }
    const UpdateBatch::Inner& node = batch.inner(depth, group);
    for (unsigned slot = 0; slot < 8; ++slot) {
      const std::uint64_t child_first = first | (std::uint64_t{slot} << (3 * depth));

      if (node.full >> slot & 1u) {
        EXPECT_EQ(node.child[slot], kNoGroup) << "a full node has no children";
        expand_full(child_first, depth);
      } else if (node.child[slot] != kNoGroup) {
        self(self, depth - 1, node.child[slot], child_first);
      }
    }
  };
  visit(visit, batch.depth_levels(), 0, 0);
  return out;
}

/// Every inner node's `hits` bit says whether its region holds a hit of `model`.
void expect_hit_bits(const UpdateBatch& batch, const Model& model) {
  auto visit = [&](auto& self, int depth, std::uint32_t group, std::uint64_t first) -> void {
    if (depth == 1) return;
    const UpdateBatch::Inner& node = batch.inner(depth, group);
    for (unsigned slot = 0; slot < 8; ++slot) {
      const std::uint64_t child_first = first | (std::uint64_t{slot} << (3 * depth));
      const std::uint64_t count = std::uint64_t{1} << (3 * depth);
      bool holds_hit = false;
      for (auto it = model.lower_bound(child_first); it != model.end() && it->first < child_first + count; ++it) {
        holds_hit |= it->second == Mark::hit;
      }
      ASSERT_EQ((node.hits >> slot & 1u) != 0, holds_hit) << "depth " << depth << " slot " << slot;
      if (node.child[slot] != kNoGroup) self(self, depth - 1, node.child[slot], child_first);
    }
  };
  visit(visit, batch.depth_levels(), 0, 0);
}

void random_fill(UpdateBatch& batch, Model& model, std::mt19937& rng, int depth_levels, int count) {
  const std::uint32_t size = 1u << depth_levels;
  const std::uint32_t region = std::min<std::uint32_t>(size, 8);
  for (int i = 0; i < count; ++i) {
    const std::uint64_t c = morton::encode({static_cast<std::uint32_t>(rng() % region),
                                            static_cast<std::uint32_t>(rng() % region),
                                            static_cast<std::uint32_t>(rng() % region)});
    const unsigned what = rng() % 12;
    if (what >= 10) {
      // Whole-node miss unless the node holds a hit.
      const int depth = static_cast<int>(rng() % static_cast<unsigned>(std::min(depth_levels, 3) + 1));
      const std::uint64_t first = morton::node_begin(c, depth);
      const std::uint64_t voxels = std::uint64_t{1} << (3 * depth);
      bool holds_hit = false;
      for (auto it = model.lower_bound(first); it != model.end() && it->first < first + voxels; ++it) {
        holds_hit |= it->second == Mark::hit;
      }
      ASSERT_EQ(batch.add_miss_node_unless_hit(c, depth), !holds_hit);
      if (!holds_hit) {
        for (std::uint64_t v = 0; v < voxels; ++v) add_to_model(model, first + v, Mark::miss);
      }
    } else if (what == 0) {
      batch.add_hit(c);
      add_to_model(model, c, Mark::hit);
    } else if (what == 1) {
      const int depth = static_cast<int>(rng() % static_cast<unsigned>(std::min(depth_levels, 3) + 1));
      batch.add_miss_node(c, depth);
      const std::uint64_t first = morton::node_begin(c, depth);
      for (std::uint64_t v = 0; v < (std::uint64_t{1} << (3 * depth)); ++v) add_to_model(model, first + v, Mark::miss);
    } else {
      batch.add_miss(c);
      add_to_model(model, c, Mark::miss);
    }
  }
}

TEST(UpdateBatch, HoldsExactlyTheMarkedVoxelsWithHitsWinning) {
  for (const int depth_levels : {1, 2, 3, 4, 8, 16}) {
    for (std::uint32_t seed = 1; seed <= 20; ++seed) {
      std::mt19937 rng(seed);
      UpdateBatch batch(depth_levels);
      Model model;
      random_fill(batch, model, rng, depth_levels, 600);
      ASSERT_EQ(contents(batch), model) << "depth levels " << depth_levels << " seed " << seed;
      expect_hit_bits(batch, model);
      ASSERT_FALSE(batch.empty());
    }
  }
}

TEST(UpdateBatch, FullRegionsCollapseAndRelease) {
  UpdateBatch batch(16);
  const std::size_t empty = batch.memory_bytes();
  EXPECT_TRUE(batch.empty());
  // Miss every voxel of a 16^3 block, voxel by voxel, in raster order.
  for (std::uint32_t z = 0; z < 16; ++z)
    for (std::uint32_t y = 0; y < 16; ++y)
      for (std::uint32_t x = 0; x < 16; ++x) batch.add_miss(morton::encode({x, y, z}));
  // The block is one full node at depth 4, slot 0 of its group.
  const Model model = contents(batch);
  EXPECT_EQ(model.size(), 4096u);
  std::uint32_t group = 0;
  for (int depth = 16; depth > 4; --depth) group = batch.inner(depth, group).child[0];
  EXPECT_EQ(batch.inner(4, group).full, 1u);
  EXPECT_EQ(batch.inner(4, group).child[0], kNoGroup);
  EXPECT_LT(batch.memory_bytes(), empty + 64 * 1024);
  // A hit inside splits the full node again, keeping every other miss.
  batch.add_hit(morton::encode({5, 6, 7}));
  const Model split = contents(batch);
  EXPECT_EQ(split.size(), 4096u);
  EXPECT_EQ(split.at(morton::encode({5, 6, 7})), Mark::hit);
  EXPECT_EQ(split.at(morton::encode({5, 6, 8})), Mark::miss);
  batch.reset(16);
  EXPECT_TRUE(batch.empty());
}

TEST(UpdateBatch, MergeIsTheUnion) {
  for (const int depth_levels : {1, 3, 16}) {
    for (std::uint32_t seed = 1; seed <= 10; ++seed) {
      std::mt19937 rng(seed);
      UpdateBatch a(depth_levels);
      UpdateBatch b(depth_levels);
      Model model;
      Model model_b;
      random_fill(a, model, rng, depth_levels, 400);
      random_fill(b, model_b, rng, depth_levels, 400);
      for (const auto& [code, mark] : model_b) add_to_model(model, code, mark);
      a.merge(b);
      ASSERT_EQ(contents(a), model) << "depth levels " << depth_levels << " seed " << seed;
      expect_hit_bits(a, model);
    }
  }
}

TEST(UpdateBatch, KeptNodesAreRefusedWhateverWasMissedBefore) {
  // The fast integrator's workers each add only their own rays' misses, and
  // must still answer alike whether a node may be cleared whole (issue 22:
  // a kept node whose children had all been cleared was cleared whole too,
  // once its group collapsed or right after its last child was cleared).
  // Marks as the integrator sets them: a node and its ancestors up to
  // `up_to`, whole-node misses asked at depths up to `up_to` only.
  for (const int depth_levels : {3, 4, 16}) {
    for (std::uint32_t seed = 1; seed <= 30; ++seed) {
      SCOPED_TRACE("depth levels " + std::to_string(depth_levels) + " seed " + std::to_string(seed));
      std::mt19937 rng(seed);
      const auto random_voxel = [&] {  // in the first 8^3 voxels
        return morton::encode({static_cast<std::uint32_t>(rng() % 8), static_cast<std::uint32_t>(rng() % 8),
                               static_cast<std::uint32_t>(rng() % 8)});
      };
      const int up_to = 3;
      UpdateBatch batch(depth_levels);
      Model model;
      std::set<std::pair<std::uint64_t, int>> kept;  // (first voxel, depth)
      for (int i = 0; i < 2; ++i) {
        const std::uint64_t c = random_voxel();
        batch.add_hit(c);
        add_to_model(model, c, Mark::hit);
      }
      for (int i = 0; i < 3; ++i) {
        const std::uint64_t c = random_voxel();
        const int depth = 1 + static_cast<int>(rng() % up_to);
        batch.keep_fine(c, depth, up_to);
        for (int d = depth; d <= up_to; ++d) kept.insert({morton::node_begin(c, d), d});
      }
      for (int i = 0; i < 300; ++i) {
        const std::uint64_t c = random_voxel();
        if (rng() % 3 == 0) {
          // Every voxel of a node of 2^3 or 4^3 voxels, one by one, as rays
          // crossing it add them: fills kept nodes, and groups around them.
          const int depth = 1 + static_cast<int>(rng() % 2);
          const std::uint64_t first = morton::node_begin(c, depth);
          for (std::uint64_t v = first; v < first + (std::uint64_t{1} << (3 * depth)); ++v) {
            batch.add_miss(v);
            add_to_model(model, v, Mark::miss);
          }
          continue;
        }
        const int depth = static_cast<int>(rng() % (up_to + 1));
        const std::uint64_t first = morton::node_begin(c, depth);
        const std::uint64_t voxels = std::uint64_t{1} << (3 * depth);
        bool refused = kept.contains({first, depth});
        for (auto it = model.lower_bound(first); it != model.end() && it->first < first + voxels; ++it) {
          refused |= it->second == Mark::hit;
        }
        ASSERT_EQ(batch.add_miss_node_unless_hit(c, depth), !refused) << "depth " << depth << " node " << first;
        if (!refused) {
          for (std::uint64_t v = 0; v < voxels; ++v) add_to_model(model, first + v, Mark::miss);
        }
      }
      ASSERT_EQ(contents(batch), model);
      expect_hit_bits(batch, model);
    }
  }
}

}  // namespace
}  // namespace umbra
