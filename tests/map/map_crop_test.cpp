// crop_map against brute force: every finest voxel of the cropped map holds
// the source's value (and color and its weight) inside the box and is
// unknown outside it; the tree's invariants hold, automatic pruning is kept,
// and a box that cuts a pruned node splits it.
#include <gtest/gtest.h>

#include <random>

#include "support/map_internals.hpp"
#include "support/query_oracle.hpp"
#include "umbra/map/map_crop.hpp"

namespace umbra {
namespace {

void expect_cropped(const OccupancyMap& source, const OccupancyMap& cropped, const VoxelBox& keep) {
  ASSERT_EQ(test::check_invariants(cropped), "");
  EXPECT_EQ(cropped.config().resolution, source.config().resolution);
  EXPECT_EQ(cropped.auto_prune(), source.auto_prune());
  EXPECT_EQ(cropped.has_color(), source.has_color());
  const test::DenseValues before(source);
  const test::DenseValues after(cropped);
  std::size_t kept = 0;
  for (std::uint32_t z = 0; z < before.size(); ++z) {
    for (std::uint32_t y = 0; y < before.size(); ++y) {
      for (std::uint32_t x = 0; x < before.size(); ++x) {
        const Key key{x, y, z};
        if (keep.contains(key)) {
          ASSERT_EQ(after.at(key), before.at(key)) << x << " " << y << " " << z;
          if (source.has_color()) {
            ASSERT_EQ(cropped.color(key), source.color(key)) << x << " " << y << " " << z;
          }
          kept += before.at(key) != 0.0f ? 1 : 0;
        } else {
          ASSERT_EQ(after.at(key), 0.0f) << x << " " << y << " " << z;
        }
      }
    }
  }
  EXPECT_GT(kept, 0u) << "the box kept nothing: a weak test";
}

TEST(MapCrop, KeepsTheBoxAndNothingElse) {
  std::mt19937 random(11);
  for (const bool prune : {true, false}) {
    for (unsigned seed = 1; seed <= 3; ++seed) {
      test::RandomMapSpec spec;
      spec.depth_levels = 5;
      spec.seed = seed;
      spec.auto_prune = prune;
      const OccupancyMap source = test::random_map(spec);
      std::uniform_int_distribution<std::uint32_t> key(0, 31);
      for (int i = 0; i < 4; ++i) {
        Key lo{key(random), key(random), key(random)};
        Key hi{key(random), key(random), key(random)};
        for (int axis = 0; axis < 3; ++axis) {
          if (lo[axis] > hi[axis]) std::swap(lo[axis], hi[axis]);
        }
        const VoxelBox keep{lo, hi};
        expect_cropped(source, crop_map(source, keep), keep);
      }
    }
  }
}

TEST(MapCrop, SplitsAPrunedNodeAndKeepsColorWeights) {
  MapConfig config;
  config.resolution = 0.1;
  config.depth_levels = 5;
  config.color = true;
  OccupancyMap source(config);
  // A pruned occupied 8 x 8 x 8 block: 512 voxels set alike merge into one node.
  for (std::uint32_t z = 8; z < 16; ++z) {
    for (std::uint32_t y = 8; y < 16; ++y) {
      for (std::uint32_t x = 8; x < 16; ++x) source.set_log_odds(Key{x, y, z}, 2.0f);
    }
  }
  ASSERT_LT(source.node_counts().total(), 100u) << "the block did not prune";
  // Two color samples on one voxel: a weight of 2.
  const Vec3d voxel = source.grid().center(Key{9, 9, 9});
  source.add_color(voxel, Rgb{200, 0, 0});
  source.add_color(voxel, Rgb{0, 0, 100});
  const VoxelBox keep{Key{9, 9, 9}, Key{20, 20, 12}};
  OccupancyMap cropped = crop_map(source, keep);
  expect_cropped(source, cropped, keep);
  // The weight came along: one more sample averages over three, not two.
  source.add_color(voxel, Rgb{30, 30, 30});
  cropped.add_color(voxel, Rgb{30, 30, 30});
  EXPECT_EQ(cropped.color(voxel), source.color(voxel));
}

TEST(MapCrop, ABoxOutsideTheMapIsRefused) {
  const OccupancyMap map(0.1, 5);
  EXPECT_THROW((void)crop_map(map, VoxelBox{Key{0, 0, 0}, Key{32, 1, 1}}), std::out_of_range);
  EXPECT_THROW((void)crop_map(map, VoxelBox{Key{3, 0, 0}, Key{2, 1, 1}}), std::out_of_range);
}

}  // namespace
}  // namespace umbra
