// The dense-grid oracle: random scans (fixed seeds) through the map and
// through tests/support/dense_grid, every voxel's log-odds compared bit for
// bit, and every coarser node's maximum and indicators compared with a
// brute-force recomputation. One test body, many configurations.
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <sstream>

#include <gtest/gtest.h>

#include "support/dense_grid.hpp"
#include "support/map_internals.hpp"
#include "umbra/map/occupancy_map.hpp"

namespace umbra {
namespace {

struct OracleCase {
  int depth_levels;
  double resolution;
  IntegratorKind integrator;
  double max_range;
  bool auto_prune;
  std::uint32_t seed;
};

std::string case_name(const testing::TestParamInfo<OracleCase>& info) {
  const OracleCase& c = info.param;
  std::ostringstream name;
  name << "D" << c.depth_levels << "_" << to_string(c.integrator) << (c.max_range > 0 ? "_maxrange" : "")
       << (c.auto_prune ? "_pruned" : "_unpruned") << "_seed" << c.seed;
  return name.str();
}

/// A scan that exercises every rule: walls (repeated hits, pruned free
/// space), scattered points, points outside the map, NaN / infinite points,
/// duplicates.
std::vector<Vec3f> random_scan(std::mt19937& rng, double half_extent, Vec3f origin) {
  std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
  std::uniform_int_distribution<int> kind(0, 99);
  std::vector<Vec3f> points;
  const auto h = static_cast<float>(half_extent);
  const int count = 300 + static_cast<int>(rng() % 400);
  const float wall = 0.6f * h * unit(rng);
  for (int i = 0; i < count; ++i) {
    const int k = kind(rng);
    if (k < 40) {  // a wall at x = wall
      points.push_back({wall, 0.9f * h * unit(rng), 0.9f * h * unit(rng)});
    } else if (k < 80) {  // anywhere inside
      points.push_back({0.99f * h * unit(rng), 0.99f * h * unit(rng), 0.99f * h * unit(rng)});
    } else if (k < 88) {  // outside the map
      points.push_back({2.5f * h * unit(rng), 2.5f * h * unit(rng), 1.5f * h});
    } else if (k < 92) {
      points.push_back({std::numeric_limits<float>::quiet_NaN(), 0.0f, 0.0f});
    } else if (k < 94) {
      points.push_back({0.0f, std::numeric_limits<float>::infinity(), 0.0f});
    } else if (k < 97 && !points.empty()) {  // duplicate
      points.push_back(points[rng() % points.size()]);
    } else {  // close to the origin, often in the origin voxel
      points.push_back({origin.x + 0.01f * unit(rng), origin.y + 0.01f * unit(rng), origin.z});
    }
  }
  return points;
}

class IntegratorOracle : public testing::TestWithParam<OracleCase> {};

TEST_P(IntegratorOracle, EveryVoxelAndEveryNodeMatchesTheDenseGrid) {
  const OracleCase c = GetParam();
  std::mt19937 rng(c.seed);
  const SensorModel sensor;
  OccupancyMap map(c.resolution, c.depth_levels, sensor);
  map.set_auto_prune(c.auto_prune);
  test::DenseGrid oracle(c.resolution, c.depth_levels, sensor.clamp_min_log_odds(), sensor.clamp_max_log_odds());
  const double half = map.grid().half_extent();
  std::uniform_real_distribution<float> inside(-0.9f * static_cast<float>(half), 0.9f * static_cast<float>(half));

  InsertOptions options;
  options.integrator = c.integrator;
  options.max_range = c.max_range > 0 ? c.max_range * half : c.max_range;
  test::DenseScanOptions dense_options{c.integrator == IntegratorKind::discrete, options.max_range};

  for (int scan = 0; scan < 6; ++scan) {
    const Vec3f origin{inside(rng), inside(rng), inside(rng)};
    const std::vector<Vec3f> points = random_scan(rng, half, origin);
    const InsertStats stats = map.insert_point_cloud(origin, points, options);
    oracle.insert_scan(origin, points, dense_options, sensor.hit_log_odds(), sensor.miss_log_odds());
    ASSERT_GT(stats.non_finite, 0u);
    ASSERT_EQ(test::check_invariants(map), "") << "after scan " << scan;

    // A few single-voxel updates in between, also through both models.
    for (int i = 0; i < 20; ++i) {
      const Key key{static_cast<std::uint32_t>(rng() % oracle.size()),
                    static_cast<std::uint32_t>(rng() % oracle.size()),
                    static_cast<std::uint32_t>(rng() % oracle.size())};
      const float delta = (rng() % 2) ? sensor.hit_log_odds() : sensor.miss_log_odds();
      map.update_log_odds(key, delta);
      oracle.add(key, delta);
    }
    ASSERT_EQ(test::check_invariants(map), "") << "after single updates " << scan;
  }

  // Every finest voxel, bit for bit.
  std::size_t known = 0;
  for (std::uint32_t z = 0; z < oracle.size(); ++z) {
    for (std::uint32_t y = 0; y < oracle.size(); ++y) {
      for (std::uint32_t x = 0; x < oracle.size(); ++x) {
        const Key key{x, y, z};
        const float expected = oracle.at(key);
        const float actual = map.node(key, 0).log_odds;
        ASSERT_EQ(std::memcmp(&expected, &actual, sizeof(float)), 0)
            << "voxel " << x << "," << y << "," << z << ": map " << actual << " oracle " << expected;
        known += expected != 0.0f;
      }
    }
  }
  const std::size_t voxels = std::size_t{oracle.size()} * oracle.size() * oracle.size();
  EXPECT_GT(known * 20, voxels) << "the random scans should observe a good part of the map";

  // Every coarser node: maximum and indicators.
  const LogOddsThresholds& t = test::log_odds_thresholds(map);
  for (int depth = 1; depth <= c.depth_levels; ++depth) {
    const std::uint32_t nodes = oracle.size() >> depth;
    for (std::uint32_t z = 0; z < nodes; ++z) {
      for (std::uint32_t y = 0; y < nodes; ++y) {
        for (std::uint32_t x = 0; x < nodes; ++x) {
          const Key key{x << depth, y << depth, z << depth};
          const Node s = map.node(key, depth);
          ASSERT_EQ(s.log_odds, oracle.max_in_node(key, depth)) << "depth " << depth;
          ASSERT_EQ(s.contains_free, oracle.any_in_node(key, depth, t.free, t.occupied, true)) << "depth " << depth;
          ASSERT_EQ(s.contains_unknown, oracle.any_in_node(key, depth, t.free, t.occupied, false))
              << "depth " << depth;
        }
      }
    }
  }
}

std::vector<OracleCase> oracle_cases() {
  std::vector<OracleCase> cases;
  std::uint32_t seed = 1;
  for (const int depth_levels : {1, 2, 3, 5, 6}) {
    for (const IntegratorKind integrator : {IntegratorKind::simple, IntegratorKind::discrete}) {
      for (const bool auto_prune : {true, false}) {
        const double resolution = depth_levels <= 3 ? 0.5 : 0.1;
        cases.push_back({depth_levels, resolution, integrator, -1.0, auto_prune, seed++});
        cases.push_back({depth_levels, resolution, integrator, 0.7, auto_prune, seed++});
      }
    }
  }
  return cases;
}

INSTANTIATE_TEST_SUITE_P(Configurations, IntegratorOracle, testing::ValuesIn(oracle_cases()), case_name);

class ColorOracle : public testing::TestWithParam<OracleCase> {};

TEST_P(ColorOracle, EveryVoxelAndNodeColorMatchesTheDenseGrid) {
  const OracleCase c = GetParam();
  std::mt19937 rng(c.seed);
  MapConfig config{c.resolution, c.depth_levels, SensorModel{}, Thresholds{}, true};
  OccupancyMap map(config);
  map.set_auto_prune(c.auto_prune);
  const SensorModel& sensor = config.sensor;
  test::DenseGrid oracle(c.resolution, c.depth_levels, sensor.clamp_min_log_odds(), sensor.clamp_max_log_odds());
  const double half = map.grid().half_extent();
  std::uniform_real_distribution<float> inside(-0.9f * static_cast<float>(half), 0.9f * static_cast<float>(half));
  InsertOptions options;
  options.integrator = c.integrator;
  options.max_range = c.max_range > 0 ? c.max_range * half : c.max_range;
  const test::DenseScanOptions dense_options{c.integrator == IntegratorKind::discrete, options.max_range};
  // Few colors, so that equal neighbours (and merges) happen.
  const Rgb palette[] = {{255, 0, 0}, {0, 255, 0}, {10, 20, 30}, {200, 200, 200}};
  for (int scan = 0; scan < 4; ++scan) {
    const Vec3f origin{inside(rng), inside(rng), inside(rng)};
    const std::vector<Vec3f> points = random_scan(rng, half, origin);
    std::vector<Rgb> colors;
    for (std::size_t i = 0; i < points.size(); ++i) colors.push_back(palette[rng() % 4]);
    map.insert_point_cloud(origin, points, colors, options);
    oracle.insert_scan(origin, points, dense_options, sensor.hit_log_odds(), sensor.miss_log_odds(), colors);
    ASSERT_EQ(test::check_invariants(map), "") << "after scan " << scan;
  }
  std::size_t colored = 0;
  for (int depth = 0; depth <= c.depth_levels; ++depth) {
    const std::uint32_t nodes = oracle.size() >> depth;
    for (std::uint32_t z = 0; z < nodes; ++z) {
      for (std::uint32_t y = 0; y < nodes; ++y) {
        for (std::uint32_t x = 0; x < nodes; ++x) {
          const Key key{x << depth, y << depth, z << depth};
          const test::DenseGrid::Color expected = oracle.node_color(key, depth);
          const std::optional<Rgb> actual = map.color(key, depth);
          ASSERT_EQ(actual.has_value(), expected.weight != 0) << "depth " << depth << " key " << x << "," << y << "," << z;
          if (!actual) continue;
          ++colored;
          ASSERT_EQ(*actual, expected.rgb) << "depth " << depth << " key " << x << "," << y << "," << z;
          if (depth == 0) {
            ASSERT_EQ(map.node(key, 0).log_odds, oracle.at(key));
          }
        }
      }
    }
  }
  EXPECT_GT(colored, 50u);
}

std::vector<OracleCase> color_cases() {
  std::vector<OracleCase> cases;
  std::uint32_t seed = 100;
  for (const int depth_levels : {2, 4, 5}) {
    for (const IntegratorKind integrator : {IntegratorKind::simple, IntegratorKind::discrete}) {
      for (const bool auto_prune : {true, false}) {
        cases.push_back({depth_levels, depth_levels <= 3 ? 0.5 : 0.1, integrator, depth_levels == 4 ? 0.7 : -1.0,
                         auto_prune, seed++});
      }
    }
  }
  return cases;
}

INSTANTIATE_TEST_SUITE_P(Configurations, ColorOracle, testing::ValuesIn(color_cases()), case_name);

}  // namespace
}  // namespace umbra
