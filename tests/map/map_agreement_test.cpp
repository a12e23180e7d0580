// compare_maps and voxel_box against brute force: every finest voxel of two
// small random maps read one by one (map.state(key)), counted into the same
// 3 x 3 table, over the whole map and inside boxes; and the errors.
#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <optional>
#include <random>

#include "support/query_oracle.hpp"
#include "umbra/map/map_agreement.hpp"
#include "umbra/map/voxel_box.hpp"

namespace umbra {
namespace {

/// The table counted voxel by voxel, only the voxels of `region` when given.
MapAgreement brute_force(const OccupancyMap& reference, const OccupancyMap& other,
                         const std::optional<VoxelBox>& region) {
  MapAgreement result;
  const std::uint32_t size = reference.grid().keys_per_axis();
  for (std::uint32_t z = 0; z < size; ++z) {
    for (std::uint32_t y = 0; y < size; ++y) {
      for (std::uint32_t x = 0; x < size; ++x) {
        const Key key{x, y, z};
        if (region && !region->contains(key)) continue;
        ++result.voxels[static_cast<int>(reference.node(key).state)][static_cast<int>(other.node(key).state)];
      }
    }
  }
  return result;
}

test::RandomMapSpec spec(unsigned seed, bool prune) {
  test::RandomMapSpec s;
  s.depth_levels = 5;
  s.seed = seed;
  s.auto_prune = prune;
  return s;
}

TEST(MapAgreement, MatchesVoxelByVoxelCounting) {
  for (unsigned seed = 1; seed <= 4; ++seed) {
    const OccupancyMap a = test::random_map(spec(seed, true));
    const OccupancyMap b = test::random_map(spec(seed + 10, seed % 2 == 0));
    const MapAgreement fast = compare_maps(a, b);
    const MapAgreement slow = brute_force(a, b, std::nullopt);
    EXPECT_EQ(fast.voxels, slow.voxels) << "seed " << seed;
    // Every voxel of the map, once.
    std::uint64_t total = 0;
    for (const auto& row : fast.voxels) total += row[0] + row[1] + row[2];
    EXPECT_EQ(total, std::uint64_t{1} << (3 * 5));
    // Some of each kind of disagreement occurs, so the test means something.
    EXPECT_GT(fast.count(OccupancyState::occupied, OccupancyState::free), 0u);
    EXPECT_GT(fast.count(OccupancyState::free, OccupancyState::unknown), 0u);
  }
}

TEST(MapAgreement, InsideBoxesMatchesVoxelByVoxelCounting) {
  const OccupancyMap a = test::random_map(spec(3, true));
  const OccupancyMap b = test::random_map(spec(7, true));
  std::mt19937 random(5);
  std::uniform_int_distribution<std::uint32_t> key(0, 31);
  for (int i = 0; i < 20; ++i) {
    Key lo{key(random), key(random), key(random)};
    Key hi{key(random), key(random), key(random)};
    for (int axis = 0; axis < 3; ++axis) {
      if (lo[axis] > hi[axis]) std::swap(lo[axis], hi[axis]);
    }
    const VoxelBox region{lo, hi};
    EXPECT_EQ(compare_maps(a, b, region).voxels, brute_force(a, b, region).voxels) << "box " << i;
  }
}

TEST(MapAgreement, RatiosAndSelfComparison) {
  const OccupancyMap a = test::random_map(spec(2, true));
  const MapAgreement self = compare_maps(a, a);
  EXPECT_EQ(self.recall(), 1.0);
  EXPECT_EQ(self.precision(), 1.0);
  EXPECT_EQ(self.free_agreement(), 1.0);
  EXPECT_EQ(self.free_left_unknown(), 0.0);
  MapAgreement t;
  t.voxels[2][2] = 3;  // occupied in both
  t.voxels[2][1] = 1;  // occupied in the reference, free in the other
  t.voxels[0][2] = 2;  // unknown in the reference, occupied in the other
  t.voxels[1][1] = 6;
  t.voxels[1][0] = 2;
  EXPECT_DOUBLE_EQ(t.recall(), 3.0 / 4.0);
  EXPECT_DOUBLE_EQ(t.precision(), 3.0 / 5.0);
  EXPECT_DOUBLE_EQ(t.free_agreement(), 6.0 / 8.0);
  EXPECT_DOUBLE_EQ(t.free_left_unknown(), 2.0 / 8.0);
}

TEST(MapAgreement, DifferentGridsAreRefusedByName) {
  const OccupancyMap a(0.1);
  const OccupancyMap b(0.05);
  try {
    (void)compare_maps(a, b);
    FAIL() << "maps of different voxels were compared";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("0.05"), std::string::npos) << e.what();
  }
  EXPECT_THROW((void)compare_maps(OccupancyMap(0.1, 16), OccupancyMap(0.1, 12)), std::invalid_argument);
}

TEST(VoxelBox, TheVoxelsABoxMeets) {
  const Grid grid(0.1, 5);  // keys 0..31, the map spans [-1.6, 1.6)
  const VoxelBox box = voxel_box(grid, Aabb{{-0.05, 0.0, 0.25}, {0.05, 0.2, 0.25}});
  EXPECT_EQ(box.lo, (Key{15, 16, 18}));
  EXPECT_EQ(box.hi, (Key{16, 18, 18}));  // 0.2 lies on a face: the voxel above it
  // Cut to the map.
  const VoxelBox big = voxel_box(grid, Aabb{{-100, -100, -100}, {100, 100, 0.0}});
  EXPECT_EQ(big.lo, (Key{0, 0, 0}));
  EXPECT_EQ(big.hi, (Key{31, 31, 16}));
  EXPECT_EQ(big.voxels_inside(Key{0, 0, 0}, 5), 32u * 32u * 17u);
  EXPECT_EQ(big.voxels_inside(Key{0, 0, 24}, 3), 0u);
  // Wholly outside, or not a box.
  EXPECT_THROW((void)voxel_box(grid, Aabb{{2, 0, 0}, {3, 1, 1}}), std::out_of_range);
  EXPECT_THROW((void)voxel_box(grid, Aabb{{0, 0, 0}, {-1, 1, 1}}), std::invalid_argument);
}

}  // namespace
}  // namespace umbra
