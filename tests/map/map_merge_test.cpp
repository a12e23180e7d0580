// OccupancyMap::merge against a dense brute force of the rule in
// docs/design.md ("Merging maps"): every finest voxel of the target ends as
// clamp(before + the other map's value at the voxel it takes), with the
// other map placed by a voxel offset or a rigid transform; tree invariants
// hold after the merge. And: the maps of two halves of a scan sequence,
// merged, equal the map of all scans (wide clamping bounds).
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <optional>
#include <random>
#include <string>

#include "support/map_internals.hpp"
#include "support/query_oracle.hpp"
#include "umbra/map/map_crop.hpp"

namespace umbra {
namespace {

/// A random map whose known voxels lie in [lo, hi] on each axis (so that
/// shifted or turned, it stays inside the target).
OccupancyMap random_part(int depth_levels, unsigned seed, bool prune, std::uint32_t lo, std::uint32_t hi) {
  test::RandomMapSpec spec;
  spec.depth_levels = depth_levels;
  spec.seed = seed;
  spec.auto_prune = prune;
  return crop_map(test::random_map(spec), VoxelBox{Key{lo, lo, lo}, Key{hi, hi, hi}});
}

/// The rule's source voxel for a target voxel under a transform, written out
/// here again: p = R^T (c - t) in double, then the other map's key of p.
std::optional<Key> rule_source(const Grid& grid, const Pose& pose, Key target) {
  const Vec3d c = grid.center(target);
  const double d[3] = {c.x - pose.m[0][3], c.y - pose.m[1][3], c.z - pose.m[2][3]};
  Vec3d p;
  for (std::size_t j = 0; j < 3; ++j) p[j] = pose.m[0][j] * d[0] + pose.m[1][j] * d[1] + pose.m[2][j] * d[2];
  return grid.key_checked(p);
}

/// Checks `merged` voxel for voxel: before[k] + source[where(k)], clamped.
template <typename Where>
void expect_merged(const test::DenseValues& before, const test::DenseValues& source, const OccupancyMap& merged,
                   Where&& where) {
  ASSERT_EQ(test::check_invariants(merged), "");
  const LogOddsRange range = LogOddsRange::from(merged.sensor_model());
  const test::DenseValues after(merged);
  std::size_t changed = 0;
  for (std::uint32_t z = 0; z < before.size(); ++z) {
    for (std::uint32_t y = 0; y < before.size(); ++y) {
      for (std::uint32_t x = 0; x < before.size(); ++x) {
        const Key key{x, y, z};
        const std::optional<Key> from = where(key);
        const float add = from ? source.at(*from) : 0.0f;
        const float expected = range.add(before.at(key), add);
        ASSERT_EQ(after.at(key), expected) << "voxel " << x << " " << y << " " << z;
        changed += add != 0.0f ? 1 : 0;
      }
    }
  }
  const std::size_t voxels = std::size_t{before.size()} * before.size() * before.size();
  EXPECT_GT(changed, voxels / 200) << "the merge added almost nothing: a weak test";
}

TEST(MapMerge, OffsetsMatchBruteForce) {
  std::mt19937 random(5);
  for (const int depth_levels : {4, 5, 6}) {
    const std::uint32_t size = 1u << depth_levels;
    const std::uint32_t lo = size / 4;
    const std::uint32_t hi = size / 2;
    for (const bool prune : {true, false}) {
      for (unsigned seed = 1; seed <= 2; ++seed) {
        test::RandomMapSpec spec;
        spec.depth_levels = depth_levels;
        spec.seed = seed + 10;
        spec.auto_prune = prune;
        const OccupancyMap target = test::random_map(spec);
        const OccupancyMap other = random_part(depth_levels, seed, !prune, lo, hi);
        const test::DenseValues before(target);
        const test::DenseValues source(other);
        // Aligned to pruned nodes, misaligned by one voxel, and random.
        std::uniform_int_distribution<std::int64_t> shift(-std::int64_t{lo}, std::int64_t{size - 1 - hi});
        const std::int64_t step = size / 8;
        for (const VoxelOffset offset : {VoxelOffset{0, 0, 0}, VoxelOffset{step, -step, 0}, VoxelOffset{1, 0, -1},
                                         VoxelOffset{shift(random), shift(random), shift(random)}}) {
          SCOPED_TRACE("depth " + std::to_string(depth_levels) + " prune " + std::to_string(prune) + " offset " +
                       std::to_string(offset.x) + " " + std::to_string(offset.y) + " " + std::to_string(offset.z));
          OccupancyMap merged = target;
          const MergeStats stats = merged.merge(other, offset);
          EXPECT_EQ(merged.auto_prune(), prune);
          EXPECT_GT(stats.voxels, 0u);
          expect_merged(before, source, merged, [&](Key key) -> std::optional<Key> {
            const std::int64_t x = std::int64_t{key.x} - offset.x;
            const std::int64_t y = std::int64_t{key.y} - offset.y;
            const std::int64_t z = std::int64_t{key.z} - offset.z;
            if (x < 0 || y < 0 || z < 0 || x >= size || y >= size || z >= size) return std::nullopt;
            return Key{std::uint32_t(x), std::uint32_t(y), std::uint32_t(z)};
          });
        }
      }
    }
  }
}

TEST(MapMerge, TransformsMatchBruteForce) {
  std::mt19937 random(7);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  for (const int depth_levels : {4, 5, 6}) {
    const std::uint32_t size = 1u << depth_levels;
    // The part around the map's centre: turned about it, it stays inside.
    const OccupancyMap other = random_part(depth_levels, 3, true, size * 3 / 8, size * 5 / 8 - 1);
    const test::DenseValues source(other);
    for (const bool prune : {true, false}) {
      test::RandomMapSpec spec;
      spec.depth_levels = depth_levels;
      spec.seed = 20 + depth_levels;
      spec.auto_prune = prune;
      const OccupancyMap target = test::random_map(spec);
      const test::DenseValues before(target);
      const double voxel = target.resolution();
      const double angle = std::numbers::pi / 6;
      const std::vector<Pose> poses = {
          // 30 degrees about z, a fraction of a voxel aside.
          Pose::from_translation_quaternion(0.37 * voxel, -0.21 * voxel, 0.0, std::cos(angle / 2), 0, 0,
                                            std::sin(angle / 2)),
          // Half a voxel aside, no turn (not a whole-voxel shift).
          Pose::from_translation_quaternion(0.5 * voxel, 0.0, -1.5 * voxel, 1, 0, 0, 0),
          // Random turn and shift.
          Pose::from_translation_quaternion(unit(random) * 2 * voxel, unit(random) * 2 * voxel,
                                            unit(random) * 2 * voxel, unit(random), unit(random), unit(random),
                                            unit(random))};
      for (std::size_t i = 0; i < poses.size(); ++i) {
        SCOPED_TRACE("depth " + std::to_string(depth_levels) + " prune " + std::to_string(prune) + " pose " +
                     std::to_string(i));
        OccupancyMap merged = target;
        merged.merge(other, poses[i]);
        expect_merged(before, source, merged,
                      [&](Key key) { return rule_source(target.grid(), poses[i], key); });
      }
    }
  }
}

TEST(MapMerge, WholeVoxelTranslationEqualsOffset) {
  const OccupancyMap other = random_part(5, 4, true, 8, 15);
  const OccupancyMap target = test::random_map({});
  OccupancyMap by_pose = target;
  OccupancyMap by_offset = target;
  by_pose.merge(other, Pose::from_translation_quaternion(0.3, -0.2, 0.5, 1, 0, 0, 0));  // voxels of 0.1 m
  by_offset.merge(other, VoxelOffset{3, -2, 5});
  const test::DenseValues a(by_pose);
  const test::DenseValues b(by_offset);
  for (std::uint32_t z = 0; z < a.size(); ++z) {
    for (std::uint32_t y = 0; y < a.size(); ++y) {
      for (std::uint32_t x = 0; x < a.size(); ++x) ASSERT_EQ(a.at({x, y, z}), b.at({x, y, z}));
    }
  }
}

TEST(MapMerge, PrunedBlockOnPrunedBlockStaysOneNode) {
  // An 8^3 occupied block of one map onto a free 8^3 block of the other:
  // one node addition, and the result stays one pruned node.
  OccupancyMap target(0.1, 5);
  OccupancyMap other(0.1, 5);
  for (std::uint32_t z = 0; z < 8; ++z) {
    for (std::uint32_t y = 0; y < 8; ++y) {
      for (std::uint32_t x = 0; x < 8; ++x) {
        target.set_log_odds(Key{x + 8, y, z}, -1.0f);
        other.set_log_odds(Key{x, y, z}, 1.5f);
      }
    }
  }
  const std::size_t nodes_before = target.node_counts().total();
  const MergeStats stats = target.merge(other, VoxelOffset{8, 0, 0});
  EXPECT_EQ(stats.nodes, 1u);
  EXPECT_EQ(stats.voxels, 512u);
  EXPECT_EQ(target.node_counts().total(), nodes_before);
  EXPECT_FLOAT_EQ(target.node(Key{12, 3, 3}).log_odds, 0.5f);
  EXPECT_EQ(target.node(Key{12, 3, 3}).depth, 3);
}

TEST(MapMerge, RefusesOtherGridsAndKeepsTheMapOnErrors) {
  OccupancyMap map(0.1, 5);
  map.set_log_odds(Key{1, 1, 1}, 1.0f);
  try {
    map.merge(OccupancyMap(0.05, 5));
    FAIL() << "no error";
  } catch (const std::invalid_argument& error) {
    EXPECT_NE(std::string(error.what()).find("0.1"), std::string::npos) << error.what();
    EXPECT_NE(std::string(error.what()).find("0.05"), std::string::npos) << error.what();
  }
  try {
    map.merge(OccupancyMap(0.1, 6));
    FAIL() << "no error";
  } catch (const std::invalid_argument& error) {
    EXPECT_NE(std::string(error.what()).find("this map 5, the other 6"), std::string::npos) << error.what();
  }
  OccupancyMap other(0.1, 5);
  other.set_log_odds(Key{30, 2, 2}, 2.0f);
  other.set_log_odds(Key{2, 2, 2}, 2.0f);
  EXPECT_THROW(map.merge(other, VoxelOffset{2, 0, 0}), std::out_of_range);  // 30 + 2 is outside
  Pose skew;
  skew.m[0][1] = 0.5;
  EXPECT_THROW(map.merge(other, skew), std::invalid_argument);
  const Pose far = Pose::from_translation_quaternion(0.25, 0, 0, 1, 0, 0, 0);
  EXPECT_THROW(map.merge(other, far), std::out_of_range);
  // Unchanged by the refused merges.
  EXPECT_EQ(map.node(Key{1, 1, 1}).log_odds, 1.0f);
  EXPECT_EQ(map.node(Key{2, 2, 2}).log_odds, 0.0f);
  EXPECT_EQ(test::check_invariants(map), "");
}

TEST(MapMerge, IntoItselfDoublesTheLogOdds) {
  OccupancyMap map(0.1, 5);
  map.set_log_odds(Key{3, 4, 5}, 0.8f);
  map.set_log_odds(Key{6, 4, 5}, -0.5f);
  map.merge(map);
  EXPECT_EQ(map.node(Key{3, 4, 5}).log_odds, 1.6f);
  EXPECT_EQ(map.node(Key{6, 4, 5}).log_odds, -1.0f);
  EXPECT_EQ(map.node(Key{0, 0, 0}).log_odds, 0.0f);
}

TEST(MapMerge, ColorsAverageByTheirSampleCounts) {
  MapConfig config;
  config.resolution = 0.1;
  config.depth_levels = 5;
  config.color = true;
  OccupancyMap map(config);
  OccupancyMap other(config);
  const Key both{4, 4, 4};
  const Key only_other{5, 4, 4};
  map.set_log_odds(both, 1.0f);
  map.add_color(map.grid().center(both), Rgb{0, 0, 0});  // weight 1
  other.set_log_odds(both, 1.0f);
  other.set_log_odds(only_other, 1.0f);
  for (int i = 0; i < 3; ++i) other.add_color(other.grid().center(both), Rgb{200, 100, 40});  // weight 3
  other.add_color(other.grid().center(only_other), Rgb{9, 8, 7});
  map.merge(other);
  // (0 * 1 + 200 * 3) / 4 = 150, (100 * 3) / 4 = 75, (40 * 3) / 4 = 30.
  EXPECT_EQ(map.color(both), (Rgb{150, 75, 30}));
  EXPECT_EQ(map.color(only_other), (Rgb{9, 8, 7}));
  EXPECT_EQ(test::tree_of(map).color_weight(test::tree_of(map).find(morton::encode(both), 0).node), 4);
  EXPECT_EQ(test::check_invariants(map), "");
  // A map without color takes the log-odds only.
  OccupancyMap plain(0.1, 5);
  plain.merge(other);
  EXPECT_EQ(plain.node(both).log_odds, 1.0f);
  EXPECT_FALSE(plain.color(both).has_value());
}

/// Random scans inside a depth-6 map, from a few origins.
std::vector<std::pair<Vec3f, std::vector<Vec3f>>> random_scans(int count) {
  std::mt19937 random(99);
  std::uniform_real_distribution<float> anywhere(-3.0f, 3.0f);
  std::vector<std::pair<Vec3f, std::vector<Vec3f>>> scans;
  for (int i = 0; i < count; ++i) {
    const Vec3f origin{anywhere(random) * 0.2f, anywhere(random) * 0.2f, anywhere(random) * 0.2f};
    std::vector<Vec3f> points(400);
    for (Vec3f& p : points) p = {anywhere(random), anywhere(random), anywhere(random) * 0.3f};
    scans.emplace_back(origin, std::move(points));
  }
  return scans;
}

TEST(MapMerge, TwoHalvesEqualOneMapWithinFloatRounding) {
  // Clamping bounds wide enough that no voxel reaches them (6 scans of at
  // most +-0.85 each stay within +-5.1 < 6.9).
  MapConfig config;
  config.resolution = 0.1;
  config.depth_levels = 6;
  config.sensor.clamp_min = 0.001;
  config.sensor.clamp_max = 0.999;
  const int scans = 6;
  const auto data = random_scans(scans);
  OccupancyMap whole(config);
  OccupancyMap first(config);
  OccupancyMap second(config);
  for (int i = 0; i < scans; ++i) {
    whole.insert_point_cloud(data[i].first, data[i].second);
    (i < scans / 2 ? first : second).insert_point_cloud(data[i].first, data[i].second);
  }
  first.merge(second);
  ASSERT_EQ(test::check_invariants(first), "");
  // The whole map adds the scans' deltas one by one; the merge adds two
  // partial sums. Float addition is not associative: each of the n - 1
  // additions of either order rounds by at most half an ulp of a partial sum
  // of magnitude <= n * 0.85, so they differ by at most 2 (n - 1) * 2^-24 *
  // n * 0.85 (4.3e-6 here); a wrong merge is off by at least a miss (0.4).
  const float tolerance = 2.0f * (scans - 1) * std::ldexp(1.0f, -24) * scans * 0.85f;
  const test::DenseValues a(whole);
  const test::DenseValues b(first);
  std::size_t observed = 0;
  std::size_t inexact = 0;
  for (std::uint32_t z = 0; z < a.size(); ++z) {
    for (std::uint32_t y = 0; y < a.size(); ++y) {
      for (std::uint32_t x = 0; x < a.size(); ++x) {
        const float one = a.at({x, y, z});
        const float merged = b.at({x, y, z});
        ASSERT_NEAR(merged, one, tolerance) << x << " " << y << " " << z;
        ASSERT_EQ(one == 0.0f, merged == 0.0f) << "known in one map only: " << x << " " << y << " " << z;
        observed += one != 0.0f ? 1 : 0;
        inexact += one != merged ? 1 : 0;
      }
    }
  }
  EXPECT_GT(observed, 1000u);
  std::printf("two halves: %zu observed voxels, %zu not bit-equal (within %.2g)\n", observed, inexact,
              double(tolerance));
}

}  // namespace
}  // namespace umbra
