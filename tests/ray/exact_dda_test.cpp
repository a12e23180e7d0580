// ExactDda and SegmentWalk against a literal, key-based copy of
// OctoMap's computeRayKeys (tests/support/dense_grid). Jumps are checked
// against the voxel-by-voxel walk: with an oracle that marks nodes of
// depth 1 to 4 as "jump over me", the jumping walk must visit exactly the
// reference walk's voxels, except that of each stretch inside a marked node
// it visits the first voxel only. Rays include the degenerate ones whose
// border crossings tie (diagonals between voxel centres, axis-aligned rays,
// rays along borders), where a jump computed as t_max + n * t_delta instead
// of the repeated sum would turn ties the other way.
#include <cstdint>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "ray/exact_dda.hpp"
#include "support/dense_grid.hpp"

namespace umbra {
namespace {

/// The depth (0: none) of the marked node holding `key`: per depth, from 4
/// down to 1, a hash of the node's key marks about one node in `one_in`.
int marked_depth(Key key, std::uint32_t seed, std::uint32_t one_in) {
  for (int depth = 4; depth >= 1; --depth) {
    std::uint64_t h = morton::encode(key.at_depth(depth)) * 0x9E3779B97F4A7C15ULL + seed * 0xC2B2AE3D27D4EB4FULL +
                      static_cast<std::uint64_t>(depth);
    h ^= h >> 29;
    h *= 0xBF58476D1CE4E5B9ULL;
    h ^= h >> 32;
    if (h % one_in == 0) return depth;
  }
  return 0;
}

/// The reference walk with each stretch inside one marked node cut to its
/// first voxel: what a walk that jumps over marked nodes must visit.
std::vector<Key> without_jumped_voxels(const std::vector<Key>& walk, std::uint32_t seed, std::uint32_t one_in,
                                       Key end) {
  std::vector<Key> kept;
  int depth = 0;
  Key node{};
  for (const Key key : walk) {
    if (depth > 0 && key.at_depth(depth) == node) continue;  // still inside the node jumped over
    kept.push_back(key);
    depth = marked_depth(key, seed, one_in);
    // A node holding the end voxel is walked voxel by voxel.
    if (depth > 0 && end.at_depth(depth) == key.at_depth(depth)) depth = 0;
    node = key.at_depth(depth);
  }
  return kept;
}

std::vector<Key> jumping_walk(const Grid& grid, Vec3f from, Vec3f to, std::uint32_t seed, std::uint32_t one_in) {
  std::vector<Key> keys;
  const Key from_key = grid.key(Vec3d(from));
  const Key to_key = grid.key(Vec3d(to));
  detail::SegmentWalk walk(grid, from, from_key, to, to_key);
  while (!walk.at_end()) {
    keys.push_back(morton::decode(walk.code()));
    walk.next(one_in == 0 ? 0 : marked_depth(keys.back(), seed, one_in));
  }
  // Then the end voxel, and nothing after it.
  EXPECT_EQ(walk.code(), morton::encode(to_key));
  EXPECT_FALSE(walk.done());
  walk.next(0);
  EXPECT_TRUE(walk.done());
  return keys;
}

void expect_walk(const Grid& grid, const test::DenseGrid& reference, Vec3f from, Vec3f to, std::uint32_t seed,
                 std::uint32_t one_in) {
  std::vector<Key> full;
  ASSERT_TRUE(reference.ray_keys(from, to, full));
  const std::vector<Key> expected =
      one_in == 0 ? full : without_jumped_voxels(full, seed, one_in, grid.key(Vec3d(to)));
  const std::vector<Key> actual = jumping_walk(grid, from, to, seed, one_in);
  ASSERT_EQ(actual.size(), expected.size()) << "ray (" << from.x << "," << from.y << "," << from.z << ") -> ("
                                            << to.x << "," << to.y << "," << to.z << "), one in " << one_in;
  for (std::size_t i = 0; i < actual.size(); ++i) ASSERT_EQ(actual[i], expected[i]) << "voxel " << i;
}

/// Random rays and degenerate ones: between voxel centres along diagonals
/// (every crossing a tie in exact arithmetic), axis-aligned, on borders.
std::vector<std::pair<Vec3f, Vec3f>> test_rays(const Grid& grid, std::uint32_t seed) {
  std::vector<std::pair<Vec3f, Vec3f>> rays;
  std::mt19937 rng(seed);
  const auto h = static_cast<float>(grid.half_extent()) * 0.999f;
  std::uniform_real_distribution<float> coordinate(-h, h);
  const auto n = static_cast<int>(grid.keys_per_axis());
  std::uniform_int_distribution<int> key(0, n - 1);
  std::uniform_int_distribution<int> offset(-n / 2, n / 2);
  for (int i = 0; i < 400; ++i) {
    rays.push_back({{coordinate(rng), coordinate(rng), coordinate(rng)}, {coordinate(rng), coordinate(rng), coordinate(rng)}});
  }
  const int directions[][3] = {{1, 1, 0}, {1, 1, 1}, {1, -1, 1}, {-1, -1, -1}, {1, 2, 0}, {2, 1, 1},
                               {1, 0, 0}, {0, -1, 0}, {0, 0, 1}, {3, 3, 1},   {-2, 1, 2}};
  for (int i = 0; i < 400; ++i) {
    const int* d = directions[i % std::size(directions)];
    const int k = std::max(1, std::abs(offset(rng)));
    Key a{};
    Key b{};
    bool inside = true;
    for (int axis = 0; axis < 3; ++axis) {
      const int from = key(rng);
      const int to = from + d[axis] * k;
      inside &= to >= 0 && to < n;
      a[axis] = static_cast<std::uint32_t>(from);
      b[axis] = static_cast<std::uint32_t>(std::clamp(to, 0, n - 1));
    }
    if (!inside) continue;
    rays.push_back({grid.center_f(a), grid.center_f(b)});
    // The same along a voxel border: corners instead of centres.
    const auto half = static_cast<float>(grid.resolution() / 2);
    const Vec3f corner{half, half, half};
    rays.push_back({grid.center_f(a) - corner, grid.center_f(b) - corner});
  }
  // Corners of the voxels at the map's low edge lie outside it.
  std::erase_if(rays, [&](const auto& ray) { return !grid.key_checked(ray.first) || !grid.key_checked(ray.second); });
  return rays;
}

TEST(ExactDda, WalkWithoutJumpsIsOctoMapsWalk) {
  for (const double resolution : {0.05, 0.1, 0.37}) {
    const Grid grid(resolution, 6);
    const test::DenseGrid reference(resolution, 6, -2.0f, 3.5f);
    for (const auto& [from, to] : test_rays(grid, 11)) expect_walk(grid, reference, from, to, 0, 0);
  }
}

TEST(ExactDda, JumpsOverNodesVisitTheWalksVoxelsOutsideThem) {
  for (const double resolution : {0.05, 0.1, 0.37}) {
    const Grid grid(resolution, 6);
    const test::DenseGrid reference(resolution, 6, -2.0f, 3.5f);
    std::uint32_t seed = 0;
    for (const std::uint32_t one_in : {1u, 2u, 5u}) {
      for (const auto& [from, to] : test_rays(grid, 20 + one_in)) {
        expect_walk(grid, reference, from, to, ++seed, one_in);
      }
    }
  }
}

/// A cast jumping over marked nodes enters each voxel past them at the ray
/// parameter the voxel-by-voxel cast enters it, and stops at the same limit.
TEST(ExactDda, LeavingANodeEntersWhereStepsEnter) {
  const Grid grid(0.1, 6);
  std::uint32_t seed = 100;
  for (const auto& [from, to] : test_rays(grid, 7)) {
    Vec3f direction = to - from;
    const auto length = static_cast<float>(octomap_norm(direction));
    if (!(length > 0.0f)) continue;
    direction = {direction.x / length, direction.y / length, direction.z / length};
    const double limit = length * 0.8;
    ++seed;
    // Every voxel the stepping cast enters up to `limit`, with where it enters.
    std::vector<std::pair<Key, double>> stepped;
    detail::ExactDda steps(grid, from, grid.key(Vec3d(from)), direction, detail::ExactDda::HalfVoxel::kDouble);
    double entered = 0.0;
    stepped.emplace_back(steps.key(), 0.0);
    while (steps.advance(entered) && entered <= limit) stepped.emplace_back(steps.key(), entered);
    // The jumping cast: each voxel it lands on must be one of those, at the same parameter.
    detail::ExactDda jumps(grid, from, grid.key(Vec3d(from)), direction, detail::ExactDda::HalfVoxel::kDouble);
    std::size_t next = 0;  // index into stepped of the voxel jumps is in
    entered = 0.0;
    for (;;) {
      while (next < stepped.size() && !(stepped[next].first == jumps.key())) ++next;
      ASSERT_LT(next, stepped.size()) << "landed on a voxel the stepping cast never enters before the limit";
      ASSERT_EQ(stepped[next].second, entered);
      const int depth = marked_depth(jumps.key(), seed, 2);
      if (depth > 0) {
        // Every voxel stepped over lies in the node left.
        const Key node = jumps.key().at_depth(depth);
        const detail::ExactDda::Left left = jumps.leave_node(depth, limit, entered);
        std::size_t after = next + 1;
        while (after < stepped.size() && stepped[after].first.at_depth(depth) == node) ++after;
        if (left != detail::ExactDda::Left::kOut) {
          ASSERT_EQ(after, stepped.size()) << "the stepping cast leaves the node before the limit";
          break;
        }
        ASSERT_LT(after, stepped.size());
        ASSERT_EQ(stepped[after].first, jumps.key());
        next = after;
        continue;
      }
      if (!jumps.advance(entered) || entered > limit) {
        ASSERT_EQ(next + 1, stepped.size());
        break;
      }
    }
  }
}

}  // namespace
}  // namespace umbra
