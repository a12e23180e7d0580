// Decay toward unknown (umbra/map/decay.hpp, docs/design.md "Decay toward
// unknown") against a brute force: a dense array of every voxel's log-odds
// (DenseGrid) to which the documented rule is applied voxel by voxel, written
// out here independently of the library. After every clock step each voxel,
// and every node's value and indicators at every depth, must equal the
// brute force's, and the tree's invariants (inner values, indicators,
// pruning) must hold. Random maps (scans and set values, blocks of equal
// values that prune), depths 3 to 5, pruning on and off, thresholds on
// either side of 0.5, rates of either sign zero, with and without a region.
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "support/dense_grid.hpp"
#include "support/map_internals.hpp"
#include "support/test_support.hpp"
#include "umbra/field/distance_field.hpp"
#include "umbra/io/map_file.hpp"
#include "umbra/map/occupancy_map.hpp"
#include "umbra/map/voxel_box.hpp"

namespace umbra {
namespace {

/// The rule of docs/design.md, written out: positive values lose `occupied`,
/// negative ones gain `free`, in single precision, stopping at 0.
float brute_decay(float l, float occupied, float free) {
  if (l > 0.0f) return std::max(l - occupied, 0.0f);
  if (l < 0.0f) return std::min(l + free, 0.0f);
  return l;
}

/// The amount a step from clock time `from` to `to` takes off at `rate`
/// log-odds per second, for rates set before the clock started at `start`:
/// the difference of the amounts accumulated since `start`, each rounded
/// down to whole quanta of 2^-16 log-odds.
float quantized_step(double rate, double start, double from, double to) {
  const double quantum = 1.0 / 65536.0;
  return static_cast<float>(
      (std::floor(rate * (to - start) / quantum) - std::floor(rate * (from - start) / quantum)) * quantum);
}

struct Case {
  int depth_levels;
  bool auto_prune;
  Thresholds thresholds;
  double occupied_rate;
  double free_rate;
  bool region;
};

std::string compare(const OccupancyMap& map, const test::DenseGrid& dense, const LogOddsThresholds& t) {
  const std::uint32_t size = dense.size();
  for (int depth = 0; depth <= map.depth_levels(); ++depth) {
    const std::uint32_t step = 1u << depth;
    for (std::uint32_t z = 0; z < size; z += step) {
      for (std::uint32_t y = 0; y < size; y += step) {
        for (std::uint32_t x = 0; x < size; x += step) {
          const Key key{x, y, z};
          const Node node = map.node(key, depth);
          const auto where = [&] {
            return "depth " + std::to_string(depth) + " key (" + std::to_string(x) + ", " + std::to_string(y) + ", " +
                   std::to_string(z) + ")";
          };
          const float expected = dense.max_in_node(key, depth);
          if (node.log_odds != expected) {
            return where() + ": value " + std::to_string(node.log_odds) + ", brute force " + std::to_string(expected);
          }
          if (node.contains_free != dense.any_in_node(key, depth, t.free, t.occupied, true)) {
            return where() + ": contains_free differs";
          }
          if (node.contains_unknown != dense.any_in_node(key, depth, t.free, t.occupied, false)) {
            return where() + ": contains_unknown differs";
          }
        }
      }
    }
  }
  return test::check_invariants(map);
}

void run_case(const Case& c, unsigned seed) {
  SCOPED_TRACE("depth " + std::to_string(c.depth_levels) + " prune " + std::to_string(c.auto_prune) + " seed " +
               std::to_string(seed));
  const double resolution = 0.1;
  MapConfig config;
  config.resolution = resolution;
  config.depth_levels = c.depth_levels;
  config.thresholds = c.thresholds;
  OccupancyMap map(config);
  map.set_auto_prune(c.auto_prune);
  const LogOddsRange range = LogOddsRange::from(config.sensor);
  test::DenseGrid dense(resolution, c.depth_levels, range.min, range.max);
  const LogOddsThresholds t = LogOddsThresholds::from(c.thresholds);
  std::mt19937 rng(seed);
  const double half = 0.5 * resolution * dense.size();
  std::uniform_real_distribution<double> coordinate(-half + 0.01, half - 0.01);
  std::uniform_int_distribution<std::uint32_t> key_axis(0, dense.size() - 1);
  std::uniform_real_distribution<float> value(range.min, range.max);

  // Scans (the simple integrator is OctoMap's rule, as DenseGrid's).
  const auto scan = [&](std::optional<double> stamp) {
    const Vec3f origin{float(coordinate(rng)), float(coordinate(rng)), float(coordinate(rng))};
    std::vector<Vec3f> points;
    for (int i = 0; i < 30; ++i) points.push_back({float(coordinate(rng)), float(coordinate(rng)), float(coordinate(rng))});
    InsertOptions options;
    options.stamp = stamp;
    map.insert_point_cloud(origin, points, options);
    dense.insert_scan(origin, points, {}, config.sensor.hit_log_odds(), config.sensor.miss_log_odds());
  };
  for (int i = 0; i < 3; ++i) scan(std::nullopt);
  // Single values, and blocks of one value (pruned to one node when pruning is on).
  for (int i = 0; i < 40; ++i) {
    const Key key{key_axis(rng), key_axis(rng), key_axis(rng)};
    const float v = i % 5 == 0 ? 0.0f : value(rng);
    map.set_log_odds(key, v);
    dense.set(key, v);
  }
  for (int b = 0; b < 4; ++b) {
    const int side = b % 2 == 0 ? 2 : 4;
    const Key corner{key_axis(rng) / side * side, key_axis(rng) / side * side, key_axis(rng) / side * side};
    const float v = value(rng);
    for (int z = 0; z < side; ++z)
      for (int y = 0; y < side; ++y)
        for (int x = 0; x < side; ++x) {
          const Key key{corner.x + x, corner.y + y, corner.z + z};
          map.set_log_odds(key, v);
          dense.set(key, v);
        }
  }
  ASSERT_EQ(compare(map, dense, t), "") << "before any decay";

  DecayRates rates{c.occupied_rate, c.free_rate, std::nullopt};
  VoxelBox box{{0, 0, 0}, {dense.size() - 1, dense.size() - 1, dense.size() - 1}};
  if (c.region) {
    const Vec3d centre{coordinate(rng) * 0.5, coordinate(rng) * 0.5, coordinate(rng)};
    rates.region = Aabb{{centre.x - 0.43, centre.y - 0.37, -half}, {centre.x + 0.43, centre.y + 0.37, centre.z}};
    box = voxel_box(map.grid(), *rates.region);
  }
  map.set_decay(rates);
  std::uniform_real_distribution<double> dt(0.01, 0.7);
  double time = 100.0;
  map.advance_clock(time);  // the first time only sets the clock
  ASSERT_EQ(compare(map, dense, t), "") << "the first time decayed something";
  for (int step = 0; step < 8; ++step) {
    const double next = step == 3 ? time - 0.5 : time + dt(rng);  // one late time: no decay
    if (next > time) {
      const float occupied = quantized_step(c.occupied_rate, 100.0, time, next);
      const float free = quantized_step(c.free_rate, 100.0, time, next);
      for (std::uint32_t z = 0; z < dense.size(); ++z)
        for (std::uint32_t y = 0; y < dense.size(); ++y)
          for (std::uint32_t x = 0; x < dense.size(); ++x) {
            const Key key{x, y, z};
            if (box.contains(key)) dense.set(key, brute_decay(dense.at(key), occupied, free));
          }
    }
    if (step % 3 == 2) {
      scan(next);  // a stamped scan: the decay first, then the scan
    } else {
      map.advance_clock(next);
    }
    time = std::max(time, next);
    ASSERT_EQ(map.clock(), time);
    ASSERT_EQ(compare(map, dense, t), "") << "after step " << step;
  }
}

TEST(Decay, MatchesBruteForceAtEveryDepth) {
  unsigned seed = 1;
  for (const int depth : {3, 4, 5}) {
    for (const bool prune : {true, false}) {
      run_case({depth, prune, Thresholds{}, 1.3, 0.6, false}, seed++);
      run_case({depth, prune, Thresholds{}, 0.0, 0.5, depth != 3}, seed++);
      // Below a free threshold of p 0.4 a single miss (logit 0.4) is not free.
      run_case({depth, prune, Thresholds{0.6, 0.4}, 0.9, 0.3, depth != 4}, seed++);
      run_case({depth, prune, Thresholds{0.6, 0.4}, 0.7, 0.0, depth == 5}, seed++);
      run_case({depth, prune, Thresholds{0.7, 0.55}, 0.0, 0.8, depth == 4}, seed++);
    }
  }
}

/// The map's file bytes (save_map), the byte-for-byte form of a map.
std::vector<std::uint8_t> bytes_of(const OccupancyMap& map, const std::string& name) {
  const auto path = test::scratch_dir() / (name + ".umap");
  save_map(map, path);
  return test::read_bytes(path);
}

/// Steps compose exactly: many small steps take off what one step over the
/// same time does, bit for bit (what a decay applied later in one go needs).
/// With steps rounded to float one by one (float(a * dt) each) the sums of
/// the small steps drift from the large one in the last bits.
TEST(Decay, ManySmallStepsEqualOneLargeStep) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> c(-2.5f, 2.5f);
  OccupancyMap seen(0.1, 8);
  for (int s = 0; s < 4; ++s) {
    std::vector<Vec3f> points;
    for (int i = 0; i < 300; ++i) points.push_back({c(rng), c(rng), c(rng)});
    seen.insert_point_cloud({c(rng) * 0.3f, c(rng) * 0.3f, 0.0f}, points);
  }
  OccupancyMap small = seen;
  OccupancyMap large = seen;
  const DecayRates rates{0.37, 0.113, std::nullopt};
  small.set_decay(rates);
  large.set_decay(rates);
  const double start = 1311877812.987032;  // a TUM stamp: large times lose digits
  small.advance_clock(start);
  large.advance_clock(start);
  std::uniform_real_distribution<double> dt(0.001, 0.09);
  double time = start;
  for (int step = 0; step < 40; ++step) small.advance_clock(time += dt(rng));
  large.advance_clock(time);
  ASSERT_NE(bytes_of(large, "large_step"), bytes_of(seen, "not_decayed"));  // something decayed
  EXPECT_EQ(bytes_of(small, "small_steps"), bytes_of(large, "large_step"));
}

/// A stamped scan decays the map on the scan's threads: the map after each
/// scan is the one of one thread, byte for byte, and a distance field
/// listening to it still answers as one built anew (the parallel step
/// reports the same changes).
TEST(Decay, StepsOnSeveralThreadsEqualOneThread) {
  // Two scenes: one 6 m wide (the step splits into subtrees high up) and
  // one 0.6 m wide, whose few known nodes make the split go down to the
  // depth of the change journal (3) and below.
  for (const float half : {3.0f, 0.3f}) {
    SCOPED_TRACE("scene half width " + std::to_string(half));
    std::mt19937 rng(17);
    std::uniform_real_distribution<float> c(-half, half);
    std::vector<std::vector<Vec3f>> scans(3);
    for (auto& s : scans)
      for (int i = 0; i < 250; ++i) s.push_back({c(rng), c(rng), c(rng) * 0.3f});
    OccupancyMap one(0.05, 10);
    OccupancyMap several(0.05, 10);
    for (OccupancyMap* map : {&one, &several}) map->set_decay({0.3, 0.15, std::nullopt});
    DistanceFieldOptions field_options;
    field_options.max_distance = 0.3;
    DistanceField field(several, field_options);
    std::vector<Vec3d> probe;
    for (int i = 0; i < 500; ++i) probe.push_back({c(rng), c(rng), c(rng) * 0.3});
    const auto ask = [&](const DistanceField& f) {
      std::vector<DistanceSample> samples(probe.size());
      f.distance_and_gradient(probe, samples);
      std::vector<double> flat;
      for (const DistanceSample& s : samples) flat.insert(flat.end(), {s.occupied, s.unknown});
      return flat;
    };
    // Each scan, then a stamped scan without points: a decay step alone,
    // whose changes the journal learns from the step only.
    for (std::size_t s = 0; s < 2 * scans.size(); ++s) {
      InsertOptions options;
      options.stamp = 0.9 * static_cast<double>(s);
      const std::vector<Vec3f> points = s % 2 == 0 ? scans[s / 2] : std::vector<Vec3f>{};
      options.threads = 1;
      one.insert_point_cloud({0.01f, 0.0f, 0.0f}, points, options);
      options.threads = 3;
      several.insert_point_cloud({0.01f, 0.0f, 0.0f}, points, options);
      ASSERT_EQ(bytes_of(several, "several"), bytes_of(one, "one")) << "after scan " << s;
      ASSERT_EQ(test::check_invariants(several), "");
      field.update();
      ASSERT_EQ(ask(field), ask(DistanceField(several, field_options))) << "after scan " << s;
    }
  }
}

TEST(Decay, DecayedVoxelsBecomeUnknownAndPruneAway) {
  // A map seen once, decayed far enough: every voxel back at 0, the tree a
  // single unknown root as if nothing was ever observed, color dropped.
  MapConfig config;
  config.resolution = 0.1;
  config.depth_levels = 6;
  config.color = true;
  OccupancyMap map(config);
  const std::vector<Vec3f> points = {{1.0f, 0.2f, 0.3f}, {-0.5f, 1.1f, 0.0f}};
  const std::vector<Rgb> colors = {{200, 10, 10}, {10, 200, 10}};
  InsertOptions options;
  options.stamp = 5.0;
  map.insert_point_cloud({0, 0, 0}, points, colors, options);
  ASSERT_EQ(map.state({1.0, 0.2, 0.3}), OccupancyState::occupied);
  ASSERT_TRUE(map.color({1.0, 0.2, 0.3}).has_value());
  map.set_decay({0.5, 0.5, std::nullopt});
  map.advance_clock(6.0);  // 0.5 off a hit's 0.85: still occupied
  EXPECT_EQ(map.state({1.0, 0.2, 0.3}), OccupancyState::occupied);
  map.advance_clock(20.0);
  EXPECT_EQ(map.state({1.0, 0.2, 0.3}), OccupancyState::unknown);
  EXPECT_FALSE(map.color({1.0, 0.2, 0.3}).has_value());
  EXPECT_EQ(map.node_counts().total(), 1u);  // the root alone, unknown
  EXPECT_EQ(map.log_odds({0.0, 0.0, 0.0}, map.depth_levels()), 0.0f);
  EXPECT_EQ(test::check_invariants(map), "");
}

/// A distance field kept up to date through the change journal sees the
/// obstacles a decay step made unknown: after update() it answers as a
/// field built from scratch on the decayed map.
TEST(Decay, DistanceFieldFollowsDecaySteps) {
  OccupancyMap map(0.1, 10);
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> c(-2.5f, 2.5f);
  for (int s = 0; s < 3; ++s) {
    std::vector<Vec3f> points;
    for (int i = 0; i < 300; ++i) points.push_back({c(rng), c(rng), c(rng)});
    InsertOptions options;
    options.stamp = s;
    map.insert_point_cloud({0.0f, 0.0f, 0.0f}, points, options);
  }
  DistanceFieldOptions field_options;
  field_options.max_distance = 0.5;
  DistanceField field(map, field_options);
  std::vector<Vec3d> probe;
  for (int i = 0; i < 2000; ++i) probe.push_back({c(rng), c(rng), c(rng)});
  const auto ask = [&](const DistanceField& f) {
    std::vector<DistanceSample> samples(probe.size());
    f.distance_and_gradient(probe, samples);
    std::vector<double> flat;
    for (const DistanceSample& s : samples) flat.insert(flat.end(), {s.occupied, s.unknown});
    return flat;
  };
  map.set_decay({0.5, 0.1, std::nullopt});
  for (const double time : {2.5, 3.5, 5.0}) {  // the hits of the first scan go first
    map.advance_clock(time);
    field.update();
    EXPECT_EQ(ask(field), ask(DistanceField(map, field_options))) << "at " << time;
  }
}

TEST(Decay, WithoutStampsOrRatesTheMapIsTheSameByteForByte) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> c(-3.0f, 3.0f);
  std::vector<std::vector<Vec3f>> scans(4);
  for (auto& s : scans)
    for (int i = 0; i < 200; ++i) s.push_back({c(rng), c(rng), c(rng)});
  const auto build = [&](std::optional<DecayRates> rates, bool stamps) {
    OccupancyMap map(0.1, 10);
    if (rates) map.set_decay(*rates);
    double time = 0.0;
    for (const auto& s : scans) {
      InsertOptions options;
      options.integrator = IntegratorKind::fast;
      if (stamps) options.stamp = time += 1.0;
      map.insert_point_cloud({0.1f, 0.2f, 0.3f}, s, options);
    }
    return map;
  };
  const auto plain = bytes_of(build(std::nullopt, false), "plain");
  ASSERT_FALSE(plain.empty());
  // Rates set, but no stamp: the clock never moves, nothing decays.
  EXPECT_EQ(bytes_of(build(DecayRates{2.0, 1.0, std::nullopt}, false), "rates"), plain);
  // Stamps, but no rates: the clock moves, nothing decays.
  EXPECT_EQ(bytes_of(build(std::nullopt, true), "stamps"), plain);
  // Both: the map differs (so the comparisons above can fail).
  EXPECT_NE(bytes_of(build(DecayRates{2.0, 1.0, std::nullopt}, true), "decayed"), plain);
}

TEST(Decay, BadRatesTimesAndStampsAreRefusedWithAMessage) {
  OccupancyMap map(0.1, 8);
  const auto message = [](auto&& action) -> std::string {
    try {
      action();
    } catch (const std::exception& e) {
      return e.what();
    }
    return "no exception";
  };
  EXPECT_NE(message([&] { map.set_decay({-1.0, 0.0, std::nullopt}); }).find("occupied_per_second"), std::string::npos);
  EXPECT_NE(message([&] { map.set_decay({0.0, NAN, std::nullopt}); }).find("free_per_second"), std::string::npos);
  EXPECT_NE(message([&] { map.set_decay({1.0, 1.0, Aabb{{1, 0, 0}, {0, 1, 1}}}); }).find("bounding box"),
            std::string::npos);
  EXPECT_THROW(map.set_decay({1.0, 1.0, Aabb{{100, 100, 100}, {101, 101, 101}}}), std::out_of_range);
  EXPECT_NE(message([&] { map.advance_clock(INFINITY); }).find("clock time"), std::string::npos);
  InsertOptions options;
  options.stamp = NAN;
  const std::vector<Vec3f> points = {{1.0f, 0.0f, 0.0f}};
  EXPECT_NE(message([&] { map.insert_point_cloud({0, 0, 0}, points, options); }).find("stamp"), std::string::npos);
  EXPECT_EQ(map.decay(), DecayRates{});
  EXPECT_FALSE(map.clock().has_value());
  // A refused stamped scan leaves the clock (and the map) as they were.
  map.set_decay({1.0, 1.0, std::nullopt});
  map.advance_clock(1.0);
  map.insert_point_cloud({0, 0, 0}, points);
  options.stamp = 50.0;
  EXPECT_THROW(map.insert_point_cloud({100, 0, 0}, points, options), std::out_of_range);
  EXPECT_EQ(map.clock(), 1.0);
  EXPECT_EQ(map.state({1.0, 0.0, 0.0}), OccupancyState::occupied);
}

}  // namespace
}  // namespace umbra
