// BrickHits (the projective integrator's hits a brick at a time) gives
// what the per-voxel path gives: the same voxels hit, the same counts of
// hits and of voxels beyond max_range, also for bricks that straddle the
// range's sphere and voxels whose centre lies on it to the last bit.
#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "integrate/brick_hits.hpp"
#include "ray/ray_direction.hpp"
#include "tree/update_batch.hpp"
#include "umbra/core/morton.hpp"
#include "umbra/integrate/insert_options.hpp"

namespace umbra {
namespace {

struct Hits {
  UpdateBatch batch;
  InsertStats stats;
};

/// The per-voxel path (add_end_voxel_hit without a box).
Hits voxel_by_voxel(const Grid& grid, Vec3f origin, double max_range, const std::vector<std::uint64_t>& codes) {
  Hits out{UpdateBatch(grid.depth_levels()), {}};
  for (const std::uint64_t code : codes) {
    if (max_range > 0.0 && octomap_norm_exceeds(grid.center_f(morton::decode(code)) - origin, max_range)) {
      ++out.stats.truncated;
    } else if (out.batch.add_hit(code)) {
      ++out.stats.hits;
    }
  }
  return out;
}

Hits by_bricks(const Grid& grid, Vec3f origin, double max_range, const std::vector<std::uint64_t>& codes) {
  Hits out{UpdateBatch(grid.depth_levels()), {}};
  BrickHits hits(grid, origin, max_range, out.batch, out.stats);
  for (const std::uint64_t code : codes) hits.add(code);
  hits.flush();
  return out;
}

void expect_same(const Grid& grid, const Hits& a, const Hits& b, const std::vector<std::uint64_t>& probes) {
  EXPECT_EQ(a.stats.hits, b.stats.hits);
  EXPECT_EQ(a.stats.truncated, b.stats.truncated);
  for (const std::uint64_t code : probes) {
    for (int depth = 0; depth <= grid.depth_levels(); ++depth) {
      ASSERT_EQ(a.batch.holds_hit(code, depth), b.batch.holds_hit(code, depth)) << "code " << code << " depth " << depth;
    }
  }
}

TEST(BrickHits, SameHitsAndCountsAsVoxelByVoxel) {
  std::mt19937 rng(22);
  for (const double resolution : {0.02, 0.004, 0.1}) {
    const Grid grid(resolution, 16);
    for (int trial = 0; trial < 6; ++trial) {
      std::uniform_real_distribution<float> u(-2.0f, 2.0f);
      const Vec3f origin{u(rng), u(rng), u(rng)};
      const double max_range = trial == 5 ? 0.0 : 40.0 * resolution * (1 + trial);
      // Voxels in clusters (a surface's bricks) around the range's sphere,
      // inside and beyond it, each once and sorted, as the image's voxels come.
      std::vector<std::uint64_t> codes;
      std::normal_distribution<double> direction(0.0, 1.0);
      std::uniform_real_distribution<double> radius(0.5, 1.5);
      for (int cluster = 0; cluster < 300; ++cluster) {
        Vec3d d{direction(rng), direction(rng), direction(rng)};
        const double length = std::sqrt(d.x * d.x + d.y * d.y + d.z * d.z);
        const double r = (max_range > 0.0 ? max_range : 1.0) * radius(rng) / length;
        const Vec3d centre{origin.x + d.x * r, origin.y + d.y * r, origin.z + d.z * r};
        std::uniform_int_distribution<int> step(-3, 3);
        const Key key = grid.key(centre);
        for (int i = 0; i < 20; ++i) {
          codes.push_back(morton::encode({key.x + step(rng), key.y + step(rng), key.z + step(rng)}));
        }
      }
      std::sort(codes.begin(), codes.end());
      codes.erase(std::unique(codes.begin(), codes.end()), codes.end());
      expect_same(grid, voxel_by_voxel(grid, origin, max_range, codes), by_bricks(grid, origin, max_range, codes), codes);
      // Unsorted (a brick's voxels handed over in several parts) gives the same too.
      std::shuffle(codes.begin(), codes.end(), rng);
      expect_same(grid, voxel_by_voxel(grid, origin, max_range, codes), by_bricks(grid, origin, max_range, codes), codes);
    }
  }
}

TEST(BrickHits, VoxelsOnTheRangeSphereToTheLastBit) {
  // max_range set to a voxel centre's own float length: that voxel is kept
  // (not beyond), the next one out is not; its brick straddles the sphere.
  const Grid grid(0.02, 16);
  const Vec3f origin{0.013f, -0.207f, 0.5f};
  for (int i = 0; i < 64; ++i) {
    const Key key{grid.key_offset() + 100u + static_cast<std::uint32_t>(i), grid.key_offset() + 7u * i, grid.key_offset() - 3u * i};
    const double max_range = octomap_norm(grid.center_f(key) - origin);
    std::vector<std::uint64_t> codes;
    for (std::uint32_t dx = 0; dx < 4; ++dx) {
      for (std::uint32_t dy = 0; dy < 4; ++dy) {
        codes.push_back(morton::encode({(key.x & ~3u) + dx, (key.y & ~3u) + dy, key.z}));
      }
    }
    std::sort(codes.begin(), codes.end());
    const Hits exact = voxel_by_voxel(grid, origin, max_range, codes);
    EXPECT_TRUE(exact.batch.holds_hit(morton::encode(key), 0));
    expect_same(grid, exact, by_bricks(grid, origin, max_range, codes), codes);
  }
}


TEST(BrickHits, FloatRoundingAtTheBricksFarCorner) {
  // Far from the origin a voxel centre's float length can exceed a bound
  // that its exact length stays below: the per-voxel test truncates that
  // voxel, so its brick must not be taken as wholly within range. Voxels at
  // their brick's far corner (keys 3 mod 4 beyond the origin), 60 to 300 m
  // out, with max_range between the exact and the float length.
  const Grid grid(0.02, 16);
  const Vec3f origin{0.001f, 0.002f, 0.003f};
  std::mt19937 rng(7);
  std::uniform_int_distribution<std::uint32_t> far(3000, 15000);
  int checked = 0;
  for (int i = 0; i < 200000 && checked < 50; ++i) {
    const Key key{grid.key_offset() + (far(rng) | 3u), grid.key_offset() + (far(rng) | 3u),
                  grid.key_offset() + (far(rng) | 3u)};
    const Vec3f offset = grid.center_f(key) - origin;
    const double in_float = static_cast<double>(offset.x * offset.x + offset.y * offset.y + offset.z * offset.z);
    const double dx = grid.axis_center(key.x) - origin.x;
    const double dy = grid.axis_center(key.y) - origin.y;
    const double dz = grid.axis_center(key.z) - origin.z;
    const double exact = dx * dx + dy * dy + dz * dz;
    const double limit = exact * (1.0 + 1.5e-9);
    if (!(in_float > limit * (1.0 + 1.2e-9))) continue;
    const double max_range = std::sqrt(limit);
    ASSERT_TRUE(octomap_norm_exceeds(offset, max_range));
    std::vector<std::uint64_t> codes{morton::encode({key.x - 1, key.y, key.z}), morton::encode(key)};
    std::sort(codes.begin(), codes.end());
    const Hits exact_hits = voxel_by_voxel(grid, origin, max_range, codes);
    EXPECT_FALSE(exact_hits.batch.holds_hit(morton::encode(key), 0));
    expect_same(grid, exact_hits, by_bricks(grid, origin, max_range, codes), codes);
    ++checked;
  }
  EXPECT_EQ(checked, 50);
}

}  // namespace
}  // namespace umbra
