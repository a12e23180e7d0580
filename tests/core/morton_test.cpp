// Morton codes: round trips at every depth, ordering, axis stepping.
#include <random>

#include <gtest/gtest.h>

#include "umbra/core/morton.hpp"

namespace umbra {
namespace {

TEST(Morton, RoundTripsEveryKeyBitAtEveryDepth) {
  std::mt19937 rng(7);
  for (int depth_levels = 1; depth_levels <= kMaxDepthLevels; ++depth_levels) {
    std::uniform_int_distribution<std::uint32_t> any_key(0, (1u << depth_levels) - 1);
    for (int i = 0; i < 2000; ++i) {
      const Key key{any_key(rng), any_key(rng), any_key(rng)};
      const std::uint64_t code = morton::encode(key);
      ASSERT_LT(code, std::uint64_t{1} << (3 * depth_levels)) << "depth levels " << depth_levels;
      ASSERT_EQ(morton::decode(code), key) << "depth levels " << depth_levels;
    }
  }
}

TEST(Morton, InterleavesXYZFromTheLowestBit) {
  EXPECT_EQ(morton::encode({1, 0, 0}), 1u);
  EXPECT_EQ(morton::encode({0, 1, 0}), 2u);
  EXPECT_EQ(morton::encode({0, 0, 1}), 4u);
  EXPECT_EQ(morton::encode({2, 0, 0}), 8u);
  const std::uint32_t max = (1u << 21) - 1;
  EXPECT_EQ(morton::encode({max, max, max}), (std::uint64_t{1} << 63) - 1);
}

TEST(Morton, SlotAndNodeBeginFollowTheTreePath) {
  const Key key{0b101, 0b011, 0b110};
  const std::uint64_t code = morton::encode(key);
  // depth 0: x bit0=1, y bit0=1, z bit0=0 -> 1 + 2
  EXPECT_EQ(morton::slot(code, 0), 3u);
  // depth 1: x=0, y=1, z=1 -> 2 + 4
  EXPECT_EQ(morton::slot(code, 1), 6u);
  // depth 2: x=1, y=0, z=1 -> 1 + 4
  EXPECT_EQ(morton::slot(code, 2), 5u);
  EXPECT_EQ(morton::decode(morton::node_begin(code, 1)), (Key{0b100, 0b010, 0b110}));
  EXPECT_EQ(morton::node_begin(code, 0), code);
}

TEST(Morton, SortingCodesVisitsChildrenBeforeTheNextSibling) {
  // All 64 voxels of a 4x4x4 node sorted by code: each consecutive run of 8
  // must be one depth-1 node.
  std::vector<std::uint64_t> codes;
  for (std::uint32_t x = 0; x < 4; ++x)
    for (std::uint32_t y = 0; y < 4; ++y)
      for (std::uint32_t z = 0; z < 4; ++z) codes.push_back(morton::encode({x, y, z}));
  std::sort(codes.begin(), codes.end());
  for (std::size_t i = 0; i < codes.size(); ++i) {
    EXPECT_EQ(codes[i] >> 3, i / 8);
  }
}

TEST(Morton, IncrementAndDecrementStepOneAxis) {
  std::mt19937 rng(11);
  std::uniform_int_distribution<std::uint32_t> any_key(1, (1u << 21) - 2);
  for (int i = 0; i < 5000; ++i) {
    const Key key{any_key(rng), any_key(rng), any_key(rng)};
    const std::uint64_t code = morton::encode(key);
    for (int axis = 0; axis < 3; ++axis) {
      Key up = key;
      up[axis] += 1;
      Key down = key;
      down[axis] -= 1;
      ASSERT_EQ(morton::increment(code, axis), morton::encode(up));
      ASSERT_EQ(morton::decrement(code, axis), morton::encode(down));
    }
  }
}

TEST(Morton, HighestDifferingDepth) {
  const std::uint64_t a = morton::encode({8, 0, 0});
  EXPECT_EQ(morton::highest_differing_depth(a, a), -1);
  EXPECT_EQ(morton::highest_differing_depth(a, morton::encode({9, 0, 0})), 0);
  EXPECT_EQ(morton::highest_differing_depth(a, morton::encode({8, 2, 0})), 1);
  EXPECT_EQ(morton::highest_differing_depth(a, morton::encode({0, 0, 0})), 3);
  EXPECT_EQ(morton::highest_differing_depth(0, morton::encode({0, 0, 1u << 20})), 20);
}

}  // namespace
}  // namespace umbra
