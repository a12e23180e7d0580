// walk_ray against a literal, key-based copy of OctoMap's computeRayKeys
// (tests/support/dense_grid), on random rays, axis-aligned rays, rays along
// voxel borders and rays that touch the map's edge.
#include <cstdlib>
#include <random>

#include <gtest/gtest.h>

#include "support/dense_grid.hpp"
#include "integrate/ray_walker.hpp"

namespace umbra {
namespace {

std::vector<Key> walk(const Grid& grid, Vec3f from, Vec3f to, bool& inside) {
  std::vector<Key> keys;
  inside = walk_ray(grid, from, to, [&](std::uint64_t code) { keys.push_back(morton::decode(code)); });
  return keys;
}

void expect_same_walk(const Grid& grid, const test::DenseGrid& reference, Vec3f from, Vec3f to) {
  std::vector<Key> expected;
  const bool expected_inside = reference.ray_keys(from, to, expected);
  bool inside = false;
  const std::vector<Key> actual = walk(grid, from, to, inside);
  ASSERT_EQ(inside, expected_inside);
  ASSERT_EQ(actual.size(), expected.size())
      << "ray (" << from.x << "," << from.y << "," << from.z << ") -> (" << to.x << "," << to.y << "," << to.z << ")";
  for (std::size_t i = 0; i < actual.size(); ++i) ASSERT_EQ(actual[i], expected[i]) << "step " << i;
}

TEST(RayWalker, MatchesOctoMapsWalkOnRandomRays) {
  for (const int depth_levels : {3, 6, 7}) {
    for (const double resolution : {0.05, 0.1, 0.37}) {
      const Grid grid(resolution, depth_levels);
      const test::DenseGrid reference(resolution, depth_levels, -2.0f, 3.5f);
      const auto h = static_cast<float>(grid.half_extent());
      std::mt19937 rng(static_cast<std::uint32_t>(depth_levels * 1000 + resolution * 100));
      std::uniform_real_distribution<float> coordinate(-h, h);
      for (int i = 0; i < 3000; ++i) {
        expect_same_walk(grid, reference, {coordinate(rng), coordinate(rng), coordinate(rng)},
                         {coordinate(rng), coordinate(rng), coordinate(rng)});
      }
    }
  }
}

TEST(RayWalker, MatchesOnAxisAlignedRaysBordersAndEdges) {
  const double resolution = 0.1;
  const Grid grid(resolution, 6);  // [-3.2, 3.2)
  const test::DenseGrid reference(resolution, 6, -2.0f, 3.5f);
  const float edge = 3.2f - 1e-4f;
  const std::vector<std::pair<Vec3f, Vec3f>> rays = {
      {{0, 0, 0}, {3, 0, 0}},           {{0, 0, 0}, {0, -3, 0}},        {{0, 0, 0}, {0, 0, 2.95f}},
      {{0.1f, 0.2f, 0.3f}, {1.1f, 1.2f, 1.3f}},  // exactly on voxel borders
      {{-edge, -edge, -edge}, {edge, edge, edge}},  // corner to corner
      {{-edge, 0, 0}, {edge, 0.05f, 0}},            // along the edge layer
      {{edge, edge, 0}, {edge, -edge, 0}},
      {{0, 0, 0}, {0, 0, 0}},                       // zero length
      {{0.01f, 0.01f, 0.01f}, {0.02f, 0.02f, 0.02f}},  // same voxel
      {{0, 0, 0}, {3.3f, 0, 0}},                       // end outside
      {{0, 0, 0}, {1, 2, -4}},                         // end outside
  };
  for (const auto& [from, to] : rays) expect_same_walk(grid, reference, from, to);
}

TEST(RayWalker, StepsAreFaceNeighboursFromTheOriginVoxel) {
  const Grid grid(0.05, 16);
  std::mt19937 rng(99);
  std::uniform_real_distribution<float> coordinate(-20.0f, 20.0f);
  for (int i = 0; i < 2000; ++i) {
    const Vec3f from{coordinate(rng), coordinate(rng), coordinate(rng)};
    const Vec3f to{coordinate(rng), coordinate(rng), coordinate(rng)};
    bool inside = false;
    const std::vector<Key> keys = walk(grid, from, to, inside);
    ASSERT_TRUE(inside);
    ASSERT_FALSE(keys.empty());
    ASSERT_EQ(keys.front(), grid.key(Vec3d(from)));
    const Key end = grid.key(Vec3d(to));
    for (std::size_t s = 1; s < keys.size(); ++s) {
      int moved = 0;
      for (int axis = 0; axis < 3; ++axis) moved += std::abs(int(keys[s][axis]) - int(keys[s - 1][axis]));
      ASSERT_EQ(moved, 1) << "step " << s;
      ASSERT_NE(keys[s], end) << "the end voxel is never visited";
    }
  }
}

TEST(RayWalker, OutsideEndsVisitNothing) {
  const Grid grid(0.1, 4);  // [-0.8, 0.8)
  bool inside = true;
  EXPECT_TRUE(walk(grid, {0, 0, 0}, {5, 0, 0}, inside).empty());
  EXPECT_FALSE(inside);
  EXPECT_TRUE(walk(grid, {-5, 0, 0}, {0, 0, 0}, inside).empty());
  EXPECT_FALSE(inside);
}

}  // namespace
}  // namespace umbra
