// walk_ray against a literal, key-based copy of OctoMap's computeRayKeys
// (tests/support/dense_grid), on random rays, axis-aligned rays, rays along
// voxel borders and rays that touch the map's edge; walk_ray_skipping
// against walk_ray when it skips nothing and against a brute-force
// segment/cube test when it skips nodes.
#include <bit>
#include <cstdlib>
#include <functional>
#include <limits>
#include <random>
#include <set>

#include <gtest/gtest.h>

#include "support/dense_grid.hpp"
#include "ray/voxel_walk.hpp"
#include "umbra/core/aabb.hpp"

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

using Runs = std::vector<std::pair<std::uint64_t, std::uint64_t>>;  // brick, voxels

Runs walk_skipping(const Grid& grid, int depth, Vec3f from, Vec3f to, const std::function<bool(std::uint64_t)>& skip) {
  Runs runs;
  walk_ray_skipping(grid, depth, from, grid.key(Vec3d(from)), to, grid.key(Vec3d(to)), skip,
                    [&](std::uint64_t brick, std::uint64_t voxels) { runs.emplace_back(brick, voxels); });
  return runs;
}

/// The runs of a walk as codes, brick by brick.
std::vector<std::uint64_t> codes_of(const Runs& runs) {
  std::vector<std::uint64_t> codes;
  for (const auto& [brick, voxels] : runs) {
    for (std::uint64_t v = voxels; v != 0; v &= v - 1) codes.push_back(brick + static_cast<std::uint64_t>(std::countr_zero(v)));
  }
  return codes;
}

/// Coordinates a hair's breadth from the voxel border at 0: tiny, denormal,
/// exactly zero, of both signs. A ray between two of them has a float
/// squared length that underflows (below about 2.6e-23 per component),
/// is denormal, or is barely normal.
std::vector<float> hair_coordinates() {
  std::vector<float> values = {0.0f, -0.0f};
  for (const float v : {1e-23f, 1e-29f, 2.5e-23f, 3e-23f, 1e-22f, 1e-20f, 1e-16f, 1e-40f,
                        std::numeric_limits<float>::denorm_min(), std::numeric_limits<float>::min()}) {
    values.push_back(v);
    values.push_back(-v);
  }
  return values;
}

TEST(RayWalker, HairThinRaysAcrossTheBorderAtZeroStopAtOnceAndMatchTheReference) {
  // The ray from the origin to (-1e-23, 1e-23, 0) ends in the voxel beside
  // the origin's, but its float squared length underflows to 0: OctoMap's
  // normalisation gives an infinite / NaN direction, and its walk ran on
  // along y without end (here: a crash, or a column of voxels to the
  // map's edge). The walk visits the origin's voxel and stops.
  const std::vector<float> values = hair_coordinates();
  for (const double resolution : {0.1, 0.5, 0.05}) {  // 0.5: the border at 0 is exact in float
    const Grid grid(resolution, 6);
    const test::DenseGrid reference(resolution, 6, -2.0f, 3.5f);
    std::mt19937 rng(static_cast<std::uint32_t>(resolution * 1000));
    std::uniform_int_distribution<std::size_t> pick(0, values.size() - 1);
    for (int i = 0; i < 20000; ++i) {
      const Vec3f from = i == 0 ? Vec3f{0, 0, 0} : Vec3f{values[pick(rng)], values[pick(rng)], values[pick(rng)]};
      const Vec3f to =
          i == 0 ? Vec3f{-1e-23f, 1e-23f, 0} : Vec3f{values[pick(rng)], values[pick(rng)], values[pick(rng)]};
      bool inside = false;
      const std::vector<Key> keys = walk(grid, from, to, inside);
      ASSERT_TRUE(inside);
      const Key a = grid.key(Vec3d(from));
      const Key b = grid.key(Vec3d(to));
      // Every coordinate is within 1e-16 of the border at 0, so the walk can
      // cross no other border: at most the three at 0, all its voxels in
      // the eight around the origin (rounding as OctoMap's may carry it over
      // the border at 0 beside the end voxel, but never further).
      ASSERT_LE(keys.size(), 4u) << "ray " << i;
      for (const Key& k : keys) {
        for (int axis = 0; axis < 3; ++axis) {
          ASSERT_TRUE(k[axis] + 1 == grid.key_offset() || k[axis] == grid.key_offset())
              << "ray " << i << " (" << from.x << "," << from.y << "," << from.z << ") -> (" << to.x << ","
              << to.y << "," << to.z << ") visits key " << k[axis] << " on axis " << axis;
        }
      }
      if (a != b) {
        ASSERT_FALSE(keys.empty());
        ASSERT_EQ(keys.front(), a);
      }
      expect_same_walk(grid, reference, from, to);
      // The fast integrator's walk: skipping nothing it is the same walk;
      // skipping every node it visits no more.
      Runs expected;
      walk_ray_runs(grid, from, a, to, b, [&](std::uint64_t brick, std::uint64_t v) { expected.emplace_back(brick, v); });
      ASSERT_EQ(walk_skipping(grid, 1, from, to, [](std::uint64_t) { return false; }), expected) << "ray " << i;
      ASSERT_LE(codes_of(walk_skipping(grid, 1, from, to, [](std::uint64_t) { return true; })).size(), keys.size());
    }
  }
}

TEST(RayWalker, RaysAlongVoxelFacesAndEdgesAndIntoTheNeighbourMatchTheReference) {
  // Rays that run exactly on voxel borders (a face: one coordinate constant
  // on a border; an edge: two), axis-aligned and diagonal in a plane, and
  // rays ending in the voxel beside the origin's, from origins on borders,
  // edges and corners.
  for (const double resolution : {0.1, 0.5, 0.05}) {
    const Grid grid(resolution, 6);
    const test::DenseGrid reference(resolution, 6, -2.0f, 3.5f);
    const auto r = static_cast<float>(resolution);
    const std::vector<float> borders = {0.0f, r, -r, 3 * r, -2 * r, 0.5f * r, 1e-23f, -1e-23f};
    std::mt19937 rng(static_cast<std::uint32_t>(resolution * 100 + 1));
    std::uniform_int_distribution<std::size_t> pick(0, borders.size() - 1);
    std::uniform_int_distribution<int> steps(-8, 8);
    std::uniform_real_distribution<float> fraction(-1.0f, 1.0f);
    for (int i = 0; i < 20000; ++i) {
      const Vec3f from{borders[pick(rng)], borders[pick(rng)], borders[pick(rng)]};
      Vec3f to = from;
      const int kind = i % 4;
      for (std::size_t axis = 0; axis < 3; ++axis) {
        if (kind == 0 && axis != std::size_t(i % 3)) continue;  // axis-aligned
        if (kind == 1 && axis == std::size_t(i % 3)) continue;  // diagonal in a plane
        const float move = kind == 3 ? fraction(rng) * r        // into a neighbour (or its own voxel)
                                     : float(steps(rng)) * r * (kind == 2 ? fraction(rng) : 1.0f);
        to[axis] = from[axis] + move;
      }
      expect_same_walk(grid, reference, from, to);
    }
  }
}

TEST(RayWalker, RunsAreTheWalksVoxelsBrickByBrick) {
  const Grid grid(0.1, 6);
  std::mt19937 rng(6);
  std::uniform_real_distribution<float> coordinate(-3.19f, 3.19f);
  for (int i = 0; i < 3000; ++i) {
    const Vec3f from{coordinate(rng), coordinate(rng), coordinate(rng)};
    const Vec3f to{coordinate(rng), coordinate(rng), coordinate(rng)};
    Runs expected;  // walk_ray's codes grouped into stretches within one brick
    walk_ray(grid, from, to, [&](std::uint64_t code) {
      const std::uint64_t brick = code & ~std::uint64_t{63};
      if (expected.empty() || expected.back().first != brick) expected.emplace_back(brick, 0);
      expected.back().second |= std::uint64_t{1} << (code & 63);
    });
    Runs runs;
    walk_ray_runs(grid, from, grid.key(Vec3d(from)), to, grid.key(Vec3d(to)),
                  [&](std::uint64_t brick, std::uint64_t voxels) { runs.emplace_back(brick, voxels); });
    ASSERT_EQ(runs, expected) << "ray " << i;
  }
}

TEST(RayWalkerSkipping, SkippingNothingIsWalkRay) {
  const Grid grid(0.1, 6);  // [-3.2, 3.2): many rays touch the edge
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> coordinate(-3.19f, 3.19f);
  for (int i = 0; i < 3000; ++i) {
    const Vec3f from{coordinate(rng), coordinate(rng), coordinate(rng)};
    const Vec3f to{coordinate(rng), coordinate(rng), coordinate(rng)};
    Runs expected;
    walk_ray_runs(grid, from, grid.key(Vec3d(from)), to, grid.key(Vec3d(to)),
                  [&](std::uint64_t brick, std::uint64_t voxels) { expected.emplace_back(brick, voxels); });
    std::size_t asked = 0;
    const auto actual = walk_skipping(grid, 2, from, to, [&](std::uint64_t) {
      ++asked;
      return false;
    });
    ASSERT_EQ(actual, expected) << "ray " << i;
    std::set<std::uint64_t> nodes;
    for (const std::uint64_t code : codes_of(expected)) nodes.insert(code >> 6);
    EXPECT_EQ(asked, nodes.size()) << "asked once per node entered, ray " << i;
  }
}

/// Length of the part of segment a-b inside the cube [low, low + size]^3 (-1: none).
double length_inside(Vec3d a, Vec3d b, Vec3d low, double size) {
  const Aabb cube{low, low + Vec3d{size, size, size}};
  const auto part = cube.clip(a, b);
  return part ? (part->second - part->first) * (b - a).norm() : -1.0;
}

TEST(RayWalkerSkipping, JumpsOverSkippedNodesAndWalksTheOthersVoxelByVoxel) {
  const double resolution = 0.1;
  const Grid grid(resolution, 6);
  const int depth = 2;  // 40 cm nodes
  std::mt19937 rng(8);
  std::uniform_real_distribution<float> coordinate(-3.19f, 3.19f);
  std::size_t jumps = 0;
  std::size_t visited_total = 0;
  for (int i = 0; i < 300; ++i) {
    const Vec3f from{coordinate(rng), coordinate(rng), coordinate(rng)};
    const Vec3f to{coordinate(rng), coordinate(rng), coordinate(rng)};
    // A fixed pseudo-random half of the nodes is skipped.
    auto skipped = [](std::uint64_t node_code) { return ((node_code >> 6) * 0x9E3779B97F4A7C15ULL) >> 63 != 0; };
    const auto visited = codes_of(walk_skipping(grid, depth, from, to, [&](std::uint64_t node) {
      jumps += skipped(node);
      return skipped(node);
    }));
    visited_total += visited.size();
    const std::set<std::uint64_t> seen(visited.begin(), visited.end());
    ASSERT_EQ(seen.size(), visited.size()) << "a voxel visited twice, ray " << i;
    const Key end_key = grid.key(Vec3d(to));
    for (const std::uint64_t code : visited) {
      ASSERT_FALSE(skipped(code >> 6 << 6)) << "visited a voxel of a skipped node, ray " << i;
      ASSERT_NE(morton::decode(code), end_key);
      // Every visited voxel lies on the segment (to rounding).
      ASSERT_GT(length_inside(Vec3d(from), Vec3d(to), grid.min_corner(morton::decode(code)), resolution), -0.5)
          << "ray " << i;
    }
    // Every voxel the segment crosses for more than a hundredth of a voxel,
    // outside the skipped nodes and away from the end, is visited.
    const Key a = grid.key(Vec3d(from));
    for (std::uint32_t z = std::min(a.z, end_key.z); z <= std::max(a.z, end_key.z); ++z) {
      for (std::uint32_t y = std::min(a.y, end_key.y); y <= std::max(a.y, end_key.y); ++y) {
        for (std::uint32_t x = std::min(a.x, end_key.x); x <= std::max(a.x, end_key.x); ++x) {
          const Key key{x, y, z};
          const std::uint64_t code = morton::encode(key);
          if (skipped(code >> 6 << 6)) continue;
          if (std::abs(int(x) - int(end_key.x)) <= 1 && std::abs(int(y) - int(end_key.y)) <= 1 &&
              std::abs(int(z) - int(end_key.z)) <= 1) {
            continue;
          }
          if (length_inside(Vec3d(from), Vec3d(to), grid.min_corner(key), resolution) > 0.01 * resolution) {
            ASSERT_TRUE(seen.count(code)) << "crossed voxel " << x << "," << y << "," << z << " missed, ray " << i;
          }
        }
      }
    }
  }
  EXPECT_GT(jumps, 500u);
  EXPECT_GT(visited_total, 5000u);
}

}  // namespace
}  // namespace umbra
